//! The skipping grid: the shared conformance suite with `validate()` after every build, and
//! the stronger property its jumps promise: on every ray, the same answer as the uniform grid
//! bit for bit, with the same triangle tests and mailbox skips (the same non-empty cells in the
//! same order), never more cells — on scenes with much empty space, and rays that start
//! inside, run along cell planes, or have ±0 direction components.

use raybench_accel::{Accel, Counters};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_grid::build::Layout;
use raybench_grid::{Grid, GridParams, SkipGrid, SkipGridParams};
use raybench_testkit::points::point_conformance;
use raybench_testkit::{
    Case, camera_ray_sets, check_case, check_conformance, check_lattice, edge_cases,
    expect_too_large, generated, random_rays_in, refused_rays, seeded_cases,
};
use std::sync::Arc;

const SEED: u64 = 0x5c1_9a7e;

fn with_grid(grid: GridParams) -> SkipGridParams {
    SkipGridParams {
        grid,
        ..SkipGridParams::default()
    }
}

#[test]
fn default_conforms() {
    check_conformance::<SkipGrid>(&SkipGridParams::default(), &|g, m| g.validate(m));
}

#[test]
fn extreme_knobs_conform() {
    for params in [
        // Most cells empty and far from triangles: long jumps.
        with_grid(GridParams::fine()),
        // One cell; a grid capped at 8 cells per axis.
        with_grid(GridParams::with_density(1e-6)),
        with_grid(GridParams {
            max_resolution: 8,
            ..GridParams::with_density(64.0)
        }),
        // Jumps only from the farthest cells; and from every cell that allows one.
        SkipGridParams {
            min_jump: 255,
            ..SkipGridParams::default()
        },
        SkipGridParams {
            min_jump: 2,
            ..with_grid(GridParams::fine())
        },
    ] {
        check_conformance::<SkipGrid>(&params, &|g, m| g.validate(m));
    }
}

#[test]
fn default_conforms_on_the_shared_scenes() {
    let checked = raybench_testkit::conformance_on_shared_scenes::<SkipGrid>(
        &SkipGridParams::default(),
        &|g, m| g.validate(m),
    );
    eprintln!("real scenes checked: {checked}");
}

#[test]
fn rays_along_cell_planes_edges_and_corners() {
    // The lattice scene with 0.5-wide cells (dyadic planes), as the uniform grid's test.
    let mesh = raybench_testkit::lattice_scene();
    for density in [512.0, 4096.0] {
        let params = with_grid(GridParams::with_density(density / mesh.len() as f64));
        check_lattice::<SkipGrid>("cell-planes", &params, &|g, m| g.validate(m));
    }
}

/// A small deterministic generator (the tests depend on no RNG crate).
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Rays for the skip: from random points of the grid (inside, so walks start anywhere), with
/// directions that are random, axis-parallel (one or two components ±0), or lying in a cell
/// plane from an origin on it (grazing every cell boundary they pass), and rays from outside
/// aimed through the grid along and between cell planes.
fn skip_rays(mesh: &TriangleMesh, params: &GridParams, n: usize, seed: u64) -> Vec<Ray> {
    let b = mesh.bounds();
    let layout = Layout::new(&b, mesh.len(), params);
    let mut rng = XorShift(seed | 1);
    let mut rays = random_rays_in(&b.enlarged(0.05), n, seed);
    let zeros = [0.0f32, -0.0];
    for i in 0..n {
        let mut o = Vec3::from_array(std::array::from_fn(|a| {
            b.min[a] + (b.max[a] - b.min[a]) * rng.unit()
        }));
        let mut d = Vec3::from_array(std::array::from_fn(|_| rng.unit() * 2.0 - 1.0));
        match i % 4 {
            0 => {}
            1 => d[rng.below(3)] = zeros[rng.below(2)],
            2 => {
                let keep = rng.below(3);
                for a in 0..3 {
                    if a != keep {
                        d[a] = zeros[rng.below(2)];
                    }
                }
            }
            _ => {
                // On a cell plane of one axis, moving within it.
                let a = rng.below(3);
                let planes = &layout.planes[a];
                o[a] = planes[rng.below(planes.len())] as f32;
                d[a] = zeros[rng.below(2)];
            }
        }
        let t_max = if i % 7 == 0 {
            (b.max - b.min).length() * rng.unit()
        } else {
            f32::INFINITY
        };
        rays.push(Ray::new(o, d, 0.0, t_max));
    }
    rays
}

