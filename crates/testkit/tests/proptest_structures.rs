//! Property: on random small meshes and adversarial rays, every structure answers like brute
//! force, and its `validate()` passes after every build.
//!
//! Meshes have 1–40 triangles with coordinates drawn from small integers (exact arithmetic,
//! many coincident vertices, shared edges and coplanar faces), dyadic fractions and arbitrary
//! floats, optionally shifted far from the origin; some triangles are points, collinear,
//! repeat a vertex or copy an earlier triangle. Rays start anywhere in the box, on vertices,
//! edge midpoints and centroids; they run axis-parallel with ±0 components, at vertices and
//! centroids (hits exactly at t = 1), along edges and in a triangle's plane, over intervals
//! such as t_max = 0, t_min = t_max and t_min = -0.
//!
//! Each case goes through `raybench_testkit::check_case` for every structure: the closest and
//! any hit classified against `BruteForce` with the default tolerance (every verdict but
//! `Mismatch` passes), the counted walk equal to the timed one, the batch path equal to the
//! single-ray path.
//!
//! 256 cases by default; `PROPTEST_CASES=20000` for a long run. A failure is shrunk, printed
//! with the mesh and ray bits, and its seed kept in `proptest-regressions/` (commit it: every
//! later run replays it first).

use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use raybench_accel::classify::VerdictCounts;
use raybench_bvh::{Bvh, Bvh4, Bvh8, BvhParams, WideParams};
use raybench_geom::{Aabb, Ray, Triangle, TriangleMesh, Vec3};
use raybench_grid::{Grid, Grid2, Grid2Params, GridParams, SkipGrid, SkipGridParams};
use raybench_kdtree::{KdParams, KdTree};
use raybench_octree::{Octree, OctreeParams};
use raybench_testkit::{Case, check_case};
use std::sync::Arc;

/// How a triangle of the mesh is made from its three drawn points.
#[derive(Clone, Debug)]
enum Shape {
    Triangle,
    /// All three corners at the first point.
    Point,
    /// The third corner on the line through the first two (collinear in exact arithmetic; in
    /// f32 often a sliver).
    Collinear,
    /// The second corner repeated.
    RepeatedVertex,
    /// An exact copy of an earlier triangle (index modulo the triangles so far).
    CopyOfEarlier(usize),
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        8 => Just(Shape::Triangle),
        1 => Just(Shape::Point),
        1 => Just(Shape::Collinear),
        1 => Just(Shape::RepeatedVertex),
        2 => any::<usize>().prop_map(Shape::CopyOfEarlier),
    ]
}

/// Small integers give exact arithmetic and coincidences; dyadic fractions stay exact too;
/// arbitrary floats exercise rounding.
fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        (-4i32..=4).prop_map(|i| i as f32),
        (-64i32..=64).prop_map(|k| k as f32 / 16.0),
        -8.0f32..8.0,
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Where the whole mesh sits: mostly at the origin, sometimes where f32 spacing is coarse.
fn offset() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        6 => Just(Vec3::ZERO),
        1 => Just(Vec3::splat(1024.0)),
        1 => Just(Vec3::new(1e5, -1e5, 3e4)),
        1 => Just(Vec3::splat(-1e6)),
    ]
}

#[derive(Clone, Debug)]
struct MeshSpec {
    triangles: Vec<(Shape, Vec3, Vec3, Vec3)>,
    offset: Vec3,
}

fn mesh_spec() -> impl Strategy<Value = MeshSpec> {
    (
        prop::collection::vec((shape(), point(), point(), point()), 1..=40),
        offset(),
    )
        .prop_map(|(triangles, offset)| MeshSpec { triangles, offset })
}

impl MeshSpec {
    fn triangles(&self) -> Vec<Triangle> {
        let mut out: Vec<Triangle> = Vec::with_capacity(self.triangles.len());
        for (shape, a, b, c) in &self.triangles {
            let (a, b, c) = (*a + self.offset, *b + self.offset, *c + self.offset);
            let t = match shape {
                Shape::Triangle => Triangle::new(a, b, c),
                Shape::Point => Triangle::new(a, a, a),
                Shape::Collinear => Triangle::new(a, b, a + (b - a) * 2.0),
                Shape::RepeatedVertex => Triangle::new(a, b, b),
                Shape::CopyOfEarlier(i) if !out.is_empty() => out[i % out.len()],
                Shape::CopyOfEarlier(_) => Triangle::new(a, b, c),
            };
            out.push(t);
        }
        out
    }

