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
