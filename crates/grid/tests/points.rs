//! Grid closest-point cases on top of the shared point suite: points exactly on cell planes,
//! edges and corners, points far outside the grid, and what the counters must show.

use raybench_accel::{Accel, Counters};
use raybench_geom::{TriangleMesh, Vec3};
use raybench_grid::{Grid, GridParams};
use raybench_testkit::points::{
    check_points, check_points_at_radii, counted_work as work, points_in_box, points_near_surface,
    points_on_planes,
};
use raybench_testkit::{generated, lattice_scene};
use std::sync::Arc;

const SEED: u64 = 0x5eed_7601;

fn soup() -> Arc<TriangleMesh> {
    generated("soup:triangles=3000", SEED)
}

/// The lattice scene in 8³ cells of side 0.5: points on every plane, edge and corner of the
/// grid (and one cell beyond it), then random points with one or two coordinates snapped to a
/// plane. A point on a plane is in both closed cells; either may be its home cell.
#[test]
fn points_on_cell_planes_edges_and_corners() {
    let mesh = lattice_scene();
    let params = GridParams::with_density(512.0 / mesh.len() as f64);
    let grid = Grid::build(mesh.clone(), &params).unwrap();
    assert_eq!(grid.resolution(), [8, 8, 8]);
    let points = points_on_planes(-0.5, 0.5, 11, 2, &mesh.bounds(), SEED);
    check_points_at_radii(&grid, &mesh, &points);
}

/// Near the surface, the search opens a few cells and tests a few triangles.
#[test]
fn pruning_keeps_near_surface_queries_local() {
    let mesh = soup();
    let grid = Grid::build(mesh.clone(), &GridParams::default()).unwrap();
    let points = points_near_surface(&mesh, 1000, 0.01 * mesh.bounds().diagonal(), SEED);
    let c = work(&grid, &points, f32::INFINITY);
    let per = |x: u64| x as f64 / points.len() as f64;
    let cells: u32 = grid.resolution().iter().product();
    eprintln!(
        "per query: {} tests, {} cells of {cells}",
        per(c.prim_tests),
        per(c.cells)
    );
    // Measured 6.9 tests and 2.0 cells (of 2744) per query; a search that stopped pruning
    // would open whole shells of cells.
    assert!(per(c.prim_tests) < 20.0, "of 3000 triangles: {c:?}");
    assert!(per(c.cells) < 8.0, "of {cells} cells: {c:?}");
}

/// A point far beyond one face of the grid starts from the clamped cell, and only the layer
/// of cells facing it can hold the nearest triangle: every row of that face is examined, but
/// each stops at its first cell out of reach. Shells never go past the grid's resolution.
#[test]
fn far_points_examine_about_one_layer() {
    let mesh = soup();
    let grid = Grid::build(mesh.clone(), &GridParams::default()).unwrap();
    let [nx, ny, nz] = grid.resolution();
    let b = mesh.bounds();
    let away = 1e4 * b.diagonal();
    let points = [
        Vec3::new(b.max.x + away, b.center().y, b.center().z),
        Vec3::new(b.center().x, b.min.y - away, b.max.z),
        Vec3::new(b.min.x - away, b.max.y + away, b.min.z - away),
    ];
    check_points(&grid, &mesh, &points, f32::INFINITY).unwrap();
    let mut c = Counters::default();
    grid.closest_point_counted(points[0], f32::INFINITY, &mut c);
    eprintln!("{c:?} for {nx}x{ny}x{nz} cells");
    assert!(c.cells <= 3 * (ny * nz) as u64, "{c:?}, {nx}x{ny}x{nz}");
    // Beyond the radius: not one cell.
    let mut c = Counters::default();
    assert_eq!(
        grid.closest_point_counted(points[0], away * 0.5, &mut c),
        None
    );
    assert_eq!(c, Counters::default());
}

/// A finite radius prunes from the first shell on.
#[test]
fn the_radius_prunes_from_the_start() {
    let mesh = soup();
    let grid = Grid::build(mesh.clone(), &GridParams::default()).unwrap();
    let points = points_in_box(&mesh.bounds().enlarged(0.2), 1000, SEED);
    let all = work(&grid, &points, f32::INFINITY);
    let near = work(&grid, &points, 0.01);
    assert!(near.prim_tests < all.prim_tests / 2, "{near:?} vs {all:?}");
    assert!(near.cells < all.cells, "{near:?} vs {all:?}");
    assert!(all.mailbox_skips > 0, "{all:?}");
}