    fn mesh(&self) -> Arc<TriangleMesh> {
        let (mesh, removed) =
            TriangleMesh::from_triangles(&self.triangles()).expect("40 triangles fit");
        // Every coordinate is finite and far below 1.844e18: nothing may be removed.
        assert_eq!(removed.total(), 0, "{removed:?}");
        Arc::new(mesh)
    }
}

/// Where a ray starts. Indices pick a triangle (modulo the mesh) and a corner or edge.
#[derive(Clone, Debug)]
enum Origin {
    /// A point of the mesh's box enlarged by half its size, as fractions per axis.
    InBox(f32, f32, f32),
    Vertex(usize, usize),
    EdgeMidpoint(usize, usize),
    Centroid(usize),
}

/// Where a ray goes.
#[derive(Clone, Debug)]
enum Direction {
    Any(Vec3),
    /// Along `axis` with `sign`; the other two components are +0 or -0.
    AxisParallel {
        axis: usize,
        negative: bool,
        zero_signs: (bool, bool),
    },
    /// From the origin to a vertex (a hit exactly at t = 1 unless something is closer).
    ToVertex(usize, usize),
    ToCentroid(usize),
    /// Parallel to an edge of a triangle.
    AlongEdge(usize, usize),
    /// In the plane of a triangle: a combination of two of its edges.
    InPlane(usize, f32, f32),
}

/// The hit interval `(t_min, t_max]`.
#[derive(Clone, Debug)]
enum Interval {
    Infinite,
    /// t_min = t_max = 0: empty.
    Zero,
    /// t_min = -0: accepted by Embree, the same as 0.
    MinusZero,
    /// t_min = t_max = t: empty; at t = 1 exactly where aimed rays hit.
    Equal(f32),
    /// (0, t]: at t = 1 an aimed ray's hit lies exactly on t_max.
    UpTo(f32),
    /// (t, inf): at t = 1 an aimed ray's hit lies exactly on t_min.
    From(f32),
}

fn origin() -> impl Strategy<Value = Origin> {
    prop_oneof![
        3 => (0.0f32..=1.0, 0.0f32..=1.0, 0.0f32..=1.0).prop_map(|(x, y, z)| Origin::InBox(x, y, z)),
        1 => (any::<usize>(), 0usize..3).prop_map(|(t, k)| Origin::Vertex(t, k)),
        1 => (any::<usize>(), 0usize..3).prop_map(|(t, k)| Origin::EdgeMidpoint(t, k)),
        1 => any::<usize>().prop_map(Origin::Centroid),
    ]
}

fn direction() -> impl Strategy<Value = Direction> {
    prop_oneof![
        2 => point().prop_map(Direction::Any),
        2 => (0usize..3, any::<bool>(), any::<(bool, bool)>()).prop_map(
            |(axis, negative, zero_signs)| Direction::AxisParallel { axis, negative, zero_signs }
        ),
        2 => (any::<usize>(), 0usize..3).prop_map(|(t, k)| Direction::ToVertex(t, k)),
        2 => any::<usize>().prop_map(Direction::ToCentroid),
        1 => (any::<usize>(), 0usize..3).prop_map(|(t, k)| Direction::AlongEdge(t, k)),
        1 => (any::<usize>(), -2.0f32..2.0, -2.0f32..2.0)
            .prop_map(|(t, a, b)| Direction::InPlane(t, a, b)),
    ]
}

fn interval() -> impl Strategy<Value = Interval> {
    let t = prop_oneof![Just(1.0f32), Just(0.5), 0.0f32..4.0];
    prop_oneof![
        6 => Just(Interval::Infinite),
        1 => Just(Interval::Zero),
        1 => Just(Interval::MinusZero),
        1 => t.clone().prop_map(Interval::Equal),
        1 => t.clone().prop_map(Interval::UpTo),
        1 => t.prop_map(Interval::From),
    ]
}

