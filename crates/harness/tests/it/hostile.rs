//! Inputs a hostile or unlucky user gives: FIFOs and devices where files belong, counts that
//! cannot fit, zero runs, thread storms, duplicate names, bad views, output directories that
//! are in use, hold an earlier run or have the wrong kind of file, interrupts, and names with
//! control characters. Each ends in a clear error (or a clean stop) within seconds, before any
//! output is written; none hangs, aborts or loses a report.

use crate::common::{assert_clear_error, files_below, invoke, raybench, scratch};
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// Waits for `child`, killing it (and failing) if it has not ended after a minute: what these
/// tests guard against is a hang, so a hang must fail the test, not stall the suite.
fn finish(mut child: Child, what: &str) -> (i32, String) {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            let code = status.code().unwrap_or(-1);
            return (code, String::from_utf8_lossy(&out.stderr).into_owned());
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("{what}: still running after a minute (a hang)");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn spawn(args: &[&str], dir: Option<&Path>) -> Child {
    let mut cmd = raybench();
    cmd.args(args).stdout(Stdio::piped()).stderr(Stdio::piped());
    if let Some(d) = dir {
        cmd.current_dir(d);
    }
    cmd.spawn().unwrap()
}

fn mkfifo(path: &Path) -> bool {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("NOT RUN: mkfifo is not available");
        return false;
    }
    true
}

/// A FIFO given as a scene, as a report, or as an optional entry of a suite: each is named as
/// a FIFO at once (reading one would block until a writer appears).
#[test]
fn fifos_and_devices_are_refused_without_blocking() {
    let d = scratch("fifo");
    let fifo = d.join("scene.obj");
    if !mkfifo(&fifo) {
        return;
    }
    let out = d.join("out");
    let fifo_s = fifo.to_str().unwrap();
    let scene = spawn(
        &["run", "--scenes", fifo_s, "--structures", "bvh-binned"],
        None,
    );
    let (code, stderr) = finish(scene, "run on a FIFO scene");
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("is a FIFO (named pipe), not a regular file"),
        "{stderr}"
    );
    let report = spawn(&["report", fifo_s, "--out", out.to_str().unwrap()], None);
    let (code, stderr) = finish(report, "report on a FIFO");
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("is a FIFO"), "{stderr}");
    let suite_dir = d.join("suites");
    std::fs::create_dir_all(&suite_dir).unwrap();
    std::fs::write(
        suite_dir.join("fifo.json"),
        format!(
            r#"{{"name": "fifo", "description": "a FIFO as an optional scene",
                "scenes": ["plane:quads=2", {{"obj": "{fifo_s}", "optional": true}}],
                "structures": ["bvh-binned"], "workloads": ["primary"], "rays": 100}}"#
        ),
    )
    .unwrap();
    let mut cmd = raybench();
    cmd.env("RAYBENCH_SUITES", &suite_dir)
        .args(["run", "--suite", "fifo", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let (code, stderr) = finish(cmd.spawn().unwrap(), "a suite with a FIFO entry");
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("is a FIFO"), "{stderr}");
    assert!(
        !out.exists(),
        "nothing may be written before the scenes are checked"
    );
    // A device behind an .obj name (a symbolic link to /dev/zero) would stream until memory
    // runs out.
    let zero = d.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    assert_clear_error(
        &[
            "run",
            "--scenes",
            zero.to_str().unwrap(),
            "--structures",
            "bvh-binned",
        ],
        "zero.obj: is a character device, not a regular file",
    );
    assert_clear_error(&["report", "/dev/zero"], "is a character device");
    std::fs::remove_dir_all(d).unwrap();
}

