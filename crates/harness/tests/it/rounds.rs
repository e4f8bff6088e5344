//! Interleaved rounds: every timed pass is kept, ratios come with intervals, with a time
//! budget the extra rounds keep the reference paired with everyone who takes part, and a timed
//! build replaces the structure traced so far instead of living beside it.

use crate::common;

use raybench_accel::{Accel, BuildError, BuildStats, Counters, Hit, Memory, PointHit};
use raybench_bvh::{Bvh, BvhParams};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_harness::Registry;
use raybench_harness::pipeline::ONE_COPY_FROM;
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

/// Copies of each [`Tally`] alive now, and the most ever alive at once: index 0 for the one
/// that reports its true size, 1 for the one that claims more than [`ONE_COPY_FROM`].
static LIVE: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
static MOST: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// A binary BVH that counts its live copies, and may claim to be larger than it is.
#[derive(Debug)]
struct Tally {
    bvh: Bvh,
    large: bool,
}

impl Drop for Tally {
    fn drop(&mut self) {
        LIVE[self.large as usize].fetch_sub(1, Ordering::SeqCst);
    }
}

impl Accel for Tally {
    /// The BVH's parameters, and whether to claim a size over [`ONE_COPY_FROM`].
    type Params = (BvhParams, bool);
    fn build(mesh: Arc<TriangleMesh>, (p, large): &(BvhParams, bool)) -> Result<Tally, BuildError> {
        let bvh = Bvh::build(mesh, p)?;
        let i = *large as usize;
        let live = LIVE[i].fetch_add(1, Ordering::SeqCst) + 1;
        MOST[i].fetch_max(live, Ordering::SeqCst);
        Ok(Tally { bvh, large: *large })
    }
    fn name(&self) -> &str {
        "tally"
    }
    fn intersect(&self, r: &Ray) -> Option<Hit> {
        self.bvh.intersect(r)
    }
    fn occluded(&self, r: &Ray) -> bool {
        self.bvh.occluded(r)
    }
    fn intersect_counted(&self, r: &Ray, c: &mut Counters) -> Option<Hit> {
        self.bvh.intersect_counted(r, c)
    }
    fn occluded_counted(&self, r: &Ray, c: &mut Counters) -> bool {
        self.bvh.occluded_counted(r, c)
    }
    fn closest_point(&self, p: Vec3, radius: f32) -> Option<PointHit> {
        self.bvh.closest_point(p, radius)
    }
    fn closest_point_counted(&self, p: Vec3, radius: f32, c: &mut Counters) -> Option<PointHit> {
        self.bvh.closest_point_counted(p, radius, c)
    }
    fn build_stats(&self) -> BuildStats {
        self.bvh.build_stats()
    }
    fn memory(&self) -> Memory {
        let mut m = self.bvh.memory();
        if self.large {
            m.nodes += ONE_COPY_FROM;
        }
        m
    }
}

#[test]
fn a_large_structure_is_held_as_one_copy_and_a_small_one_keeps_its_warm_up_build() {
    let mut registry = Registry::builtin();
    for (name, large) in [("tally-small", false), ("tally-large", true)] {
        let description = "a binary BVH counting its copies (the large one claims over 1 GiB)";
        let params = (BvhParams::binned(), large);
        registry
            .register::<Tally>(name, description, params)
            .unwrap();
    }
    let opts = RunOptions {
        workloads: vec![Workload::Primary, Workload::Shadow],
        rays: 500,
        build_runs: 4,
        trace_runs: 4,
        images: false,
        reference: "bvh-binned".into(),
        ..common::options(&["tally-small", "tally-large", "bvh-binned"])
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=1000".into())];
    let report = run_with(&registry, &opts, &scenes).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert_eq!(report.mismatches(), 0);
    for name in ["tally-small", "tally-large"] {
        let r = report.results.iter().find(|r| r.structure == name);
        let r = r.unwrap_or_else(|| panic!("{name} in the report"));
        assert_eq!(r.build.samples_ms.len(), 4, "{name}");
        assert!(
            r.workloads
                .iter()
                .all(|w| w.mqueries_per_s.samples.len() == 4),
            "{name}"
        );
    }
    // The warm-up build lives through the rounds beside each timed one; the large one is
    // replaced by each timed build, never two alive at once.
    assert_eq!(MOST[0].load(Ordering::SeqCst), 2);
    assert_eq!(MOST[1].load(Ordering::SeqCst), 1);
    for live in &LIVE {
        assert_eq!(
            live.load(Ordering::SeqCst),
            0,
            "every copy dropped after the run"
        );
    }
}