#[derive(Clone, Debug)]
struct RaySpec {
    origin: Origin,
    direction: Direction,
    interval: Interval,
}

fn ray_spec() -> impl Strategy<Value = RaySpec> {
    (origin(), direction(), interval()).prop_map(|(origin, direction, interval)| RaySpec {
        origin,
        direction,
        interval,
    })
}

fn corner(t: &Triangle, k: usize) -> Vec3 {
    [t.v0, t.v1, t.v2][k % 3]
}

impl RaySpec {
    /// The ray over the mesh with triangles `tris` and bounding box `bounds`.
    fn ray(&self, tris: &[Triangle], bounds: &Aabb) -> Ray {
        let pick = |i: usize| tris[i % tris.len()];
        let origin = match self.origin {
            Origin::InBox(x, y, z) => {
                let b = bounds;
                let size = b.extent().max(Vec3::splat(1.0));
                b.min - size * 0.5 + Vec3::new(x, y, z) * size * 2.0
            }
            Origin::Vertex(t, k) => corner(&pick(t), k),
            Origin::EdgeMidpoint(t, k) => {
                let tri = pick(t);
                (corner(&tri, k) + corner(&tri, k + 1)) * 0.5
            }
            Origin::Centroid(t) => pick(t).centroid(),
        };
        let dir = match self.direction {
            Direction::Any(d) => d,
            Direction::AxisParallel {
                axis,
                negative,
                zero_signs: (s1, s2),
            } => {
                let zero = |minus: bool| if minus { -0.0 } else { 0.0 };
                let mut d = Vec3::new(zero(s1), zero(s2), zero(s1 ^ s2));
                d[axis] = if negative { -1.0 } else { 1.0 };
                d
            }
            Direction::ToVertex(t, k) => corner(&pick(t), k) - origin,
            Direction::ToCentroid(t) => pick(t).centroid() - origin,
            Direction::AlongEdge(t, k) => {
                let tri = pick(t);
                corner(&tri, k + 1) - corner(&tri, k)
            }
            Direction::InPlane(t, a, b) => {
                let tri = pick(t);
                (tri.v1 - tri.v0) * a + (tri.v2 - tri.v0) * b
            }
        };
        let (t_min, t_max) = match self.interval {
            Interval::Infinite => (0.0, f32::INFINITY),
            Interval::Zero => (0.0, 0.0),
            Interval::MinusZero => (-0.0, f32::INFINITY),
            Interval::Equal(t) => (t, t),
            Interval::UpTo(t) => (0.0, t),
            Interval::From(t) => (t, f32::INFINITY),
        };
        Ray::new(origin, dir, t_min, t_max)
    }
}

type Check = fn(&Case) -> Result<VerdictCounts, String>;

