//! `raybench compare`: identical reports pass; a changed counter, a new mismatch, a changed SAH
//! cost, a missing entry or a slowdown beyond the threshold fail; different settings are caught.

use crate::common;
mod timing;

use raybench_harness::output::compare_table::full_table;
use raybench_harness::pipeline::run::run;
use raybench_harness::report::compare::{CompareOptions, Comparison, Severity, compare};
use raybench_harness::report::interval::Interval;
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

/// Every finding and every row, as the Markdown writes them.
fn text(c: &Comparison) -> String {
    let findings: Vec<&str> = c.findings.iter().map(|f| f.what.as_str()).collect();
    format!("{}\n{}", findings.join("\n"), full_table(c))
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
    assert_eq!(c.regressions(), 0, "{}", text(&c));
    assert!(text(&c).contains("| soup:triangles=300 | bvh-binned | primary |"));
    assert!(text(&c).contains("same"), "{}", text(&c));
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
    let s = bvh(&mut base().clone()).workloads[0]
        .speedup_vs_reference
        .unwrap();
    // Narrow intervals around both ratios: the slowdown is significant.
    let narrow = |x: f64| Interval {
        lo: x * 0.99,
        hi: x * 1.01,
        level: 0.9375,
    };
    let old = with_base_interval(narrow(s));
    let mut new = base().clone();
    let w = &mut bvh(&mut new).workloads[0];
    w.speedup_vs_reference = Some(s / 1.2); // 20 % slower
    w.speedup_interval = Some(narrow(s / 1.2));
    let regressions = |opts: &CompareOptions| compare(&old, &new, opts).regressions();
    // One scene: the per-scene threshold decides.
    let strict = CompareOptions {
        max_scene_slowdown: 0.10,
        ..CompareOptions::default()
    };
    let c = compare(&old, &new, &strict);
    assert!(
        c.findings.iter().any(|f| f.what.contains("Mrays/s ratio")),
        "{}",
        text(&c)
    );
    assert_eq!(regressions(&strict), 1, "{}", text(&c));
    let lenient = CompareOptions {
        max_scene_slowdown: 0.25,
        ..strict
    };
    assert_eq!(regressions(&lenient), 0);
    let advisory = CompareOptions {
        timing_advisory: true,
        ..strict
    };
    let c = compare(&old, &new, &advisory);
    assert_eq!(c.regressions(), 0);
    assert!(c.findings.iter().any(|f| f.severity == Severity::Advisory));
}

/// The base report with `interval` as bvh-binned's first workload's ratio interval.
fn with_base_interval(interval: Interval) -> Report {
    let mut b = base().clone();
    bvh(&mut b).workloads[0].speedup_interval = Some(interval);
    b
}

#[test]
fn a_slowdown_within_the_noise_is_advisory_and_a_significant_one_fails() {
    let s = bvh(&mut base().clone()).workloads[0]
        .speedup_vs_reference
        .unwrap();
    let interval = |x: f64, half: f64| Interval {
        lo: x * (1.0 - half),
        hi: x * (1.0 + half),
        level: 0.9375,
    };
    let judge = |half: f64| {
        let mut new = base().clone();
        let w = &mut bvh(&mut new).workloads[0];
        w.speedup_vs_reference = Some(s / 1.3); // 30 % slower
        w.speedup_interval = Some(interval(s / 1.3, half));
        let opts = CompareOptions {
            max_scene_slowdown: 0.10,
            ..CompareOptions::default()
        };
        let c = compare(&with_base_interval(interval(s, half)), &new, &opts);
        let f = c
            .findings
            .iter()
            .find(|f| f.what.contains("Mrays/s ratio"))
            .cloned();
        (c.regressions(), f.expect("a finding about the slowdown"))
    };
    // ±2 %: even the most favourable ends are 25 % apart, beyond 10 %.
    let (regressions, f) = judge(0.02);
    assert_eq!(regressions, 1, "{f:?}");
    assert!(
        f.what.contains("30.0 % slower") && f.what.contains("significant"),
        "{f:?}"
    );
    // ±15 %: the ends overlap the threshold, so it is not significant.
    let (regressions, f) = judge(0.15);
    assert_eq!(regressions, 0, "{f:?}");
    assert_eq!(f.severity, Severity::Advisory);
    assert!(f.what.contains("not significant"), "{f:?}");
}

