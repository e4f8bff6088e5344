//! The toy against brute force on raybench's conformance suite (seeded scenes and the edge
//! cases: empty mesh, one triangle, one shared centroid, flat boxes, axis-parallel rays), with
//! `validate()` after every build: the example cannot silently be wrong.

use custom_structure::{ToyBvh, ToyParams};
use raybench_accel::Accel;
use raybench_testkit::points::point_conformance;
use raybench_testkit::{check_conformance, generated};

fn validated(bvh: &ToyBvh, mesh: &raybench_geom::TriangleMesh) -> Result<(), String> {
    bvh.validate(mesh)
}

#[test]
fn rays_conform_with_default_and_one_triangle_leaves() {
    for max_leaf_size in [4, 1, 64] {
        check_conformance::<ToyBvh>(&ToyParams { max_leaf_size }, &validated);
    }
}

#[test]
fn closest_points_conform() {
    let counts = point_conformance::<ToyBvh>(&ToyParams::default(), &validated);
    assert_eq!(counts.mismatch, 0);
}

#[test]
fn the_tree_is_a_function_of_the_mesh() {
    let mesh = generated("soup:triangles=2000", 7);
    let a = ToyBvh::build(mesh.clone(), &ToyParams::default()).unwrap();
    let b = ToyBvh::build(mesh.clone(), &ToyParams::default()).unwrap();
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    assert_eq!(a.build_stats(), b.build_stats());
    assert!(a.build_stats().leaves >= 2000 / 4);
}

#[test]
fn a_zero_leaf_size_is_refused() {
    let mesh = generated("soup:triangles=10", 1);
    let err = ToyBvh::build(mesh, &ToyParams { max_leaf_size: 0 }).unwrap_err();
    assert!(err.to_string().contains("max_leaf_size"), "{err}");
}
