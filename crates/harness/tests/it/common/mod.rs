//! Shared by the harness's integration tests.
#![allow(dead_code)]

use raybench_harness::pipeline::run::RunOptions;
use raybench_scenes::Workload;

/// A quick, explicit run: every ray workload, 3000 rays (500 points if a test adds a point workload), one thread, one build and one trace pass,
/// against embree-medium. Tests override what they need with struct update syntax.
pub fn options(structures: &[&str]) -> RunOptions {
    RunOptions {
        suite: None,
        structures: structures.iter().map(|s| s.to_string()).collect(),
        suite_limits: false,
        workloads: Workload::RAYS.to_vec(),
        rays: 3000,
        points: 500,
        threads: 1,
        reference: "embree-medium".into(),
        seed: 7,
        build_runs: 1,
        trace_runs: 1,
        time_budget: None,
        ftz_daz: false,
        progress: false,
        images: true,
        dump_hits: None,
        picture_dir: None,
        picture_width: 640,
    }
}

/// The `raybench` binary of this build.
pub fn raybench() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_raybench"))
}

/// Exit code, stdout and stderr of one invocation.
pub fn invoke(args: &[&str]) -> (i32, String, String) {
    let out = raybench().args(args).output().unwrap();
    (
        out.status.code().expect("exited, not killed by a signal"),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A fresh, empty scratch directory for one test.
pub fn scratch(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("raybench-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every file below `dir`, relative, sorted.
pub fn files_below(dir: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// The error is on the first line of stderr and names `bad`; no panic, no backtrace.
pub fn assert_clear_error(args: &[&str], bad: &str) {
    let (code, _, stderr) = invoke(args);
    assert_eq!(code, 1, "{args:?}: {stderr}");
    let first = stderr.lines().next().unwrap_or_default();
    assert!(
        first.contains(bad),
        "{args:?}: the first line does not name {bad}: {stderr}"
    );
    assert!(
        first.starts_with("raybench: error:") || first.starts_with("error:"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "{stderr}"
    );
}
