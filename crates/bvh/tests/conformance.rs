//! The shared conformance suite for every BVH variant, `validate()` after every build.

use raybench_bvh::{Bvh, Bvh8, Bvh8Params, BvhParams};
use raybench_testkit::conformance;

fn check(params: BvhParams) {
    let counts = conformance::<Bvh>(&params, &|bvh, mesh| bvh.validate(mesh));
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
}

#[test]
fn median_conforms() {
    check(BvhParams::median());
}

#[test]
fn sweep_conforms() {
    check(BvhParams::sweep());
}

#[test]
fn binned_conforms() {
    check(BvhParams::binned());
}

#[test]
fn binned_unordered_conforms() {
    check(BvhParams::binned_unordered());
}

#[test]
fn tiny_leaves_and_coarse_bins_conform() {
    // Extreme knobs exercise deep trees and forced splits.
    check(BvhParams {
        max_leaf_size: 1,
        bins: 2,
        ..BvhParams::binned()
    });
    check(BvhParams {
        max_leaf_size: 1,
        ..BvhParams::sweep()
    });
}

#[test]
fn binned_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Bvh>(&BvhParams::binned(), &|b, m| {
            b.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}

#[test]
fn wide_conforms() {
    let counts = conformance::<Bvh8>(&Bvh8Params::default(), &|b, mesh| b.validate(mesh));
    assert_eq!(counts.mismatch, 0);
    assert!(counts.exact > 10_000, "{counts:?}");
    // Tiny leaves make deep binary trees and full wide nodes.
    let tiny = Bvh8Params {
        binary: BvhParams {
            max_leaf_size: 1,
            ..BvhParams::binned()
        },
        ..Bvh8Params::default()
    };
    let counts = conformance::<Bvh8>(&tiny, &|b, mesh| b.validate(mesh));
    assert_eq!(counts.mismatch, 0);
}

#[test]
fn wide_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Bvh8>(&Bvh8Params::default(), &|b, m| {
            b.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}
