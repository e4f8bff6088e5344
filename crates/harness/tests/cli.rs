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
