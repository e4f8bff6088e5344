//! Interleaved rounds: every timed pass is kept, ratios come with intervals, and with a time
//! budget the extra rounds keep the reference paired with everyone who takes part.

use crate::common;

use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_scenes::{SceneRequest, Workload};
use std::time::Duration;

#[test]
fn samples_intervals_and_extra_rounds_stay_paired() {
    let fixed = RunOptions {
        workloads: vec![Workload::Primary, Workload::Random],
        rays: 2000,
        build_runs: 3,
        trace_runs: 5,
        images: false,
        ..common::options(&["embree-medium", "bvh-binned", "grid"])
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=2000".into())];
    let report = run(&fixed, &scenes).unwrap();
    for r in &report.results {
        assert_eq!(r.build.samples_ms.len(), 3, "{}", r.structure);
        let bi = r
            .build_ratio_interval
            .expect("three builds give an interval");
        assert!(bi.level > 0.74 && bi.level < 0.76, "{bi:?}");
        for w in &r.workloads {
            assert_eq!(w.mqueries_per_s.samples.len(), 5);
            let i = w.speedup_interval.expect("an interval");
            let x = w.speedup_vs_reference.unwrap();
            assert!(i.lo <= x && x <= i.hi, "{i:?} {x}");
            assert_eq!(i.level, 0.9375);
        }
    }
    let adaptive = RunOptions {
        time_budget: Some(Duration::from_millis(300)),
        ..fixed
    };
    let report = run(&adaptive, &scenes).unwrap();
    let runs = |name: &str| -> Vec<usize> {
        let r = report.results.iter().find(|r| r.structure == name).unwrap();
        r.workloads.iter().map(|w| w.mqueries_per_s.runs).collect()
    };
    let reference = runs("embree-medium");
    for name in ["bvh-binned", "grid"] {
        for (mine, theirs) in runs(name).iter().zip(&reference) {
            // At least the fixed rounds; never a round the reference did not also run.
            assert!(
                *mine >= 5 && mine <= theirs,
                "{name}: {mine} against {theirs}"
            );
        }
    }
    assert_eq!(report.run.time_budget_s, Some(0.3));
}