/// Every ray: the skipping grid's closest and any hit equal the uniform grid's bit for bit,
/// with the same triangle tests and mailbox skips, and never more cells. Returns the counters
/// of both (closest hit) over the rays.
fn same_as_grid(
    name: &str,
    mesh: &Arc<TriangleMesh>,
    params: &SkipGridParams,
    rays: &[Ray],
) -> (Counters, Counters) {
    let skip = SkipGrid::build(mesh.clone(), params).unwrap();
    assert_eq!(skip.validate(mesh), Ok(()), "{name}");
    let grid = Grid::build(mesh.clone(), &params.grid).unwrap();
    let bits = |h: Option<raybench_accel::Hit>| {
        h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()))
    };
    let (mut total_g, mut total_s) = (Counters::default(), Counters::default());
    for (i, r) in rays.iter().enumerate() {
        let fail = |what: &str| format!("{name}: ray {i} {:08x?}: {what}", r.to_bits());
        for any in [false, true] {
            let (mut cg, mut cs) = (Counters::default(), Counters::default());
            let (hg, hs) = if any {
                (
                    grid.occluded_counted(r, &mut cg).then_some(()),
                    skip.occluded_counted(r, &mut cs).then_some(()),
                )
            } else {
                let (g, s) = (
                    grid.intersect_counted(r, &mut cg),
                    skip.intersect_counted(r, &mut cs),
                );
                assert_eq!(
                    bits(g),
                    bits(s),
                    "{}",
                    fail("closest hit differs from grid's")
                );
                assert_eq!(
                    bits(s),
                    bits(skip.intersect(r)),
                    "{}",
                    fail("timed path differs")
                );
                (g.map(|_| ()), s.map(|_| ()))
            };
            assert_eq!(hg, hs, "{}", fail("any hit differs from grid's"));
            assert_eq!(
                (cg.prim_tests, cg.mailbox_skips),
                (cs.prim_tests, cs.mailbox_skips),
                "{}",
                fail(&format!("different tests: grid {cg:?}, grid-skip {cs:?}"))
            );
            assert!(
                cs.cells <= cg.cells,
                "{}",
                fail(&format!("more cells: {cg:?} {cs:?}"))
            );
            assert!(cs.jumps <= cs.cells, "{}", fail(&format!("{cs:?}")));
            assert_eq!(cg.jumps, 0);
            if !any {
                total_g += cg;
                total_s += cs;
            }
        }
    }
    (total_g, total_s)
}

/// The default, and a fine grid jumping from every cell that allows it (many short jumps).
fn variants() -> [SkipGridParams; 2] {
    [
        SkipGridParams::default(),
        SkipGridParams {
            grid: GridParams::fine(),
            min_jump: 2,
        },
    ]
}

#[test]
fn the_same_answers_and_tests_as_the_uniform_grid_on_the_suite_cases() {
    for case in seeded_cases().into_iter().chain(edge_cases()) {
        for params in variants() {
            same_as_grid(&case.name, &case.mesh, &params, &case.rays);
        }
    }
}