#[test]
fn a_subset_counts_what_it_did_not_run_as_not_run() {
    let mut new = base().clone();
    new.results.retain(|r| r.structure != "bruteforce");
    let strict = compare(base(), &new, &CompareOptions::default());
    assert!(strict.regressions() > 0);
    let subset = CompareOptions {
        subset: true,
        ..CompareOptions::default()
    };
    let c = compare(base(), &new, &subset);
    assert_eq!(c.regressions(), 0, "{}", text(&c));
    assert!(c.findings.iter().any(|f| f.what.contains("not run")));
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
        text(&c).contains("WARNING: different environments (CPU"),
        "{}",
        text(&c)
    );
    assert!(
        text(&c).contains("different run settings (seed"),
        "{}",
        text(&c)
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
    let written = std::fs::read_to_string(&path).unwrap();
    assert!(written.contains("\"mrays_per_s\"") && !written.contains("\"mqueries_per_s\""));
    let read = Report::read(&path).expect("a schema-1 report reads");
    assert_eq!(read.header.schema_version, 1);
    let mut same = read.clone();
    same.header.schema_version = base().header.schema_version;
    assert_eq!(
        serde_json::to_string(&same).unwrap(),
        serde_json::to_string(base()).unwrap()
    );
    let c = compare(&read, base(), &CompareOptions::default());
    assert_eq!(c.regressions(), 0, "{}", text(&c));
    // The baselines CI compares against load whatever version they were written with.
    for baseline in ci_baselines() {
        Report::read(&baseline).unwrap_or_else(|e| panic!("{}: {e:#}", baseline.display()));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The committed CI baselines, one per CPU: model and ISA (`reports/baseline/ci-<cpu>.json`).
fn ci_baselines() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reports/baseline");
    let mut found: Vec<_> = std::fs::read_dir(&dir)
        .expect("reports/baseline lists")
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            name.starts_with("ci-") && name.ends_with(".json")
        })
        .collect();
    found.sort();
    assert!(!found.is_empty(), "no reports/baseline/ci-*.json");
    found
}

/// Every CI baseline against every other passes with timing advisory: they differ only in the
/// CPU they were timed on, so their answers and deterministic figures agree (scripts/
/// update-baseline removes one that stops agreeing).
#[test]
fn the_ci_baselines_of_different_cpus_agree_but_for_timing() {
    let all: Vec<Report> = ci_baselines()
        .iter()
        .map(|p| Report::read(p).unwrap_or_else(|e| panic!("{}: {e:#}", p.display())))
        .collect();
    for a in &all {
        for b in &all {
            let c = compare(a, b, &CompareOptions::default());
            assert_eq!(
                c.regressions(),
                0,
                "{} against {}: {:?}",
                a.header.environment.cpu_model,
                b.header.environment.cpu_model,
                c.findings
                    .iter()
                    .filter(|f| f.severity == Severity::Regression)
                    .collect::<Vec<_>>()
            );
        }
    }
}

#[test]
fn the_ci_baseline_against_itself_fits_a_pull_request_comment_verdict_first() {
    use raybench_harness::output::compare_table::{MARKDOWN_LIMIT, MarkdownLimits, markdown};
    let path = ci_baselines().remove(0);
    let ci = Report::read(&path).expect("the CI baseline reads");
    let opts = CompareOptions::default();
    let c = compare(&ci, &ci, &opts);
    assert_eq!(c.regressions(), 0);
    assert!(c.rows.len() > 500, "{} rows", c.rows.len());
    let limits = MarkdownLimits {
        max_rows: 40,
        max_findings: 25,
        only_changed: false,
    };
    let md = markdown(&ci, &ci, &c, &opts, &limits, None);
    assert!(
        md.starts_with("## raybench compare: PASS"),
        "{}",
        &md[..200]
    );
    assert!(md.len() < MARKDOWN_LIMIT, "{} characters", md.len());
    // Nothing changed: with --only-changed the table is empty.
    let only = MarkdownLimits {
        only_changed: true,
        ..limits
    };
    let md = markdown(&ci, &ci, &c, &opts, &only, None);
    assert!(
        md.contains(&format!("0 of {} rows (changed only)", c.rows.len())),
        "{md}"
    );
    // Even every row cannot pass the limit.
    let all = MarkdownLimits {
        max_rows: usize::MAX,
        ..limits
    };
    assert!(markdown(&ci, &ci, &c, &opts, &all, None).len() <= MARKDOWN_LIMIT + 200);
}

