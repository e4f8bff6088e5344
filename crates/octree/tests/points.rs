//! Octree closest-point cases on top of the shared point suite: points exactly on octant
//! planes, edges and corners, and what the counters must show (pruning, nearest octant first,
//! the radius).

use raybench_accel::{Accel, Counters};
use raybench_geom::{TriangleMesh, Vec3};
use raybench_octree::{Octree, OctreeParams};
use raybench_testkit::points::{
    check_points, check_points_at_radii, counted_work as work, points_in_box, points_near_surface,
    points_on_planes,
};
use raybench_testkit::{generated, lattice_scene};
use std::sync::Arc;

const SEED: u64 = 0x5eed_7801;

fn soup() -> Arc<TriangleMesh> {
    generated("soup:triangles=3000", SEED)
}

/// The lattice scene's root is the cube [0, 4]³, so octant planes are dyadic: points on every
/// plane, edge and corner down to 1/4 cells (and beyond the root), then random points with
/// one or two coordinates snapped to one. Such a point touches several octants at distance 0.
#[test]
fn points_on_octant_planes_edges_and_corners() {
    let mesh = lattice_scene();
    for max_obj in [1, 8] {
        let params = OctreeParams {
            max_obj,
            ..OctreeParams::default()
        };
        let tree = Octree::build(mesh.clone(), &params).unwrap();
        tree.validate(&mesh).unwrap();
        assert_eq!(
            (tree.root_box().min, tree.root_box().max),
            (Vec3::ZERO, Vec3::splat(4.0))
        );
        let points = points_on_planes(-0.25, 0.25, 19, 3, &mesh.bounds(), SEED);
        check_points_at_radii(&tree, &mesh, &points);
    }
}

/// Near the surface, the search opens a few leaves and tests a few triangles.
#[test]
fn pruning_keeps_near_surface_queries_local() {
    let mesh = soup();
    let tree = Octree::build(mesh.clone(), &OctreeParams::default()).unwrap();
    let points = points_near_surface(&mesh, 1000, 0.01 * mesh.bounds().diagonal(), SEED);
    let c = work(&tree, &points, f32::INFINITY);
    let per = |x: u64| x as f64 / points.len() as f64;
    let leaves = tree.build_stats().leaves;
    eprintln!(
        "per query: {} tests, {} leaves of {leaves}, {} nodes",
        per(c.prim_tests),
        per(c.leaves),
        per(c.nodes)
    );
    // Measured 6.0 tests and 1.5 leaves (of 3298) per query; a search that stopped pruning
    // would open hundreds.
    assert!(per(c.prim_tests) < 20.0, "of 3000 triangles: {c:?}");
    assert!(per(c.leaves) < 6.0, "of {leaves} leaves: {c:?}");
}

/// A finite radius prunes from the root on; a point farther than the radius from the root
/// box costs nothing, and a far point descends nearest octant first.
#[test]
fn the_radius_prunes_from_the_start() {
    let mesh = soup();
    let tree = Octree::build(mesh.clone(), &OctreeParams::default()).unwrap();
    let points = points_in_box(&mesh.bounds().enlarged(0.2), 1000, SEED);
    let all = work(&tree, &points, f32::INFINITY);
    let near = work(&tree, &points, 0.01);
    assert!(near.prim_tests < all.prim_tests / 2, "{near:?} vs {all:?}");
    assert!(near.nodes < all.nodes, "{near:?} vs {all:?}");
    assert!(all.mailbox_skips > 0, "{all:?}");
    let far = mesh.bounds().max + Vec3::splat(10.0);
    let mut c = Counters::default();
    assert_eq!(tree.closest_point_counted(far, 1.0, &mut c), None);
    assert_eq!(c, Counters::default());
    check_points(&tree, &mesh, &[far], f32::INFINITY).unwrap();
    tree.closest_point_counted(far, f32::INFINITY, &mut c);
    // Measured 5 leaves and 12 tests: the corner octants facing the point, not the tree.
    assert!(c.leaves <= 10 && c.prim_tests < 40, "{c:?}");
}
