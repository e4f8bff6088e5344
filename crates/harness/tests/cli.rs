//! The `raybench` binary as a user runs it.

use std::process::Command;

fn raybench() -> Command {
    Command::new(env!("CARGO_BIN_EXE_raybench"))
}

#[test]
fn list_names_structures_workloads_and_suites() {
    let out = raybench().arg("list").output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "bruteforce",
        "embree-medium",
        "embree-robust",
        "sphere",
        "primary",
        "diffuse",
        "ci",
        "default",
    ] {
        assert!(text.contains(name), "`raybench list` lacks {name}:\n{text}");
    }
}

#[test]
fn run_writes_a_report_and_prints_the_summary() {
    let dir = std::env::temp_dir().join(format!("raybench-cli-{}", std::process::id()));
    let out = raybench()
        .args([
            "run",
            "--scenes",
            "sphere:triangles=800",
            "--structures",
            "bruteforce,embree-medium",
        ])
        .args([
            "--rays",
            "1000",
            "--build-runs",
            "1",
            "--trace-runs",
            "1",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("0 mismatches"), "{stdout}");
    assert!(dir.join("report.json").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_arguments_fail_with_a_message() {
    let out = raybench()
        .args(["run", "--scenes", "sphere", "--workloads", "sideways"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("sideways"));
    let out = raybench()
        .args(["run", "--suite", "no-such-suite"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-suite"));
}

#[test]
fn the_ci_suite_runs_end_to_end_with_zero_mismatches() {
    let dir = std::env::temp_dir().join(format!("raybench-ci-suite-{}", std::process::id()));
    let out = raybench()
        .args([
            "run",
            "--suite",
            "ci",
            "--rays",
            "3000",
            "--build-runs",
            "1",
            "--trace-runs",
            "1",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = raybench_harness::report::Report::read(&dir.join("report.json")).unwrap();
    assert_eq!(report.mismatches(), 0);
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let scenes: Vec<&str> = report.scenes.iter().map(|s| s.name.as_str()).collect();
    for generator in [
        "sphere",
        "soup",
        "plane",
        "teapot",
        "teapot-in-stadium",
        "grass",
        "terrain",
        "hair",
        "city",
    ] {
        assert!(
            scenes
                .iter()
                .any(|s| s.split(':').next() == Some(generator)),
            "{generator}: {scenes:?}"
        );
    }
    if std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/stanford-bunny.obj"
    ))
    .exists()
    {
        assert!(scenes.contains(&"stanford-bunny.obj"), "{scenes:?}");
        assert!(
            report
                .notes
                .iter()
                .any(|n| n.contains("bruteforce skipped on stanford-bunny.obj")),
            "{:?}",
            report.notes
        );
    } else {
        eprintln!(
            "NOT CHECKED: ../shared/scenes is absent, so the suite's bunny was skipped (as a note)"
        );
        assert!(
            report.notes.iter().any(|n| n.contains("stanford-bunny")),
            "{:?}",
            report.notes
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}