#[test]
fn json_and_junit_carry_the_verdict_and_the_failing_row() {
    use raybench_harness::output::compare_table::{json, junit};
    let mut new = base().clone();
    bvh(&mut new).workloads[0]
        .counters_total
        .as_mut()
        .unwrap()
        .nodes += 1;
    let opts = CompareOptions::default();
    let c = compare(base(), &new, &opts);
    let v: serde_json::Value = serde_json::from_str(&json(&c, &opts, true)).unwrap();
    assert_eq!(v["verdict"], "fail");
    assert_eq!(v["regressions"], 1);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 1, "only the changed row: {rows:?}");
    assert_eq!(rows[0]["counters"], "CHANGED");
    let xml = junit(&c);
    assert!(xml.contains("failures=\"1\""), "{xml}");
    assert!(xml.contains("counters changed"), "{xml}");
    let same = compare(base(), base(), &opts);
    let v: serde_json::Value = serde_json::from_str(&json(&same, &opts, false)).unwrap();
    assert_eq!(v["verdict"], "pass");
    assert!(junit(&same).contains("failures=\"0\""));
}

/// `base()` with its one scene repeated under a second name, every ratio given a ±1 % interval.
fn two_scenes() -> Report {
    let mut r = base().clone();
    let copies: Vec<_> = r
        .results
        .iter()
        .cloned()
        .map(|mut e| {
            e.scene = "soup-again".into();
            e
        })
        .collect();
    r.results.extend(copies);
    for e in &mut r.results {
        for w in &mut e.workloads {
            let x = w.speedup_vs_reference.unwrap();
            w.speedup_interval = Some(Interval {
                lo: x * 0.99,
                hi: x * 1.01,
                level: 0.9375,
            });
        }
    }
    r
}

/// Slows bvh-binned's primary rays by `factor` on the scenes named.
fn slowed(report: &Report, factor: f64, scenes: &[&str]) -> Report {
    let mut r = report.clone();
    for e in r.results.iter_mut().filter(|e| e.structure == "bvh-binned") {
        if !scenes.contains(&e.scene.as_str()) {
            continue;
        }
        let w = e
            .workloads
            .iter_mut()
            .find(|w| w.workload == "primary")
            .unwrap();
        let x = w.speedup_vs_reference.unwrap() / factor;
        w.speedup_vs_reference = Some(x);
        w.speedup_interval = Some(Interval {
            lo: x * 0.99,
            hi: x * 1.01,
            level: 0.9375,
        });
    }
    r
}

#[test]
fn the_geometric_mean_gates_and_one_scene_alone_is_advisory() {
    let base = two_scenes();
    let opts = CompareOptions::default();
    // 30 % slower everywhere: the geometric mean fails, significantly.
    let c = compare(
        &base,
        &slowed(&base, 1.3, &["soup:triangles=300", "soup-again"]),
        &opts,
    );
    let failing: Vec<&str> = c
        .findings
        .iter()
        .filter(|f| f.severity == Severity::Regression)
        .map(|f| f.what.as_str())
        .collect();
    assert_eq!(failing.len(), 1, "{failing:?}");
    assert!(failing[0].contains("bvh-binned / primary (geometric mean over 2 scenes)"));
    assert!(failing[0].contains("30.0 % slower") && failing[0].contains("significant"));
    // 15 % slower on one scene: the mean moves 7 %, the scene stays under its 50 %.
    let c = compare(&base, &slowed(&base, 1.15, &["soup-again"]), &opts);
    assert_eq!(c.regressions(), 0, "{}", text(&c));
    assert!(c.findings.iter().any(|f| f.severity == Severity::Advisory
        && f.what.contains("soup-again / bvh-binned / primary")
        && f.what.contains("gated by the geometric mean")));
    // 2× slower on one scene: beyond the per-scene threshold, and significant.
    let c = compare(&base, &slowed(&base, 2.0, &["soup-again"]), &opts);
    assert!(c.findings.iter().any(|f| f.severity == Severity::Regression
        && f.what.starts_with("soup-again / bvh-binned / primary")));
}
