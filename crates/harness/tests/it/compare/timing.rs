//! `raybench compare` on timing alone: which slowdowns gate (Embree against Embree does not),
//! and the list of structures a timing-only failure names for a second timing
//! (`--timing-regressions-to`, used by scripts/ci-gate).

use crate::common;
use raybench_harness::output::compare_table::full_table;
use raybench_harness::pipeline::run::run;
use raybench_harness::report::compare::{CompareOptions, Comparison, Severity, compare};
use raybench_harness::report::interval::Interval;
use raybench_harness::report::run::{Report, ResultEntry};
use raybench_scenes::SceneRequest;
use std::process::Command;
use std::sync::OnceLock;

/// One small real run, shared by every test (bruteforce and bvh-binned against embree-medium),
/// with narrow intervals around every ratio, so that a slowdown of 20 % is significant.
fn base() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        let options = raybench_harness::pipeline::run::RunOptions {
            workloads: raybench_scenes::Workload::ALL[..2].to_vec(),
            rays: 1000,
            ..common::options(&["bruteforce", "bvh-binned", "embree-medium"])
        };
        let mut r = run(&options, &[SceneRequest::Spec("soup:triangles=300".into())]).unwrap();
        for e in &mut r.results {
            for w in &mut e.workloads {
                w.speedup_interval = w.speedup_vs_reference.map(narrow);
            }
        }
        r
    })
}

fn narrow(x: f64) -> Interval {
    Interval {
        lo: x * 0.99,
        hi: x * 1.01,
        level: 0.9375,
    }
}

/// Every finding and every row, as the Markdown writes them.
fn text(c: &Comparison) -> String {
    let findings: Vec<&str> = c.findings.iter().map(|f| f.what.as_str()).collect();
    format!("{}\n{}", findings.join("\n"), full_table(c))
}

fn entry<'a>(report: &'a mut Report, structure: &str) -> &'a mut ResultEntry {
    report
        .results
        .iter_mut()
        .find(|r| r.structure == structure)
        .unwrap()
}

/// `structure`'s first workload 20 % slower, with a narrow interval.
fn slow(report: &mut Report, structure: &str) {
    let w = &mut entry(report, structure).workloads[0];
    let s = w.speedup_vs_reference.unwrap() / 1.2;
    w.speedup_vs_reference = Some(s);
    w.speedup_interval = Some(narrow(s));
}

/// One scene's threshold at 10 %, so that one scene's 20 % slowdown fails.
fn strict() -> CompareOptions {
    CompareOptions {
        max_scene_slowdown: 0.10,
        ..CompareOptions::default()
    }
}

/// Embree's single-ray presets against the Embree reference are the machine's figures, not
/// raybench's: their slowdowns are advisory. An Embree entry that batches rays in raybench's
/// wrapper (a stream) and raybench's own entries stay gated.
#[test]
fn embree_against_embree_is_advisory_and_the_batched_entries_stay_gated() {
    let mut old = base().clone();
    let template = entry(&mut old, "bvh-binned").clone();
    for (name, params) in [
        (
            "embree-robust",
            serde_json::json!({"quality": "medium", "robust": true}),
        ),
        (
            "embree-medium-stream",
            serde_json::json!({"quality": "medium", "coherent_stream": true}),
        ),
    ] {
        let mut e = template.clone();
        e.structure = name.into();
        e.params = params;
        old.results.push(e);
    }
    let mut new = old.clone();
    for s in [
        "bruteforce",
        "bvh-binned",
        "embree-robust",
        "embree-medium-stream",
    ] {
        slow(&mut new, s);
    }
    let c = compare(&old, &new, &strict());
    let of = |name: &str, severity: Severity| {
        c.findings
            .iter()
            .any(|f| f.severity == severity && f.at.contains(&format!("/ {name} /")))
    };
    assert!(of("embree-robust", Severity::Advisory), "{}", text(&c));
    assert!(!of("embree-robust", Severity::Regression), "{}", text(&c));
    assert!(
        text(&c).contains("Embree against Embree, not gated"),
        "{}",
        text(&c)
    );
    assert!(
        of("embree-medium-stream", Severity::Regression),
        "{}",
        text(&c)
    );
    assert!(of("bvh-binned", Severity::Regression), "{}", text(&c));
    assert!(of("bruteforce", Severity::Regression), "{}", text(&c));
}

