//! The shared conformance suite (raybench-testkit) for every Embree preset: seeded scenes and
//! edge cases against brute force, zero mismatches.

use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_testkit::{conformance, no_validation};

fn check(params: EmbreeParams) {
    let counts = conformance::<EmbreeScene>(&params, &no_validation);
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact + counts.within_tolerance > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
}

#[test]
fn embree_low_conforms() {
    check(EmbreeParams::low());
}

#[test]
fn embree_medium_conforms() {
    check(EmbreeParams::medium());
}

/// Coherent batches through `rtcIntersect1M` (the conformance suite's coherent-batch check
/// holds every answer that differs from `rtcIntersect1`'s to brute force).
#[test]
fn embree_medium_stream_conforms() {
    check(EmbreeParams::medium_stream());
}

/// Coherent batches through `rtcIntersect16`/`rtcOccluded16` (the coherent-batch check runs
/// ranges that end inside a packet and one that starts off a packet boundary).
#[test]
fn embree_medium_packet16_conforms() {
    check(EmbreeParams::medium_packet16());
}

#[test]
fn embree_high_conforms() {
    check(EmbreeParams::high());
}

#[test]
fn embree_robust_conforms() {
    check(EmbreeParams::robust());
}

/// Closest-point queries (`rtcPointQuery`) against brute force on the shared point suite:
/// every preset, zero mismatches.
#[test]
fn embree_point_queries_conform() {
    use raybench_testkit::points::point_conformance;
    for params in [
        EmbreeParams::low(),
        EmbreeParams::medium(),
        EmbreeParams::high(),
        EmbreeParams::robust(),
    ] {
        let counts = point_conformance::<EmbreeScene>(&params, &no_validation);
        assert_eq!(counts.mismatch, 0, "{params:?}");
    }
}

#[test]
fn embree_point_queries_conform_on_the_shared_scenes() {
    use raybench_testkit::points::point_conformance_on_shared_scenes;
    let checked = point_conformance_on_shared_scenes::<EmbreeScene>(
        &EmbreeParams::medium(),
        &no_validation,
        70,
        30,
    );
    eprintln!("point queries checked on {checked} shared scenes");
}
