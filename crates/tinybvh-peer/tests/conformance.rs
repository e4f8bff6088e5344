//! tinybvh's layouts against brute force on every testkit case, `validate()` after each build;
//! the cases tinybvh is known to fail are named, so a fixed or new failure changes the list
//! (and docs/structures.md, which reports it). Also: identical answers and shapes whatever the
//! rayon pool a build runs on, and above tinybvh's own multithreading threshold.

use raybench_accel::Accel;
use raybench_testkit::{check_case, edge_cases, seeded_cases};
use raybench_tinybvh_peer::{BuildMode, TinyBvh, TinyBvhParams};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Runs every case; the failing ones must be exactly `known`, the passing ones must exercise hits.
fn check_known<A: Accel>(
    params: &A::Params,
    validate: &dyn Fn(&A, &raybench_geom::TriangleMesh) -> Result<(), String>,
    known: &[&str],
) {
    let mut failing = Vec::new();
    let mut total = raybench_accel::classify::VerdictCounts::default();
    for case in seeded_cases().into_iter().chain(edge_cases()) {
        match catch_unwind(AssertUnwindSafe(|| {
            check_case::<A>(&case, params, validate)
        })) {
            Ok(Ok(c)) => total += c,
            Ok(Err(e)) => {
                eprintln!("finding: {e}");
                failing.push(case.name.to_string());
            }
            Err(_) => failing.push(case.name.to_string()),
        }
    }
    assert_eq!(failing, known, "the cases tinybvh fails changed");
    eprintln!("verdicts: {total:?}");
    // Rays with t_min > 0 start at origin + t_min·dir (see the crate's `ray` module), so many
    // hits agree within tolerance rather than bit for bit: both count as exercised hits.
    let hits = total.exact + total.within_tolerance;
    assert!(hits > 10_000, "the suite must exercise hits: {total:?}");
}

fn params(build: BuildMode) -> TinyBvhParams {
    TinyBvhParams {
        build,
        ..TinyBvhParams::default()
    }
}

#[test]
fn wald_binned_fails_only_its_known_cases() {
    check_known::<TinyBvh>(&params(BuildMode::Binned), &|a, m| a.validate(m), &[]);
}

#[test]
fn wald_sbvh_fails_only_its_known_cases() {
    check_known::<TinyBvh>(&params(BuildMode::Spatial), &|a, m| a.validate(m), &[]);
}

#[cfg(target_feature = "avx2")]
#[test]
fn bvh8_cpu_fails_only_its_known_cases() {
    use raybench_tinybvh_peer::{TinyBvh8, TinyBvh8Params};
    check_known::<TinyBvh8>(&TinyBvh8Params::default(), &|a, m| a.validate(m), &[]);
}

/// Answers, shape and memory of a build on a rayon pool of `threads`.
fn built_with<A: Accel>(
    p: &A::Params,
    spec: &str,
    threads: usize,
) -> (
    Vec<Option<raybench_accel::Hit>>,
    raybench_accel::BuildStats,
    u64,
)
where
    A::Params: Sync,
{
    let mesh = raybench_testkit::generated(spec, 7);
    let rays = raybench_testkit::random_rays_in(&mesh.bounds(), 3000, 7);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let a = pool.install(|| A::build(mesh.clone(), p).unwrap());
    let hits = rays.iter().map(|r| a.intersect(r)).collect();
    (hits, a.build_stats(), a.memory().total())
}

fn deterministic<A: Accel>(p: &A::Params)
where
    A::Params: Sync,
{
    // 3,000 triangles builds on one thread; 60,000 crosses tinybvh's 50,000-triangle threshold
    // above which it builds subtrees on its own C++ threads.
    for spec in ["soup:triangles=3000", "sphere:triangles=60000"] {
        let one = built_with::<A>(p, spec, 1);
        assert!(one.0.iter().filter(|h| h.is_some()).count() > 100, "{spec}");
        for threads in [2, 1] {
            assert_eq!(one, built_with::<A>(p, spec, threads), "{spec}");
        }
    }
}

#[test]
fn same_answers_and_shape_whatever_the_thread_count() {
    deterministic::<TinyBvh>(&params(BuildMode::Binned));
    deterministic::<TinyBvh>(&params(BuildMode::Spatial));
    #[cfg(target_feature = "avx2")]
    deterministic::<raybench_tinybvh_peer::TinyBvh8>(&Default::default());
}

/// A finding, not a wrapper bug: tinybvh's scalar Möller–Trumbore (the Wald layout's) rejects
/// |det| < 1e-6 in absolute terms, so a unit ray misses a triangle with half-millimetre edges
/// (det = 2.5e-7 here) that brute force and Embree hit; BVH8_CPU's test has no such threshold.
/// On stanford-bunny.obj (edges around 1e-3) this makes thousands of `peer-tinybvh` mismatches.
#[test]
fn wald_layout_misses_triangles_whose_determinant_is_below_1e_6() {
    use raybench_accel::BruteForce;
    use raybench_geom::{Ray, Vec3};
    let e = 5e-4;
    let mesh = raybench_testkit::mesh(
        vec![Vec3::ZERO, Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, e, 0.0)],
        vec![[0, 1, 2]],
    );
    let ray = Ray::new(
        Vec3::new(e / 4.0, e / 4.0, 1.0),
        Vec3::NEG_Z,
        0.0,
        f32::INFINITY,
    );
    let oracle = BruteForce::build(mesh.clone(), &Default::default()).unwrap();
    assert!(oracle.intersect(&ray).is_some());
    for build in [BuildMode::Binned, BuildMode::Spatial] {
        let tiny = TinyBvh::build(mesh.clone(), &params(build)).unwrap();
        assert_eq!(tiny.intersect(&ray), None, "{build:?}");
        // The same triangle ten times larger (det 2.5e-5) is hit.
        let big = raybench_testkit::mesh(
            vec![
                Vec3::ZERO,
                Vec3::new(10.0 * e, 0.0, 0.0),
                Vec3::new(0.0, 10.0 * e, 0.0),
            ],
            vec![[0, 1, 2]],
        );
        let tiny = TinyBvh::build(big, &params(build)).unwrap();
        assert!(tiny.intersect(&ray).is_some(), "{build:?}");
    }
    #[cfg(target_feature = "avx2")]
    {
        let bvh8 = raybench_tinybvh_peer::TinyBvh8::build(mesh, &Default::default()).unwrap();
        let (got, want) = (
            bvh8.intersect(&ray).unwrap(),
            oracle.intersect(&ray).unwrap(),
        );
        assert_eq!(got.prim, want.prim);
        assert!((got.t - want.t).abs() <= 1e-6, "{got:?} {want:?}");
    }
}
