//! The shared conformance suite for both k-d tree variants and for extreme knobs, with
//! `validate()` after every build; the real scenes of ../shared/scenes for kd-sah; the same
//! for closest-point queries (testkit's point suite, every variant).

use raybench_kdtree::{KdParams, KdTree};
use raybench_testkit::points::{point_conformance, point_conformance_on_shared_scenes};
use raybench_testkit::{check_conformance, expect_too_large, generated};

fn check(params: KdParams) {
    check_conformance::<KdTree>(&params, &|kd, mesh| kd.validate(mesh));
}

#[test]
fn sah_conforms() {
    check(KdParams::sah());
}

#[test]
fn median_conforms() {
    check(KdParams::median());
}

#[test]
fn without_mailbox_conforms() {
    check(KdParams {
        mailbox: false,
        ..KdParams::sah()
    });
}

#[test]
fn exhaustive_walk_conforms() {
    check(KdParams::exhaustive());
    check(KdParams {
        mailbox: false,
        ..KdParams::exhaustive()
    });
}

#[test]
fn extreme_knobs_conform() {
    // A single leaf holding everything (depth 0).
    check(KdParams {
        max_depth: Some(0),
        ..KdParams::sah()
    });
    // Splitting always pays (free traversal, no empty bonus): deep trees, tiny leaves, many
    // duplicated references, down to the depth limit.
    check(KdParams {
        traversal_cost: 0.0,
        empty_bonus: 1.0,
        ..KdParams::sah()
    });
    // Aggressive empty-space cutting, and the median tree with leaves of one triangle and a
    // deep limit. Where no plane separates the triangles (the one-centroid case), every level
    // copies every reference, so the tree grows until the memory share stops it: a 64 MiB
    // limit stops it as the 8 GiB default does, with a hundredth of the references to build
    // and walk.
    check(KdParams {
        empty_bonus: 0.1,
        ..KdParams::sah()
    });
    check(KdParams {
        leaf_size: 1,
        max_depth: Some(40),
        memory_limit_bytes: 64 << 20,
        ..KdParams::median()
    });
}

#[test]
fn sah_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<KdTree>(&KdParams::sah(), &|kd, m| {
            kd.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}

// ---- Closest-point queries --------------------------------------------------------------

#[test]
fn point_queries_conform() {
    for params in [
        KdParams::sah(),
        KdParams::median(),
        KdParams {
            mailbox: false,
            ..KdParams::sah()
        },
        // One leaf holding everything, and deep trees with tiny leaves.
        KdParams {
            max_depth: Some(0),
            ..KdParams::sah()
        },
        KdParams {
            traversal_cost: 0.0,
            empty_bonus: 1.0,
            ..KdParams::sah()
        },
    ] {
        let counts = point_conformance::<KdTree>(&params, &|kd, m| kd.validate(m));
        assert_eq!(counts.mismatch, 0, "{}", params.name());
    }
}

#[test]
fn point_queries_conform_on_the_shared_scenes() {
    let checked = point_conformance_on_shared_scenes::<KdTree>(
        &KdParams::sah(),
        &|kd, m| kd.validate(m),
        70,
        30,
    );
    eprintln!("real scenes checked: {checked}");
}

/// A scene too large for the memory limit is refused before the build allocates anything; a
/// limit that fits the triangles but few references caps the tree's references instead (and
/// says so in the statistics), and the tree is still correct.
#[test]
fn too_large_is_an_error_not_an_abort() {
    use raybench_accel::Accel;
    let mesh = generated("soup:triangles=2000", 1);
    let tiny = KdParams {
        memory_limit_bytes: 64 * 1024,
        ..KdParams::sah()
    };
    expect_too_large::<KdTree>(&mesh, &tiny);
    // Room for the triangles and about 1.5 references each: fewer splits, same answers.
    let tight = KdParams {
        memory_limit_bytes: 2000 * 116 + 3000 * 108,
        ..KdParams::sah()
    };
    let tree = KdTree::build(mesh.clone(), &tight).expect("builds within the limit");
    tree.validate(&mesh).expect("valid");
    let stats = tree.build_stats();
    assert!(stats.refs <= 3000, "{stats:?}");
    assert!(stats.extra["memory_capped_leaves"] > 0.0, "{stats:?}");
}
