//! `raybench compare`: identical reports pass; a changed counter, a new mismatch, a changed SAH
//! cost, a missing entry or a slowdown beyond the threshold fail; different settings are caught.

mod common;

use raybench_harness::pipeline::run::run;
use raybench_harness::report::compare::{CompareOptions, Severity, compare};
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

/// One small real run, shared by every test (bruteforce and bvh-binned against embree-medium).
fn base() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        let opts = raybench_scenes::Workload::ALL[..2].to_vec();
        let options = raybench_harness::pipeline::run::RunOptions {
            workloads: opts,
            rays: 1000,
            ..common::options(&["bruteforce", "bvh-binned", "embree-medium"])
        };
        run(&options, &[SceneRequest::Spec("soup:triangles=300".into())]).unwrap()
    })
}

fn regressions(new: &Report, opts: &CompareOptions) -> Vec<String> {
    compare(base(), new, opts)
        .findings
        .into_iter()
        .filter(|f| f.severity == Severity::Regression)
        .map(|f| f.what)
        .collect()
}

fn bvh(report: &mut Report) -> &mut raybench_harness::report::run::ResultEntry {
    report
        .results
        .iter_mut()
        .find(|r| r.structure == "bvh-binned")
        .unwrap()
}

#[test]
fn identical_reports_have_no_regression() {
    let c = compare(base(), base(), &CompareOptions::default());
    assert_eq!(c.regressions(), 0, "{}", c.markdown);
    assert!(
        c.markdown
            .contains("| soup:triangles=300 | bvh-binned | primary |")
    );
    assert!(c.markdown.contains("same"), "{}", c.markdown);
}

#[test]
fn a_changed_counter_is_a_regression() {
    let mut new = base().clone();
    let w = &mut bvh(&mut new).workloads[0];
    w.counters_total.as_mut().unwrap().nodes += 1;
    let r = regressions(&new, &CompareOptions::default());
    assert_eq!(r.len(), 1, "{r:?}");
    assert!(r[0].contains("counters changed"), "{r:?}");
}

#[test]
fn a_changed_sah_cost_is_a_regression() {
    let mut new = base().clone();
    let stats = &mut bvh(&mut new).build_stats;
    stats.sah_cost = stats.sah_cost.map(|c| c * 1.0001);
    let r = regressions(&new, &CompareOptions::default());
    assert!(r.iter().any(|x| x.contains("sah_cost changed")), "{r:?}");
}

#[test]
fn a_new_mismatch_is_a_regression() {
    let mut new = base().clone();
    bvh(&mut new).workloads[1].agreement.counts.mismatch += 1;
    let r = regressions(&new, &CompareOptions::default());
    assert!(
        r.iter().any(|x| x.contains("mismatches rose from 0 to 1")),
        "{r:?}"
    );
}

#[test]
fn a_slowdown_beyond_the_threshold_fails_unless_advisory() {
    let mut new = base().clone();
    let w = &mut bvh(&mut new).workloads[0];
    let s = w.speedup_vs_reference.unwrap();
    w.speedup_vs_reference = Some(s / 1.2); // 20 % slower
    let strict = CompareOptions::default();
    let r = regressions(&new, &strict);
    assert!(r.iter().any(|x| x.contains("Mrays/s ratio")), "{r:?}");
    let lenient = CompareOptions {
        max_slowdown: 0.25,
        ..strict
    };
    assert!(regressions(&new, &lenient).is_empty());
    let advisory = CompareOptions {
        timing_advisory: true,
        ..strict
    };
    let c = compare(base(), &new, &advisory);
    assert_eq!(c.regressions(), 0);
    assert!(c.findings.iter().any(|f| f.severity == Severity::Advisory));
}

#[test]
fn a_missing_structure_is_a_regression() {
    let mut new = base().clone();
    new.results.retain(|r| r.structure != "bvh-binned");
    let r = regressions(&new, &CompareOptions::default());
    assert!(
        r.iter().any(|x| x.contains("missing from the new report")),
        "{r:?}"
    );
}

