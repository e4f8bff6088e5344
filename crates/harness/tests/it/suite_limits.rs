//! Suites in `run`: brute force's triangle limit (structures the user did not name, a suite's
//! list or every structure, skip it above 20,000 triangles with a note; named, it runs
//! everywhere), and a suite given by its manifest's path instead of its name.

use crate::common::{raybench, scratch};
use raybench_harness::report::run::Report;
use std::path::Path;
use std::process::Command;

/// Runs `run`, which must succeed, and reads the report it wrote into `out`.
fn report_of(mut run: Command, out: &Path) -> Report {
    let status = run.arg("--out").arg(out).output().unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    Report::read(&out.join("report.json")).unwrap()
}

/// A suite runs brute force only on scenes within its limit (20,000 triangles), with a note
/// naming the scene and the limit; naming it with `--structures` runs it everywhere.
#[test]
fn a_suite_skips_brute_force_past_its_limit_and_says_so() {
    let dir = scratch("suite-limit");
    std::fs::write(
        dir.join("limits.json"),
        r#"{"name": "limits", "description": "brute force past its suite limit",
            "scenes": ["sphere:triangles=30000", "teapot:triangles=500"],
            "structures": ["bruteforce", "bvh8-binned"], "workloads": ["primary"], "rays": 200}"#,
    )
    .unwrap();
    let run = |out: &str, extra: &[&str]| {
        let mut run = raybench();
        run.env("RAYBENCH_SUITES", &dir)
            .args(["run", "--suite", "limits", "--no-images"])
            .args(extra);
        report_of(run, &dir.join(out))
    };
    let brute_scenes = |r: &Report| -> Vec<String> {
        let mut s: Vec<String> = r
            .results
            .iter()
            .filter(|e| e.structure == "bruteforce")
            .map(|e| e.scene.clone())
            .collect();
        s.sort();
        s
    };
    let limited = run("limited", &[]);
    assert_eq!(brute_scenes(&limited), ["teapot:triangles=500"]);
    assert!(
        limited.notes.iter().any(
            |n| n.contains("bruteforce skipped on sphere:triangles=30000")
                && n.contains("suite limit 20000")
        ),
        "{:?}",
        limited.notes
    );
    assert_eq!(limited.mismatches(), 0);
    let named = run("named", &["--structures", "bruteforce,bvh8-binned"]);
    assert_eq!(
        brute_scenes(&named),
        ["sphere:triangles=30000", "teapot:triangles=500"]
    );
    assert!(
        !named.notes.iter().any(|n| n.contains("skipped")),
        "{:?}",
        named.notes
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Without `--suite` or `--structures`, every structure runs, and brute force keeps its limit
/// there too: a user who names only a large scene has not asked for hours of brute force.
#[test]
fn every_structure_by_default_skips_brute_force_past_its_limit() {
    let dir = scratch("default-limit");
    let mut run = raybench();
    run.args([
        "run",
        "--scenes",
        "sphere:triangles=30000,teapot:triangles=500",
        "--workloads",
        "primary",
        "--rays",
        "200",
        "--build-runs",
        "1",
        "--trace-runs",
        "1",
        "--no-images",
    ]);
    let report = report_of(run, &dir.join("out"));
    assert!(report.run.suite_limits);
    for brute in ["bruteforce", "bruteforce-watertight"] {
        let scenes: Vec<&str> = report
            .results
            .iter()
            .filter(|e| e.structure == brute)
            .map(|e| e.scene.as_str())
            .collect();
        assert_eq!(scenes, ["teapot:triangles=500"], "{brute}");
        assert!(
            report
                .notes
                .iter()
                .any(|n| n.contains(&format!("{brute} skipped on sphere:triangles=30000"))),
            "{:?}",
            report.notes
        );
    }
    assert!(
        report
            .results
            .iter()
            .any(|e| e.structure == "kd-sah" && e.scene == "sphere:triangles=30000"),
        "every other structure runs on the large scene"
    );
    assert_eq!(report.mismatches(), 0);
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--suite` takes a manifest's path as well as a suite's name: a value ending in `.json` is the
/// file itself (its OBJ paths relative to its own directory), whatever `RAYBENCH_SUITES` says;
/// a missing one is an error naming that path, not a suite of `bench-scenes/`.
#[test]
fn a_suite_runs_from_a_manifest_path() {
    let dir = scratch("suite-path");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    let manifest = dir.join("mine.json");
    std::fs::write(
        &manifest,
        r#"{"name": "mine", "description": "a suite outside bench-scenes",
            "scenes": ["teapot:triangles=500", {"obj": "quad.obj"}],
            "structures": ["bvh8-binned"], "workloads": ["primary"], "rays": 200}"#,
    )
    .unwrap();
    let mut run = raybench();
    run.env("RAYBENCH_SUITES", dir.join("elsewhere"))
        .args([
            "run",
            "--no-images",
            "--build-runs",
            "1",
            "--trace-runs",
            "1",
        ])
        .arg("--suite")
        .arg(&manifest);
    let report = report_of(run, &dir.join("out"));
    let scenes: Vec<&str> = report.scenes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(scenes.len(), 2, "{scenes:?}");
    assert!(scenes[0].starts_with("teapot"), "{scenes:?}");
    assert!(scenes[1].ends_with("quad.obj"), "{scenes:?}");

    let missing = dir.join("absent.json");
    let out = raybench()
        .args(["run", "--no-images", "--suite"])
        .arg(&missing)
        .arg("--out")
        .arg(dir.join("out2"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&*missing.to_string_lossy()) && !stderr.contains("absent.json.json"),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
