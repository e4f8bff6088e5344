//! Interleaved rounds: every timed pass is kept, ratios come with intervals, with a time
//! budget the extra rounds keep the reference paired with everyone who takes part, and a build
//! is timed again only while a second copy of the structure fits in memory.

use crate::common;

use raybench_accel::{Accel, BuildError, BuildStats, Counters, Hit, Memory, PointHit};
use raybench_bvh::{Bvh, BvhParams};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_harness::Registry;
use raybench_harness::pipeline::run::{RunOptions, run, run_with};
use raybench_scenes::{SceneRequest, Workload};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
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

/// How many times [`Huge`] was built.
static HUGE_BUILDS: AtomicUsize = AtomicUsize::new(0);

/// A binary BVH that claims an exabyte of memory: no machine has room for a second copy.
#[derive(Debug)]
struct Huge(Bvh);

impl Accel for Huge {
    type Params = BvhParams;
    fn build(mesh: Arc<TriangleMesh>, p: &BvhParams) -> Result<Huge, BuildError> {
        HUGE_BUILDS.fetch_add(1, Ordering::SeqCst);
        Ok(Huge(Bvh::build(mesh, p)?))
    }
    fn name(&self) -> &str {
        "huge"
    }
    fn intersect(&self, r: &Ray) -> Option<Hit> {
        self.0.intersect(r)
    }
    fn occluded(&self, r: &Ray) -> bool {
        self.0.occluded(r)
    }
    fn intersect_counted(&self, r: &Ray, c: &mut Counters) -> Option<Hit> {
        self.0.intersect_counted(r, c)
    }
    fn occluded_counted(&self, r: &Ray, c: &mut Counters) -> bool {
        self.0.occluded_counted(r, c)
    }
    fn closest_point(&self, p: Vec3, radius: f32) -> Option<PointHit> {
        self.0.closest_point(p, radius)
    }
    fn closest_point_counted(&self, p: Vec3, radius: f32, c: &mut Counters) -> Option<PointHit> {
        self.0.closest_point_counted(p, radius, c)
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
    fn memory(&self) -> Memory {
        Memory {
            nodes: 1 << 60,
            ..self.0.memory()
        }
    }
}

#[test]
fn a_build_with_no_room_for_a_second_copy_is_not_timed_again_and_the_report_says_so() {
    let mut registry = Registry::builtin();
    registry
        .register::<Huge>(
            "huge",
            "a binary BVH claiming an exabyte",
            BvhParams::binned(),
        )
        .unwrap();
    let opts = RunOptions {
        workloads: vec![Workload::Primary, Workload::Shadow],
        rays: 500,
        build_runs: 3,
        trace_runs: 3,
        images: false,
        reference: "bvh-binned".into(),
        ..common::options(&["huge", "bvh-binned"])
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=1000".into())];
    let report = run_with(&registry, &opts, &scenes).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert_eq!(report.mismatches(), 0);
    let result = |name: &str| report.results.iter().find(|r| r.structure == name).unwrap();
    // Built once, for the checks; that build's time stands for it.
    assert_eq!(HUGE_BUILDS.load(Ordering::SeqCst), 1);
    let huge = result("huge");
    assert_eq!(huge.build.samples_ms.len(), 1);
    assert!(huge.build.median_ms > 0.0);
    assert!(huge.build_ratio_to_reference.is_some());
    assert!(
        huge.workloads
            .iter()
            .all(|w| w.mqueries_per_s.samples.len() == 3)
    );
    assert_eq!(result("bvh-binned").build.samples_ms.len(), 3);
    let note = report
        .notes
        .iter()
        .find(|n| n.starts_with("huge on sphere:triangles=1000: "));
    let note = note.unwrap_or_else(|| panic!("no note on the untimed builds: {:?}", report.notes));
    assert!(
        note.contains("its build time is the warm-up build's") && note.contains("available"),
        "{note}"
    );
}
