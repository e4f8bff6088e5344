//! The oracle against itself with the other triangle test: the watertight brute force must
//! agree with the Möller–Trumbore brute force everywhere except classified edge cases.

use raybench_accel::{BruteForce, BruteForceParams};
use raybench_geom::TriangleTest;

#[test]
fn bruteforce_conforms() {
    let counts = raybench_testkit::conformance::<BruteForce>(
        &BruteForceParams::default(),
        &raybench_testkit::no_validation,
    );
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
}

#[test]
fn watertight_bruteforce_conforms() {
    let params = BruteForceParams {
        triangle_test: TriangleTest::Watertight,
    };
    let counts =
        raybench_testkit::conformance::<BruteForce>(&params, &raybench_testkit::no_validation);
    assert_eq!(counts.mismatch, 0);
}
