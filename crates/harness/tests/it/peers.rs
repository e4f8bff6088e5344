//! The `peer-*` entries (other crates' structures) against BruteForce on every testkit case
//! (seeded scenes and edge cases), and a missing capability reported as "not offered".
//!
//! A peer's wrong answers are findings about that crate, not failures to hide: each test names
//! the cases its crate (at the pinned version) is known to fail and asserts that exactly those
//! fail, so every other case must agree with brute force, and a fixed or new failure changes
//! the list (and docs/structures.md, which reports it).
#![cfg(feature = "peers")]

use crate::common;

use raybench_accel::Accel;
use raybench_harness::output::summary::summary_table;
use raybench_harness::peers::{
    BvhCrate, BvhCrateParams, KdtreeRay, KdtreeRayParams, Obvhs, ObvhsParams, Parry, ParryParams,
};
use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::registry;
use raybench_scenes::{SceneRequest, Workload};
use raybench_testkit::points::point_conformance;
use raybench_testkit::{check_case, edge_cases, no_validation, seeded_cases};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Runs every case; asserts that the failing ones (a mismatch with brute force, an
/// inconsistency between the structure's own queries, or a panic inside the crate) are exactly
/// `known`, and that the passing ones exercised hits.
fn check_peer<A: Accel>(params: &A::Params, known: &[&str]) {
    let mut failing = Vec::new();
    let mut exact = 0;
    for case in seeded_cases().into_iter().chain(edge_cases()) {
        match catch_unwind(AssertUnwindSafe(|| {
            check_case::<A>(&case, params, &no_validation)
        })) {
            Ok(Ok(counts)) => exact += counts.exact,
            Ok(Err(e)) => {
                eprintln!("finding: {e}");
                failing.push(case.name.to_string());
            }
            Err(_) => failing.push(case.name.to_string()),
        }
    }
    assert_eq!(failing, known, "the cases this crate fails changed");
    assert!(exact > 10_000, "the suite must exercise hits: {exact}");
}

#[test]
fn bvh_crate_agrees_with_brute_force_everywhere() {
    check_peer::<BvhCrate>(&BvhCrateParams {}, &[]);
    let counts = point_conformance::<BvhCrate>(&BvhCrateParams {}, &no_validation);
    assert!(counts.answered() > 1000, "{counts:?}");
}

#[test]
fn obvhs_fails_only_its_known_cases() {
    // Axis-parallel rays whose other direction components are -0 miss flat boxes; the tree over
    // identical triangles is deeper than the crate's 32-entry traversal stack (its debug-build
    // validation panics; a release build walks it unchecked).
    let identical: &[&str] = if cfg!(debug_assertions) {
        &["identical-triangles"]
    } else {
        &[]
    };
    let mut known = vec!["one-triangle"];
    known.extend(identical);
    known.extend(["flat-scene", "axis-parallel-rays", "coplanar-axis-aligned"]);
    check_peer::<Obvhs>(&ObvhsParams::default(), &known);
}

#[test]
fn parry3d_fails_only_its_known_cases() {
    // Rays leaving a surface stop at t = 0 on it (parry's casts have no t_min); a ray of the
    // edges-and-planes soup misses a triangle; near 1.8e18 two casts of one ray disagree.
    check_peer::<Parry>(
        &ParryParams {},
        &["rays-from-surfaces", "edges-and-planes-soup", "near-1.8e18"],
    );
    let counts = point_conformance::<Parry>(&ParryParams {}, &no_validation);
    assert!(counts.answered() > 1000, "{counts:?}");
}

#[test]
fn kdtree_ray_fails_only_its_known_cases() {
    // Axis-parallel rays whose other direction components are -0 miss flat cells.
    check_peer::<KdtreeRay>(
        &KdtreeRayParams {},
        &["flat-scene", "axis-parallel-rays", "coplanar-axis-aligned"],
    );
}

#[test]
fn every_peer_is_registered_as_a_peer_and_only_peers_are() {
    let registry = registry::Registry::builtin();
    let all = registry.entries();
    let peers: Vec<&str> = all.iter().filter(|e| e.peer).map(|e| e.name).collect();
    assert_eq!(
        peers,
        [
            "peer-bvh",
            "peer-obvhs",
            "peer-parry3d",
            "peer-kdtree-ray",
            "peer-tinybvh",
            "peer-tinybvh-hq",
        ]
        .into_iter()
        .chain(cfg!(target_feature = "avx2").then_some("peer-tinybvh-bvh8"))
        .collect::<Vec<_>>()
    );
    assert!(
        all.iter()
            .all(|e| e.peer == raybench_harness::registry::is_peer_name(e.name))
    );
}

#[test]
fn a_peer_without_closest_point_is_reported_as_not_offered() {
    let options = RunOptions {
        workloads: vec![Workload::Random, Workload::POINTS[0]],
        points: 200,
        rays: 500,
        images: false,
        ..common::options(&["embree-medium", "peer-obvhs", "peer-bvh"])
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=500".into())];
    let report = run(&options, &scenes).expect("the run succeeds");
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let point = Workload::POINTS[0].name();
    let of = |name: &str| report.results.iter().find(|r| r.structure == name).unwrap();
    let obvhs = of("peer-obvhs");
    assert_eq!(obvhs.not_offered, [point]);
    assert!(obvhs.workloads.iter().all(|w| !w.point_query));
    assert!(obvhs.workloads.iter().any(|w| w.workload == "random"));
    let bvh = of("peer-bvh");
    assert!(bvh.not_offered.is_empty());
    assert!(bvh.workloads.iter().any(|w| w.workload == point));
    let json = serde_json::to_value(obvhs).unwrap();
    assert_eq!(json["not_offered"][0], point);
    let table = summary_table(&report);
    let row = table.lines().find(|l| l.contains("peer-obvhs")).unwrap();
    assert!(row.contains("not offered"), "{row}");
    let row = table.lines().find(|l| l.contains("peer-bvh")).unwrap();
    assert!(!row.contains("not offered"), "{row}");
}

/// Builds in a rayon pool of `threads` and traces `rays` (closest hit).
fn answers_with_threads<A: Accel>(
    params: &A::Params,
    mesh: &std::sync::Arc<raybench_geom::TriangleMesh>,
    rays: &[raybench_geom::Ray],
    threads: usize,
) -> Vec<Option<raybench_accel::Hit>>
where
    A::Params: Sync,
{
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let accel = pool.install(|| A::build(mesh.clone(), params).unwrap());
    rays.iter().map(|r| accel.intersect(r)).collect()
}

#[test]
fn peers_answer_identically_whatever_the_build_thread_count() {
    let mesh = raybench_testkit::generated("soup:triangles=3000", 7);
    let rays = raybench_testkit::random_rays_in(&mesh.bounds(), 3000, 7);
    fn same<A: Accel>(
        p: &A::Params,
        mesh: &std::sync::Arc<raybench_geom::TriangleMesh>,
        rays: &[raybench_geom::Ray],
    ) where
        A::Params: Sync,
    {
        let one = answers_with_threads::<A>(p, mesh, rays, 1);
        assert!(one.iter().filter(|h| h.is_some()).count() > 100);
        assert_eq!(one, answers_with_threads::<A>(p, mesh, rays, 2));
    }
    same::<BvhCrate>(&BvhCrateParams {}, &mesh, &rays);
    same::<Obvhs>(&ObvhsParams::default(), &mesh, &rays);
    same::<Parry>(&ParryParams {}, &mesh, &rays);
    same::<KdtreeRay>(&KdtreeRayParams {}, &mesh, &rays);
}
