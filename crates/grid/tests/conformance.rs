//! The shared conformance suite for every grid variant, `validate()` after every build, plus
//! rays aimed at the grid's own geometry: axis-parallel, starting inside, exactly along cell
//! planes, edges and corners.

use raybench_accel::Accel;
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_grid::{Grid, GridParams};
use raybench_testkit::points::{point_conformance, point_conformance_on_shared_scenes};
use raybench_testkit::{
    check_conformance, check_lattice, expect_too_large, generated, lattice_rays, lattice_scene,
    refused_rays,
};
use std::sync::Arc;

fn check(params: GridParams) {
    check_conformance::<Grid>(&params, &|g, mesh| g.validate(mesh));
}

#[test]
fn default_conforms() {
    check(GridParams::default());
}

#[test]
fn coarse_conforms() {
    check(GridParams::coarse());
}

#[test]
fn fine_conforms() {
    check(GridParams::fine());
}

#[test]
fn extreme_knobs_conform() {
    // One cell for everything; a very dense grid capped at 8 cells per axis; a single cell
    // per axis by cap.
    check(GridParams::with_density(1e-6));
    check(GridParams {
        max_resolution: 8,
        ..GridParams::with_density(64.0)
    });
    check(GridParams {
        max_resolution: 1,
        ..GridParams::default()
    });
    check(GridParams::with_density(200.0));
}

#[test]
fn default_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Grid>(&GridParams::default(), &|g, m| {
            g.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}

#[test]
fn too_large_is_an_error_not_an_abort() {
    let mesh = generated("soup:triangles=2000", 1);
    let params = GridParams {
        memory_limit_bytes: 64 * 1024,
        ..GridParams::default()
    };
    expect_too_large::<Grid>(&mesh, &params);
    // References alone over the limit (the offsets and copies fit).
    let params = GridParams {
        memory_limit_bytes: 2000 * 48 + 4 * 4100 + 12 * 1000,
        ..GridParams::with_density(2.0)
    };
    expect_too_large::<Grid>(&mesh, &params);
}

/// The testkit's lattice scene with a grid of 8³ cells of side 0.5 (dyadic planes).
fn plane_scene() -> (Arc<TriangleMesh>, GridParams) {
    let mesh = lattice_scene();
    // λN = 512 cells over a 4³ box: side 0.5, 8 per axis.
    let params = GridParams::with_density(512.0 / mesh.len() as f64);
    (mesh, params)
}

#[test]
fn rays_along_cell_planes_edges_and_corners() {
    let (mesh, params) = plane_scene();
    let grid = Grid::build(mesh, &params).unwrap();
    assert_eq!(
        grid.resolution(),
        [8, 8, 8],
        "the scene must give 0.5-wide cells"
    );
    check_lattice::<Grid>("cell-planes", &params, &|g, m| g.validate(m));
}

#[test]
fn walks_are_bounded_and_counted() {
    let (mesh, params) = plane_scene();
    let grid = Grid::build(mesh, &params).unwrap();
    // A ray missing everything along a cell edge walks at most one row of cells.
    let r = Ray::infinite(Vec3::new(0.5, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
    let mut c = raybench_accel::Counters::default();
    grid.intersect_counted(&r, &mut c);
    assert!(c.cells >= 1 && c.cells <= 8, "{c:?}");
    // The mailbox skips a triangle met again: the big slanted one spans many cells.
    let mut total = raybench_accel::Counters::default();
    for r in lattice_rays() {
        grid.intersect_counted(&r, &mut total);
    }
    assert!(total.mailbox_skips > 0, "{total:?}");
    // Invalid rays (NaN, zero direction) miss in bounded time.
    for r in refused_rays() {
        let mut c = raybench_accel::Counters::default();
        let _ = grid.intersect_counted(&r, &mut c);
        assert!(c.cells <= 24, "{r:?}: {c:?}");
    }
}

// ---- Closest-point queries --------------------------------------------------------------

#[test]
fn point_queries_conform() {
    for params in [
        GridParams::default(),
        GridParams::coarse(),
        GridParams::fine(),
        // One cell for everything, and a dense grid capped at 8 cells per axis.
        GridParams::with_density(1e-6),
        GridParams {
            max_resolution: 8,
            ..GridParams::with_density(64.0)
        },
    ] {
        let counts = point_conformance::<Grid>(&params, &|g, m| g.validate(m));
        assert_eq!(counts.mismatch, 0, "{}", params.name());
    }
}

#[test]
fn point_queries_conform_on_the_shared_scenes() {
    let checked = point_conformance_on_shared_scenes::<Grid>(
        &GridParams::default(),
        &|g, m| g.validate(m),
        70,
        30,
    );
    eprintln!("real scenes checked: {checked}");
}
