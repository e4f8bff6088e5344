//! Ctrl-C during `raybench run`: the finished scenes are written in a report marked incomplete,
//! nothing is drawn, the exit status is 130; `--resume DIR` runs the rest with the recorded
//! settings and leaves one complete report. A second `--resume`, or a flag beside it, is
//! refused.

use crate::common;

use raybench_harness::report::run::Report;
use std::io::{BufRead, BufReader};
use std::process::Stdio;

#[test]
fn an_interrupted_run_keeps_its_finished_scenes_and_resumes() {
    let dir = std::env::temp_dir().join(format!("raybench-interrupt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scenes = "teapot,sphere:triangles=20000,soup:triangles=20000,terrain";
    let mut child = common::raybench()
        .args([
            "run",
            "--scenes",
            scenes,
            "--structures",
            "embree-medium,bvh-binned",
        ])
        .args([
            "--workloads",
            "primary,random",
            // Enough passes that the second scene is still being timed (a second or more on
            // one core) when the interrupt arrives, a few milliseconds after its line.
            "--rays",
            "30000",
            "--trace-runs",
            "30",
        ])
        .args(["--no-images", "--out", dir.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once the second scene's timing has started: the first is finished by then.
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let mut lines = stderr.lines().map_while(Result::ok);
    for line in lines.by_ref() {
        if line.contains("sphere:triangles=20000: timing") {
            break;
        }
    }
    let pid = child.id().to_string();
    let killed = std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap();
    assert!(killed.success());
    let rest: Vec<String> = lines.collect();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{rest:?}");
    assert!(
        rest.iter().any(|l| l.contains("marked incomplete")),
        "{rest:?}"
    );
    let report = Report::read(&dir.join("report.json")).unwrap();
    let inc = report.incomplete.as_ref().expect("marked incomplete");
    let names: Vec<&str> = report.scenes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["teapot"]);
    assert_eq!(inc.remaining.len(), 3, "{inc:?}");
    assert!(report.results.iter().all(|r| r.scene == "teapot"));
    assert!(!dir.join("index.html").exists(), "nothing is drawn");

    let (code, _, err) = common::invoke(&["run", "--resume", dir.to_str().unwrap(), "--rays", "9"]);
    assert_eq!(code, 1);
    assert!(err.contains("drop --rays"), "{err}");
    // Fewer trace passes would be a different run: the resumed part keeps the recorded 30.
    let (code, out, err) = common::invoke(&["run", "--resume", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}\n{err}");
    let report = Report::read(&dir.join("report.json")).unwrap();
    assert!(report.incomplete.is_none());
    let names: Vec<&str> = report.scenes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "teapot",
            "sphere:triangles=20000",
            "soup:triangles=20000",
            "terrain"
        ]
    );
    assert_eq!(report.results.len(), 8);
    assert!(
        report
            .results
            .iter()
            .all(|r| r.workloads[0].mqueries_per_s.runs == 30)
    );
    assert!(dir.join("index.html").exists());
    let (code, _, err) = common::invoke(&["run", "--resume", dir.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("is complete"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