/// Scenes that are mostly empty space: a small cluster against a huge box (the teapot in a
/// stadium at several size ratios, and two clusters at opposite corners of a box), where the
/// walk must jump, and must still agree with the uniform grid bit for bit.
#[test]
fn empty_space_is_jumped_without_changing_an_answer() {
    let mut scenes: Vec<(String, Arc<TriangleMesh>)> = ["0.01", "0.0001", "0.00001"]
        .iter()
        .map(|r| {
            let spec = format!(
                "teapot-in-stadium:stadium_triangles=8000,teapot_triangles=2000,size_ratio={r}"
            );
            let mesh = generated(&spec, SEED);
            (spec, mesh)
        })
        .collect();
    // Two clusters of 400 triangles at opposite corners of a box 40 times their size.
    let near = generated("soup:triangles=400", SEED);
    let far = generated("soup:triangles=400", SEED ^ 1);
    let mut positions = Vec::new();
    for (mesh, shift) in [(&near, Vec3::ZERO), (&far, Vec3::splat(40.0))] {
        for i in 0..mesh.len() {
            let t = mesh.triangle(i);
            positions.extend([t.v0 + shift, t.v1 + shift, t.v2 + shift]);
        }
    }
    let indices = (0..positions.len() as u32 / 3)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let corners = raybench_testkit::mesh(positions, indices);
    scenes.push(("two corners".into(), corners));
    for (name, mesh) in &scenes {
        for params in variants() {
            let grid = params.grid.clone();
            let mut rays = skip_rays(mesh, &grid, 3000, SEED);
            if let Ok(scene) = raybench_testkit::scenes::generate(name, SEED) {
                let [a, b] = camera_ray_sets(&scene, 1000);
                rays.extend(a);
                rays.extend(b);
            }
            let (g, s) = same_as_grid(name, mesh, &params, &rays);
            let n = rays.len() as f64;
            eprintln!(
                "{name} λ {} min_jump {}: cells per ray grid {:.1}, grid-skip {:.1}, jumps {:.2}",
                grid.density,
                params.min_jump,
                g.cells as f64 / n,
                s.cells as f64 / n,
                s.jumps as f64 / n
            );
            assert!(s.jumps > 0, "{name}: no jump");
            // Two clusters 40 sizes apart: most of a ray's walk is empty space.
            let most = if name == "two corners" { 0.6 } else { 1.0 };
            assert!(
                (s.cells as f64) < most * g.cells as f64,
                "{name}: cells {} against the grid's {}",
                s.cells,
                g.cells
            );
            // Also held against brute force by the shared checks.
            let case = Case {
                name: name.clone(),
                seed: SEED,
                mesh: mesh.clone(),
                rays: rays.clone(),
            };
            let counts = check_case::<SkipGrid>(&case, &params, &|g, m| g.validate(m))
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(counts.mismatch, 0);
        }
    }
}

/// Cells of side 1 over [0, 64]³ (integer planes, exact in f32) holding small triangles far
/// apart, and rays from lattice points along directions of components −1, 0 and 1 (and ±0):
/// their crossings tie exactly on two or three axes at every cell corner they pass, where
/// stepping takes the tied axes in a fixed order, so the corner cells a ray only touches are
/// visited or not by that order. A jump must land on a state stepping reaches (every crossing
/// strictly before the block's exit, none at it), or it skips or adds such cells and the
/// triangle tests differ from the uniform grid's.
#[test]
fn jumps_keep_the_step_order_at_exact_corners() {
    let mut rng = XorShift(SEED);
    let mut positions = vec![
        Vec3::ZERO,
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.0, 0.5, 0.0),
    ];
    let far = Vec3::splat(64.0);
    positions.extend([
        far,
        far - Vec3::new(0.5, 0.0, 0.0),
        far - Vec3::new(0.0, 0.5, 0.0),
    ]);
    for _ in 0..400 {
        // A small triangle around a lattice point, so corner cells are the ones it touches.
        let c = Vec3::from_array(std::array::from_fn(|_| 1.0 + rng.below(63) as f32));
        let e = |rng: &mut XorShift| Vec3::from_array(std::array::from_fn(|_| rng.unit() - 0.5));
        positions.extend([
            c + e(&mut rng) * 0.6,
            c + e(&mut rng) * 0.6,
            c + e(&mut rng) * 0.6,
        ]);
    }
    let indices = (0..positions.len() as u32 / 3)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = raybench_testkit::mesh(positions, indices);
    let params = SkipGridParams {
        grid: GridParams::with_density(64.0 * 64.0 * 64.0 / mesh.len() as f64),
        min_jump: 2,
    };
    let skip = SkipGrid::build(mesh.clone(), &params).unwrap();
    assert_eq!(
        skip.grid().resolution(),
        [64, 64, 64],
        "the test needs unit cells"
    );
    let units = [-1.0f32, 0.0, -0.0, 1.0];
    let mut rays = Vec::new();
    for _ in 0..600 {
        let o = Vec3::from_array(std::array::from_fn(|_| rng.below(65) as f32));
        for _ in 0..8 {
            let d = Vec3::from_array(std::array::from_fn(|_| units[rng.below(4)]));
            if d.abs().max_element() > 0.0 {
                rays.push(Ray::infinite(o, d));
            }
        }
    }
    let (g, s) = same_as_grid("lattice corners", &mesh, &params, &rays);
    assert!(s.jumps > 0 && s.prim_tests > 0, "{s:?}");
    eprintln!("lattice corners: grid {g:?}, grid-skip {s:?}");
}