/// A failure made of timing slowdowns alone names its structures; any other regression (here a
/// changed counter) means no second timing can clear it, and no failure names nothing.
#[test]
fn a_timing_only_failure_names_its_structures() {
    assert_eq!(compare(base(), base(), &strict()).timing_only(), None);
    let mut new = base().clone();
    slow(&mut new, "bvh-binned");
    slow(&mut new, "bruteforce");
    let c = compare(base(), &new, &strict());
    assert_eq!(
        c.timing_only(),
        Some(vec!["bruteforce".to_string(), "bvh-binned".to_string()]),
        "{}",
        text(&c)
    );
    let w = &mut entry(&mut new, "bvh-binned").workloads[1];
    w.counters_total.as_mut().unwrap().nodes += 1;
    let c = compare(base(), &new, &strict());
    assert!(c.regressions() >= 3, "{}", text(&c));
    assert_eq!(c.timing_only(), None, "{}", text(&c));
}

/// Reports timed on different CPU models: a slowdown is advisory (a ratio to the reference
/// does not carry from one CPU to another), with a note naming both CPUs, while a changed
/// counter still fails; on the same CPU the same slowdown fails.
#[test]
fn timing_on_another_cpu_is_advisory_and_counters_still_gate() {
    let mut new = base().clone();
    slow(&mut new, "bvh-binned");
    assert_eq!(compare(base(), &new, &strict()).regressions(), 1);
    new.header.environment.cpu_model = format!("not {}", base().header.environment.cpu_model);
    another_cpu_gates_counters_only(new);
}

/// One model name with other SIMD features (an `AMD EPYC` with AVX-512 and one without, whose
/// kernels differ) is another CPU too: the slowdown is advisory, a changed counter still fails.
#[test]
fn timing_on_the_same_model_with_other_simd_features_is_advisory() {
    let mut new = base().clone();
    slow(&mut new, "bvh-binned");
    let flags = &mut new.header.environment.cpu_flags;
    if flags.iter().any(|f| f == "avx512f") {
        flags.retain(|f| !f.starts_with("avx512"));
    } else {
        flags.push("avx512f".to_string());
    }
    assert_eq!(
        new.header.environment.cpu_model,
        base().header.environment.cpu_model
    );
    another_cpu_gates_counters_only(new);
}

/// `new`, slower than the base on `bvh-binned` and timed on another CPU: an advisory and a note
/// naming the new CPU, no regression; then with a counter changed, a regression that is not
/// timing alone.
fn another_cpu_gates_counters_only(mut new: Report) {
    let c = compare(base(), &new, &strict());
    assert_eq!(c.regressions(), 0, "{}", text(&c));
    assert!(
        c.findings
            .iter()
            .any(|f| f.severity == Severity::Advisory && f.at.contains("/ bvh-binned /")),
        "{}",
        text(&c)
    );
    assert!(
        c.findings.iter().any(|f| f.severity == Severity::Note
            && f.what.contains("timing slowdowns are advisory")
            && f.what.contains(&new.header.environment.cpu_model)
            && f.what.contains(&new.header.environment.cpu_flags.join(" "))),
        "{}",
        text(&c)
    );
    let w = &mut entry(&mut new, "bvh-binned").workloads[1];
    w.counters_total.as_mut().unwrap().nodes += 1;
    let c = compare(base(), &new, &strict());
    assert!(c.regressions() >= 1, "{}", text(&c));
    assert_eq!(c.timing_only(), None, "{}", text(&c));
}

/// `--timing-regressions-to FILE`: the list on a timing-only failure (exit 2), no file after a
/// pass (a stale list removed), and an error naming the flag when FILE is a directory.
#[test]
fn the_command_writes_the_list_only_for_a_timing_only_failure() {
    let dir = std::env::temp_dir().join(format!("raybench-compare-timing-{}", std::process::id()));
    let base_path = base().write_atomic(&dir.join("base")).unwrap();
    let mut new = base().clone();
    slow(&mut new, "bvh-binned");
    let new_path = new.write_atomic(&dir.join("new")).unwrap();
    let list = dir.join("list.txt");
    let compare_to = |new: &std::path::Path, list: &std::path::Path| {
        Command::new(env!("CARGO_BIN_EXE_raybench"))
            .arg("compare")
            .args([base_path.as_path(), new])
            .args(["--max-scene-slowdown", "10", "--timing-regressions-to"])
            .arg(list)
            .output()
            .unwrap()
    };
    let slower = compare_to(&new_path, &list);
    assert_eq!(slower.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&list).unwrap(), "bvh-binned\n");
    let same = compare_to(&base_path, &list);
    assert_eq!(same.status.code(), Some(0));
    assert!(!list.exists(), "a pass leaves no list behind");
    let not_a_file = compare_to(&base_path, &dir);
    assert_eq!(not_a_file.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&not_a_file.stderr).contains("--timing-regressions-to"));
    std::fs::remove_dir_all(&dir).ok();
}