/// Counts are bounded before any work: a ray count that cannot fit in memory, zero or absurd
/// numbers of timed runs, a thread storm, sizes that overflow.
#[test]
fn numbers_are_bounded_before_any_work() {
    let d = scratch("bounds");
    let out = d.join("out");
    let out_s = out.to_str().unwrap();
    let base = [
        "run",
        "--scenes",
        "soup:triangles=100",
        "--structures",
        "bvh-binned",
    ];
    let with = |extra: &[&'static str]| -> Vec<String> {
        let mut v: Vec<&str> = base.to_vec();
        v.extend_from_slice(extra);
        v.extend_from_slice(&["--out", out_s]);
        v.into_iter().map(String::from).collect()
    };
    let run = |extra: &[&'static str]| {
        let args = with(extra);
        invoke(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (code, _, stderr) = run(&["--rays", "18446744073709551615"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("is more than this machine can hold"),
        "{stderr}"
    );
    assert!(stderr.contains("at most"), "{stderr}");
    let (code, _, stderr) = run(&[
        "--points",
        "18446744073709551615",
        "--workloads",
        "points-near",
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("--points"), "{stderr}");
    for (flag, value, says) in [
        ("--build-runs", "0", "measure nothing"),
        ("--trace-runs", "0", "measure nothing"),
        ("--build-runs", "18446744073709551615", "at most 1000"),
        ("--trace-runs", "1001", "at most 1000"),
        ("--threads", "100000", "measure the scheduler"),
    ] {
        let (code, _, stderr) = run(&[flag, value]);
        assert_eq!(code, 1, "{flag} {value}: {stderr}");
        assert!(
            stderr.contains(flag) && stderr.contains(says),
            "{flag} {value}: {stderr}"
        );
    }
    assert!(!out.exists(), "a refused command writes nothing");
    std::fs::remove_dir_all(d).unwrap();
}

/// A name given twice, and a view the generator does not have, are refused before anything is
/// written.
#[test]
fn duplicate_names_and_unknown_views_are_refused_up_front() {
    let d = scratch("names");
    let out = d.join("out");
    let out_s = out.to_str().unwrap();
    for (args, says) in [
        (
            vec![
                "--scenes",
                "soup:triangles=100",
                "--workloads",
                "random,random",
            ],
            "--workloads names `random` twice",
        ),
        (
            vec!["--scenes", "soup:triangles=100,soup:triangles=100"],
            "--scenes names `soup:triangles=100` twice",
        ),
        (
            vec![
                "--scenes",
                "soup:triangles=100",
                "--structures",
                "grid,grid",
            ],
            "--structures names `grid` twice",
        ),
        (
            vec!["--scenes", "soup:triangles=100,soup:view=nowhere"],
            "unknown view `nowhere` (known: default)",
        ),
    ] {
        let mut full = vec!["run"];
        full.extend(args);
        full.extend(["--out", out_s]);
        let (code, _, stderr) = invoke(&full);
        assert_eq!(code, 1, "{full:?}: {stderr}");
        assert!(stderr.contains(says), "{full:?}: {stderr}");
    }
    assert!(!out.exists(), "nothing may be written");
    std::fs::remove_dir_all(d).unwrap();
}

fn small_run(out: &Path, seed: &str) -> Vec<String> {
    [
        "run",
        "--scenes",
        "sphere:triangles=2000",
        "--structures",
        "bvh-binned,grid",
        "--workloads",
        "primary,random",
        "--rays",
        "20000",
        "--build-runs",
        "2",
        "--trace-runs",
        "3",
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec()
}

/// Two runs started together on one `--out`: exactly one runs, the other fails at once with a
/// clear message, and the directory holds one run's files.
#[test]
fn two_runs_on_one_out_never_mix() {
    let d = scratch("concurrent");
    let out = d.join("out");
    let args_a = small_run(&out, "11");
    let args_b = small_run(&out, "12");
    let a = spawn(&args_a.iter().map(String::as_str).collect::<Vec<_>>(), None);
    let b = spawn(&args_b.iter().map(String::as_str).collect::<Vec<_>>(), None);
    let (code_a, err_a) = finish(a, "run a");
    let (code_b, err_b) = finish(b, "run b");
    let ok: Vec<bool> = [code_a, code_b].iter().map(|&c| c == 0).collect();
    assert_eq!(
        ok.iter().filter(|&&x| x).count(),
        1,
        "a: {err_a}\nb: {err_b}"
    );
    let (winner_seed, loser_err) = if ok[0] { (11, &err_b) } else { (12, &err_a) };
    assert!(
        loser_err.contains("is in use by another raybench command")
            || loser_err.contains("already holds the output of an earlier command"),
        "{loser_err}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["run"]["seed"], winner_seed);
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        page.contains(&format!("seed {winner_seed}")),
        "the page is the winner's"
    );
    assert!(files_below(&out).iter().all(|f| !f.contains(".tmp")));
    std::fs::remove_dir_all(d).unwrap();
}

/// An `--out` that already holds a report is refused unless `--force`; `--force` removes the
/// earlier drawing so no chart of another run stays beside the new report. Paths of the
/// wrong kind (report.json a directory, charts a file) are caught before the work.
#[test]
fn an_out_with_an_earlier_run_or_the_wrong_kind_of_file_is_caught_first() {
    let d = scratch("earlier");
    let out = d.join("out");
    let args = small_run(&out, "3");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, _, stderr) = invoke(&args);
    assert_eq!(code, 0, "{stderr}");
    std::fs::write(out.join("charts/stale-from-another-run.svg"), "<svg/>").unwrap();
    let (code, _, stderr) = invoke(&args);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("give --force to replace it"), "{stderr}");
    let mut forced = args.clone();
    forced.push("--force");
    let (code, _, stderr) = invoke(&forced);
    assert_eq!(code, 0, "{stderr}");
    assert!(!out.join("charts/stale-from-another-run.svg").exists());
    for (setup, says) in [
        (
            "report.json",
            "report.json is a directory where raybench writes a file",
        ),
        (
            "charts",
            "charts is a file where raybench writes a directory",
        ),
    ] {
        let other = d.join(format!("kind-{setup}"));
        std::fs::create_dir_all(&other).unwrap();
        if setup == "charts" {
            std::fs::write(other.join(setup), "x").unwrap();
        } else {
            std::fs::create_dir_all(other.join(setup)).unwrap();
        }
        let args = small_run(&other, "3");
        let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
        args.push("--force");
        let (code, _, stderr) = invoke(&args);
        assert_eq!(code, 1, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

/// Without `--out`, a second run never replaces the first: each gets its own directory.
#[test]
fn the_default_out_is_never_reused() {
    let d = scratch("default-out");
    let args = [
        "run",
        "--scenes",
        "plane:quads=2",
        "--structures",
        "bvh-binned",
        "--workloads",
        "primary",
        "--rays",
        "100",
        "--no-images",
    ];
    for _ in 0..2 {
        let (code, stderr) = finish(spawn(&args, Some(&d)), "a run without --out");
        assert_eq!(code, 0, "{stderr}");
    }
    let mut dirs: Vec<String> = std::fs::read_dir(d.join("reports"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    dirs.sort();
    assert_eq!(dirs.len(), 2, "{dirs:?}");
    assert!(
        dirs[1].starts_with(&dirs[0]) && dirs[1].ends_with("-2"),
        "{dirs:?}"
    );
    for dir in dirs {
        assert!(d.join("reports").join(dir).join("report.json").is_file());
    }
    std::fs::remove_dir_all(d).unwrap();
}

/// Ctrl-C during a run ends it with status 130 and leaves no temporary file behind.
#[test]
fn an_interrupt_leaves_no_temporary_file() {
    let d = scratch("interrupt");
    let out = d.join("out");
    // Long enough (tens of seconds) that the interrupt lands mid-run.
    let out_s = out.to_str().unwrap();
    let args = [
        "run",
        "--scenes",
        "soup:triangles=20000",
        "--structures",
        "bvh-binned,grid,octree",
        "--rays",
        "200000",
        "--trace-runs",
        "50",
        "--out",
        out_s,
    ];
    let child = spawn(&args, None);
    std::thread::sleep(Duration::from_millis(700));
    let sent = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(sent.is_ok_and(|s| s.success()), "kill -INT failed");
    let (code, stderr) = finish(child, "an interrupted run");
    assert_eq!(code, 130, "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let left: Vec<String> = files_below(&out)
        .into_iter()
        .filter(|f| f.contains(".tmp") || f.contains("probe"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    std::fs::remove_dir_all(d).unwrap();
}

/// A file name with an ANSI escape is printed escaped, never raw to the terminal.
#[test]
fn control_characters_in_names_are_escaped() {
    let d = scratch("ansi");
    let name = d.join("clear\u{1b}[2J.obj");
    std::fs::write(&name, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let out = d.join("out");
    let (code, _, stderr) = invoke(&[
        "run",
        "--scenes",
        name.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        !stderr.contains('\u{1b}'),
        "a raw escape reached the terminal: {stderr:?}"
    );
    assert!(stderr.contains("clear\\u{1b}[2J.obj"), "{stderr}");
    std::fs::remove_dir_all(d).unwrap();
}
