//! `raybench history`: reports ordered by time; a changed counter and a ratio that left its
//! interval are marked at the report where they happened; the page and the summary are written.

use crate::common;

use raybench_harness::output::history::{Entry, markdown, order, page, series};
use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::report::interval::Interval;
use raybench_harness::report::run::Report;
use raybench_scenes::{SceneRequest, Workload};
use std::path::PathBuf;

/// One small run with three rounds, so every ratio has an interval.
fn base() -> Report {
    let options = RunOptions {
        workloads: vec![Workload::Primary, Workload::Random],
        rays: 1000,
        build_runs: 3,
        trace_runs: 3,
        images: false,
        ..common::options(&["bvh-binned", "grid", "embree-medium"])
    };
    let scenes = [
        SceneRequest::Spec("soup:triangles=300".into()),
        SceneRequest::Spec("sphere:triangles=500".into()),
    ];
    run(&options, &scenes).unwrap()
}

fn at(report: &Report, stamp: &str, revision: &str) -> Entry {
    let mut r = report.clone();
    r.header.environment.timestamp = stamp.into();
    r.header.environment.git_revision = revision.into();
    Entry {
        path: PathBuf::from(format!("{revision}/report.json")),
        report: r,
    }
}

#[test]
fn events_are_marked_where_they_happened() {
    let b = base();
    // Five commits, given out of order: the third changes grid's counters on one scene, the
    // fifth halves bvh-binned's random-ray ratio with narrow intervals on both sides.
    let mut entries = vec![
        at(&b, "2026-11-05T00:00:00Z", "eeee"),
        at(&b, "2026-11-01T00:00:00Z", "aaaa"),
        at(&b, "2026-11-03T00:00:00Z", "cccc"),
        at(&b, "2026-11-02T00:00:00Z", "bbbb"),
        at(&b, "2026-11-04T00:00:00Z", "dddd"),
    ];
    let narrow = |x: f64| Interval {
        lo: x * 0.98,
        hi: x * 1.02,
        level: 0.9375,
    };
    for e in &mut entries {
        let rev = e.report.header.environment.git_revision.clone();
        for r in &mut e.report.results {
            for w in &mut r.workloads {
                let mut x = w.speedup_vs_reference.unwrap();
                if rev == "eeee" && r.structure == "bvh-binned" && w.workload == "random" {
                    x /= 2.0;
                }
                w.speedup_vs_reference = Some(x);
                w.speedup_interval = Some(narrow(x));
                if rev.as_str() >= "cccc"
                    && r.structure == "grid"
                    && r.scene.starts_with("soup")
                    && w.workload == "primary"
                {
                    w.counters_total.as_mut().unwrap().cells += 1;
                }
            }
        }
    }
    let entries = order(entries);
    let revs: Vec<&str> = entries
        .iter()
        .map(|e| e.report.header.environment.git_revision.as_str())
        .collect();
    assert_eq!(revs, ["aaaa", "bbbb", "cccc", "dddd", "eeee"]);
    let all = series(&entries);
    let events: Vec<(String, String, usize, String)> = all
        .iter()
        .flat_map(|s| {
            s.events
                .iter()
                .map(|(i, w)| (s.structure.clone(), s.workload.clone(), *i, w.clone()))
        })
        .collect();
    assert_eq!(events.len(), 2, "{events:?}");
    assert_eq!(
        (events[0].0.as_str(), events[0].1.as_str(), events[0].2),
        ("bvh-binned", "random", 4)
    );
    assert!(events[0].3.contains("slower"), "{events:?}");
    assert_eq!(
        (events[1].0.as_str(), events[1].1.as_str(), events[1].2),
        ("grid", "primary", 2)
    );
    assert!(
        events[1].3.contains("counters changed on 1 of 2 scenes"),
        "{events:?}"
    );
    // No series for the reference; two scenes behind every point.
    assert!(
        all.iter()
            .all(|s| s.structure != "embree-medium" && s.scenes.len() == 2)
    );
    let md = markdown(&entries, &all, 50);
    assert!(
        md.contains("5 reports") && md.contains("2 event(s)"),
        "{md}"
    );
    assert!(md.contains("`eeee` (#5) bvh-binned / random"), "{md}");
    let html = page(&entries, &all);
    assert!(html.contains("<svg") && html.contains("stroke=\"#b00\""));
    // The summary is bounded.
    assert!(markdown(&entries, &all, 1).contains("… and 1 more"));
}