/// Every structure with the parameters the registry builds it with
/// (crates/harness/src/registry.rs), `validate()` after the build.
const STRUCTURES: [(&str, Check); 16] = [
    ("bvh-median", |c| {
        check_case::<Bvh>(c, &BvhParams::median(), &|a, m| a.validate(m))
    }),
    ("bvh-sweep", |c| {
        check_case::<Bvh>(c, &BvhParams::sweep(), &|a, m| a.validate(m))
    }),
    ("bvh-binned", |c| {
        check_case::<Bvh>(c, &BvhParams::binned(), &|a, m| a.validate(m))
    }),
    ("bvh-binned-unordered", |c| {
        check_case::<Bvh>(c, &BvhParams::binned_unordered(), &|a, m| a.validate(m))
    }),
    ("bvh4-binned", |c| {
        check_case::<Bvh4>(c, &WideParams::for_width(4), &|a, m| a.validate(m))
    }),
    ("bvh8-binned", |c| {
        check_case::<Bvh8>(c, &WideParams::default(), &|a, m| a.validate(m))
    }),
    ("kd-sah", |c| {
        check_case::<KdTree>(c, &KdParams::sah(), &|a, m| a.validate(m))
    }),
    ("kd-median", |c| {
        check_case::<KdTree>(c, &KdParams::median(), &|a, m| a.validate(m))
    }),
    ("grid-coarse", |c| {
        check_case::<Grid>(c, &GridParams::coarse(), &|a, m| a.validate(m))
    }),
    ("grid", |c| {
        check_case::<Grid>(c, &GridParams::default(), &|a, m| a.validate(m))
    }),
    ("grid-fine", |c| {
        check_case::<Grid>(c, &GridParams::fine(), &|a, m| a.validate(m))
    }),
    ("grid-skip", |c| {
        check_case::<SkipGrid>(c, &SkipGridParams::default(), &|a, m| a.validate(m))
    }),
    // Jumps from every cell that allows one, over a grid of mostly empty cells.
    ("grid-skip-fine", |c| {
        let params = SkipGridParams {
            grid: GridParams::fine(),
            min_jump: 2,
        };
        check_case::<SkipGrid>(c, &params, &|a, m| a.validate(m))
    }),
    ("grid2", |c| {
        check_case::<Grid2>(c, &Grid2Params::default(), &|a, m| a.validate(m))
    }),
    // Grids in nearly every cell, many levels deep, even for a few triangles.
    ("grid2-deep", |c| {
        check_case::<Grid2>(c, &Grid2Params::deep(), &|a, m| a.validate(m))
    }),
    ("octree", |c| {
        check_case::<Octree>(c, &OctreeParams::default(), &|a, m| a.validate(m))
    }),
];

/// Runs every structure on the case; `Err` names the structure and the failing ray.
fn check_every_structure(case: &Case) -> Result<(), String> {
    for (name, check) in STRUCTURES {
        check(case).map_err(|e| format!("{name}: {e}"))?;
    }
    Ok(())
}

fn config() -> ProptestConfig {
    ProptestConfig {
        // Next to this crate's Cargo.toml, where a reviewer looks for it (the default would
        // put it beside this file: there is no lib.rs above tests/).
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/proptest-regressions/proptest_structures.txt"
        )))),
        // `cases` stays at proptest's default: 256, or PROPTEST_CASES.
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn every_structure_agrees_with_brute_force(
        mesh in mesh_spec(),
        rays in prop::collection::vec(ray_spec(), 1..48),
    ) {
        let tris = mesh.triangles();
        let built = mesh.mesh();
        let bounds = built.bounds();
        let case = Case {
            name: "proptest".into(),
            seed: 0,
            rays: rays.iter().map(|r| r.ray(&tris, &bounds)).collect(),
            mesh: built,
        };
        if let Err(e) = check_every_structure(&case) {
            return Err(TestCaseError::fail(e));
        }
    }
}

/// The generators must reach the cases they exist for: hits, exact t = 1 hits at vertices and
/// centroids, degenerate triangles and empty intervals. Seeded, so it cannot pass by luck.
#[test]
fn the_generators_reach_hits_and_degenerate_input() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::{Config, TestRng, TestRunner};
    let mut runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::deterministic_rng(Default::default()),
    );
    let (mut hits, mut rays_total, mut degenerate, mut far) = (0, 0, 0, 0);
    for _ in 0..200 {
        let mesh = mesh_spec().new_tree(&mut runner).unwrap().current();
        let rays = prop::collection::vec(ray_spec(), 1..48)
            .new_tree(&mut runner)
            .unwrap()
            .current();
        let tris = mesh.triangles();
        let built = mesh.mesh();
        let bounds = built.bounds();
        degenerate += tris.iter().filter(|t| t.area() == 0.0).count();
        far += usize::from(mesh.offset != Vec3::ZERO);
        let oracle = <raybench_accel::BruteForce as raybench_accel::Accel>::build(
            built,
            &Default::default(),
        )
        .unwrap();
        for r in &rays {
            rays_total += 1;
            let ray = r.ray(&tris, &bounds);
            hits += usize::from(raybench_accel::Accel::intersect(&oracle, &ray).is_some());
        }
    }
    assert!(hits * 5 > rays_total, "{hits} hits in {rays_total} rays");
    assert!(degenerate > 200, "{degenerate} degenerate triangles");
    assert!(far > 20, "{far} meshes far from the origin");
}