/// The new report lists one scene × structure twice, its first copy with a mismatch: keying
/// it would keep the clean last copy, so the duplicate itself is the regression.
#[test]
fn a_report_with_duplicate_entries_is_refused_naming_them() {
    let mut new = base().clone();
    let mut bad = bvh(&mut new).clone();
    bad.workloads[0].agreement.counts.mismatch = 7;
    let at = new
        .results
        .iter()
        .position(|r| r.structure == "bvh-binned")
        .unwrap();
    new.results.insert(at, bad);
    let r = regressions(&new, &CompareOptions::default());
    assert!(
        r.iter()
            .any(|x| x
                .contains("the new report lists soup:triangles=300 / bvh-binned more than once")),
        "{r:?}"
    );
    let mut twice = base().clone();
    let w = bvh(&mut twice).workloads[0].clone();
    bvh(&mut twice).workloads.push(w);
    let r = regressions(&twice, &CompareOptions::default());
    assert!(
        r.iter()
            .any(|x| x.contains("soup:triangles=300 / bvh-binned / primary more than once")),
        "{r:?}"
    );
}

#[test]
fn different_settings_and_machines_are_flagged() {
    let mut new = base().clone();
    new.run.seed += 1;
    new.header.environment.cpu_model = "Another CPU".into();
    let c = compare(base(), &new, &CompareOptions::default());
    assert!(
        c.markdown.contains("WARNING: different environments (CPU"),
        "{}",
        c.markdown
    );
    assert!(
        c.markdown.contains("different run settings (seed"),
        "{}",
        c.markdown
    );
    assert!(c.regressions() > 0);
}

#[test]
fn the_command_exits_0_on_identical_reports_and_2_on_a_regression() {
    let dir = std::env::temp_dir().join(format!("raybench-compare-{}", std::process::id()));
    let base_path = base().write_atomic(&dir.join("base")).unwrap();
    let mut new = base().clone();
    bvh(&mut new).workloads[0]
        .counters_total
        .as_mut()
        .unwrap()
        .prim_tests += 3;
    let new_path = new.write_atomic(&dir.join("new")).unwrap();
    let exe = env!("CARGO_BIN_EXE_raybench");
    let same = Command::new(exe)
        .args([
            "compare".as_ref(),
            base_path.as_os_str(),
            base_path.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(
        same.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&same.stdout)
    );
    let changed = Command::new(exe)
        .args([
            "compare".as_ref(),
            base_path.as_os_str(),
            new_path.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(changed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&changed.stdout).contains("REGRESSION"));
    let missing = Command::new(exe)
        .args(["compare", "/nonexistent/base.json", "/nonexistent/new.json"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/base.json"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A report of schema version 1 (fields named after rays) reads through the old names into the
/// same report, and compares against a new one without a regression.
#[test]
fn a_schema_1_report_reads_through_the_old_names() {
    let mut old = serde_json::to_value(base()).unwrap();
    old["schema_version"] = 1.into();
    let renames = [
        ("queries", "rays"),
        ("mqueries_per_s", "mrays_per_s"),
        ("counters_per_query", "counters_per_ray"),
        ("agreement", "validation"),
    ];
    let rename = |object: &mut serde_json::Value| {
        let map = object.as_object_mut().unwrap();
        for (new, was) in renames {
            if let Some(v) = map.remove(new) {
                map.insert(was.to_string(), v);
            }
        }
    };
    for scene in old["scenes"].as_array_mut().unwrap() {
        scene["workloads"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .for_each(rename);
    }
    for result in old["results"].as_array_mut().unwrap() {
        result["workloads"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .for_each(rename);
    }
    let dir = std::env::temp_dir().join(format!("raybench-schema-1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("report.json");
    std::fs::write(&path, serde_json::to_vec_pretty(&old).unwrap()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"mrays_per_s\"") && !text.contains("\"mqueries_per_s\""));
    let read = Report::read(&path).expect("a schema-1 report reads");
    assert_eq!(read.header.schema_version, 1);
    let mut same = read.clone();
    same.header.schema_version = base().header.schema_version;
    assert_eq!(
        serde_json::to_string(&same).unwrap(),
        serde_json::to_string(base()).unwrap()
    );
    let c = compare(&read, base(), &CompareOptions::default());
    assert_eq!(c.regressions(), 0, "{}", c.markdown);
    // The baseline CI compares against loads whatever version it was written with.
    let baseline = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reports/baseline/ci.json");
    Report::read(&baseline).expect("reports/baseline/ci.json reads");
    std::fs::remove_dir_all(&dir).ok();
}