#[test]
fn walks_are_bounded() {
    let mesh = generated(
        "teapot-in-stadium:stadium_triangles=4000,teapot_triangles=500",
        SEED,
    );
    let skip = SkipGrid::build(mesh.clone(), &with_grid(GridParams::fine())).unwrap();
    let [nx, ny, nz] = skip.grid().resolution();
    let bound = (nx + ny + nz) as u64;
    let mut rays: Vec<Ray> = refused_rays().to_vec();
    rays.extend(skip_rays(&mesh, &GridParams::fine(), 500, SEED ^ 7));
    // Direction components whose reciprocals are infinite (no jumps) or huge.
    let c = mesh.bounds().center();
    for tiny in [1e-39f32, -1e-39, 1e-30, f32::MIN_POSITIVE] {
        rays.push(Ray::infinite(c, Vec3::new(1.0, tiny, tiny)));
        rays.push(Ray::infinite(c, Vec3::new(tiny, -1.0, tiny)));
    }
    // A NaN or infinite origin component with a direction moving along every axis: its
    // crossings are NaN, which stepping takes as "now" and a jump must not rely on.
    for a in 0..3 {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for d in [
                Vec3::new(1.0, 0.3, -0.2),
                Vec3::new(-0.1, -1.0, 0.7),
                Vec3::splat(-1.0),
            ] {
                let mut o = c;
                o[a] = bad;
                rays.push(Ray::infinite(o, d));
            }
        }
    }
    for r in rays {
        let mut c = Counters::default();
        let _ = skip.intersect_counted(&r, &mut c);
        assert!(c.cells <= bound, "{r:?}: {c:?}");
    }
    for r in refused_rays() {
        assert_eq!(skip.intersect(&r), None, "{r:?}");
    }
}

#[test]
fn the_field_is_sound_after_every_build() {
    for (spec, grid) in [
        ("soup:triangles=3000", GridParams::default()),
        ("sphere:triangles=5000", GridParams::fine()),
        ("plane:quads=32", GridParams::fine()),
        ("grass:density=4", GridParams::default()),
        (
            "teapot-in-stadium:stadium_triangles=4000,teapot_triangles=500",
            GridParams::fine(),
        ),
    ] {
        let mesh = generated(spec, SEED);
        let skip = SkipGrid::build(mesh.clone(), &with_grid(grid)).unwrap();
        assert_eq!(skip.validate(&mesh), Ok(()), "{spec}");
        let extra = &skip.build_stats().extra;
        assert!(extra["skip_max_distance"] >= 1.0, "{spec}: {extra:?}");
    }
}

#[test]
fn bad_knobs_and_memory_are_errors_not_aborts() {
    let mesh = generated("soup:triangles=2000", 1);
    expect_too_large::<SkipGrid>(
        &mesh,
        &with_grid(GridParams {
            memory_limit_bytes: 64 * 1024,
            ..GridParams::default()
        }),
    );
    let bad = SkipGridParams {
        min_jump: 1,
        ..SkipGridParams::default()
    };
    assert!(SkipGrid::build(mesh.clone(), &bad).is_err());
    assert_eq!(SkipGridParams::default().name(), "grid-skip");
}

#[test]
fn point_queries_conform() {
    let counts = point_conformance::<SkipGrid>(&SkipGridParams::default(), &|g, m| g.validate(m));
    assert_eq!(counts.mismatch, 0);
}
