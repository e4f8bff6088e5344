//! Interleaved rounds: every timed pass is kept, ratios come with intervals, with a time
//! budget the extra rounds keep the reference paired with everyone who takes part, each timed
//! build replaces the copy the passes trace, and a build is timed again only while its new copy
//! fits in memory beside the old.

use crate::common;

use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, Walk};
use raybench_bvh::{Bvh, BvhParams};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_harness::Registry;
use raybench_harness::pipeline::run::{RunOptions, run, run_with};
use raybench_harness::report::run::Report;
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

/// Per kind of [`Counted`] (0: its true size, 1: claiming an exabyte, so that no machine has
/// room for another copy): how many were built, how many are alive, and the most alive at once.
static BUILDS: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
static LIVE: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
static MOST: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// A binary BVH that counts its copies, and may claim an exabyte of memory.
#[derive(Debug)]
struct Counted {
    bvh: Bvh,
    huge: bool,
}

impl Drop for Counted {
    fn drop(&mut self) {
        LIVE[self.huge as usize].fetch_sub(1, Ordering::SeqCst);
    }
}

impl Accel for Counted {
    /// The BVH's parameters, and whether to claim an exabyte.
    type Params = (BvhParams, bool);
    fn build(
        mesh: Arc<TriangleMesh>,
        (p, huge): &(BvhParams, bool),
    ) -> Result<Counted, BuildError> {
        let bvh = Bvh::build(mesh, p)?;
        let i = *huge as usize;
        BUILDS[i].fetch_add(1, Ordering::SeqCst);
        let live = LIVE[i].fetch_add(1, Ordering::SeqCst) + 1;
        MOST[i].fetch_max(live, Ordering::SeqCst);
        Ok(Counted { bvh, huge: *huge })
    }
    fn name(&self) -> &str {
        "counted"
    }
    raybench_accel::walk_queries!();
    fn build_stats(&self) -> BuildStats {
        self.bvh.build_stats()
    }
    fn memory(&self) -> Memory {
        let m = self.bvh.memory();
        if self.huge {
            Memory {
                nodes: 1 << 60,
                ..m
            }
        } else {
            m
        }
    }
}

/// The walk is the BVH's.
impl Walk for Counted {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.bvh.walk_ray::<ANY_HIT, C>(ray, c)
    }
    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.bvh.walk_point(p, max_radius, c)
    }
}

/// A run of a [`Counted`] BVH registered as `name` (an exabyte claimed when `huge`) against
/// `bvh-binned`, on a small sphere: its report, checked to have no errors or mismatches.
fn run_counted(name: &'static str, huge: bool, build_runs: usize, trace_runs: usize) -> Report {
    let mut registry = Registry::builtin();
    registry
        .register::<Counted>(
            name,
            "a binary BVH counting its copies",
            (BvhParams::binned(), huge),
        )
        .unwrap();
    let opts = RunOptions {
        workloads: vec![Workload::Primary, Workload::Shadow],
        rays: 500,
        build_runs,
        trace_runs,
        images: false,
        reference: "bvh-binned".into(),
        ..common::options(&[name, "bvh-binned"])
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=1000".into())];
    let report = run_with(&registry, &opts, &scenes).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert_eq!(report.mismatches(), 0);
    report
}

#[test]
fn a_build_with_no_room_for_a_second_copy_is_not_timed_again_and_the_report_says_so() {
    let report = run_counted("huge", true, 3, 3);
    let result = |name: &str| report.results.iter().find(|r| r.structure == name).unwrap();
    // Built once, for the checks; that build's time stands for it.
    assert_eq!(BUILDS[1].load(Ordering::SeqCst), 1);
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

#[test]
fn each_timed_build_replaces_the_traced_copy_so_one_copy_is_alive_at_a_time() {
    let report = run_counted("tally", false, 4, 5);
    let tally = report.results.iter().find(|r| r.structure == "tally");
    let tally = tally.expect("tally in the report");
    assert_eq!(tally.build.samples_ms.len(), 4);
    assert!(
        tally
            .workloads
            .iter()
            .all(|w| w.mqueries_per_s.samples.len() == 5)
    );
    // The warm-up build and four timed ones, each dropped before the next was made, and the
    // last dropped when the scene was done.
    assert_eq!(BUILDS[0].load(Ordering::SeqCst), 5);
    assert_eq!(MOST[0].load(Ordering::SeqCst), 1);
    assert_eq!(LIVE[0].load(Ordering::SeqCst), 0);
}
