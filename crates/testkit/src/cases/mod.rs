//! The named cases of the ray conformance suite: seeded scenes, then the edge cases of the
//! adversarial checklist (docs/validation.md, Adversarial checklist): the basic ones here, the
//! rays along edges and planes, empty intervals, invalid rays and extreme coordinates in
//! [`adversarial`].

mod adversarial;

use crate::rays::{centred_direction, centroid_rays, random_rays_in, seeded_rng, unit_f32};
use crate::{generated, mesh};
use raybench_geom::{Ray, Triangle, TriangleMesh, Vec3};
use std::sync::Arc;

/// A mesh and the rays to check on it.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub seed: u64,
    pub mesh: Arc<TriangleMesh>,
    pub rays: Vec<Ray>,
}

impl Case {
    fn new(name: &str, seed: u64, mesh: Arc<TriangleMesh>, rays: Vec<Ray>) -> Case {
        Case {
            name: name.to_string(),
            seed,
            mesh,
            rays,
        }
    }
}

/// Named seeds: a failing case names its seed, and the same seed replays it exactly.
pub const SEED_SOUP: u64 = 0x5eed_0001;
pub const SEED_SPHERE: u64 = 0x5eed_0002;
pub const SEED_PLANE: u64 = 0x5eed_0003;
pub const SEED_EDGE: u64 = 0x5eed_0004;

fn mixed_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let b = mesh.bounds().enlarged(0.1);
    let mut rays = random_rays_in(&b, n, seed);
    rays.extend(centroid_rays(mesh, n / 2, seed ^ 1));
    rays
}

/// Seeded procedural scenes with random rays and rays aimed at triangles.
pub fn seeded_cases() -> Vec<Case> {
    let soup = generated("soup:triangles=3000", SEED_SOUP);
    let sphere = generated("sphere:triangles=2000", SEED_SPHERE);
    let plane = generated("plane:quads=16", SEED_PLANE);
    let inside_sphere = random_rays_in(
        &raybench_geom::Aabb::new(Vec3::splat(-0.3), Vec3::splat(0.3)),
        1000,
        SEED_SPHERE,
    );
    vec![
        Case::new(
            "soup",
            SEED_SOUP,
            soup.clone(),
            mixed_rays(&soup, 3000, SEED_SOUP),
        ),
        Case::new(
            "sphere",
            SEED_SPHERE,
            sphere.clone(),
            mixed_rays(&sphere, 2000, SEED_SPHERE),
        ),
        Case::new("sphere-from-inside", SEED_SPHERE, sphere, inside_sphere),
        Case::new(
            "plane",
            SEED_PLANE,
            plane.clone(),
            mixed_rays(&plane, 2000, SEED_PLANE),
        ),
        Case::new(
            "plane-grid-lines",
            SEED_PLANE,
            plane.clone(),
            grid_line_rays(&plane),
        ),
    ]
}

/// Rays straight down through every vertex and edge midpoint of a plane's grid: shared edges
/// and shared vertices, where ties must be classified and nothing may fall through.
fn grid_line_rays(plane: &TriangleMesh) -> Vec<Ray> {
    let b = plane.bounds();
    let (lo, hi) = (b.min.y - 1.0, b.max.y + 1.0);
    let mut rays = Vec::new();
    for t in plane.triangles().take(400) {
        for p in [t.v0, (t.v0 + t.v1) * 0.5, (t.v1 + t.v2) * 0.5] {
            rays.push(Ray::infinite(
                Vec3::new(p.x, hi, p.z),
                Vec3::new(0.0, lo - hi, 0.0),
            ));
            rays.push(Ray::infinite(
                Vec3::new(p.x, p.y + 1.0, p.z),
                Vec3::new(-0.0, -1.0, 0.0),
            ));
        }
    }
    rays
}

fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
    Triangle::new(a.into(), b.into(), c.into())
}

pub(crate) fn from_tris(tris: &[Triangle]) -> Arc<TriangleMesh> {
    Arc::new(
        TriangleMesh::from_triangles(tris)
            .expect("small test mesh")
            .0,
    )
}

pub(crate) fn soup_tris(n: usize, seed: u64, offset: Vec3) -> Vec<Triangle> {
    let mut rng = seeded_rng(seed);
    let mut f = move || unit_f32(&mut rng);
    (0..n)
        .map(|_| {
            let c = Vec3::new(f(), f(), f()) + offset;
            let mut v = || c + (Vec3::new(f(), f(), f()) - 0.5) * 0.2;
            Triangle::new(v(), v(), v())
        })
        .collect()
}

/// Axis-parallel rays with every combination of signed-zero components, through the box.
fn axis_rays(mesh: &TriangleMesh, per_axis: usize, seed: u64) -> Vec<Ray> {
    let b = mesh.bounds().enlarged(0.05);
    let mut rng = seeded_rng(seed);
    let mut f = move || unit_f32(&mut rng);
    let mut rays = Vec::new();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            for zeros in [0.0f32, -0.0] {
                for _ in 0..per_axis {
                    let mut o = b.min + Vec3::new(f(), f(), f()) * b.extent();
                    o[axis] = if sign > 0.0 { b.min[axis] } else { b.max[axis] };
                    let mut d = Vec3::splat(zeros);
                    d[axis] = sign;
                    rays.push(Ray::infinite(o, d));
                }
            }
        }
    }
    rays
}

/// The edge cases every structure must survive and answer exactly like brute force.
pub fn edge_cases() -> Vec<Case> {
    let s = SEED_EDGE;
    let mut cases = Vec::new();

    let empty = mesh(vec![], vec![]);
    cases.push(Case::new(
        "empty-mesh",
        s,
        empty,
        random_rays_in(&raybench_geom::Aabb::new(Vec3::ZERO, Vec3::ONE), 100, s),
    ));

    let one = from_tris(&[tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])]);
    let mut one_rays = mixed_rays(&one, 300, s);
    for (x, y) in [
        (0.25, 0.25),
        (0.0, 0.5),
        (0.5, 0.0),
        (0.5, 0.5),
        (0.0, 0.0),
        (1.0, 0.0),
        (2.0, 2.0),
    ] {
        one_rays.push(Ray::infinite(
            Vec3::new(x, y, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
        ));
        one_rays.push(Ray::infinite(
            Vec3::new(x, y, -1.0),
            Vec3::new(-0.0, 0.0, 1.0),
        ));
    }
    // Hit exactly at t_max (a hit) and exactly at t_min (not a hit).
    one_rays.push(Ray::new(
        Vec3::new(0.25, 0.25, 1.0),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        1.0,
    ));
    one_rays.push(Ray::new(
        Vec3::new(0.25, 0.25, 1.0),
        Vec3::new(0.0, 0.0, -1.0),
        1.0,
        2.0,
    ));
    cases.push(Case::new("one-triangle", s, one, one_rays));

    for n in 2..=5 {
        let fan: Vec<Triangle> = (0..n)
            .map(|i| {
                let a = i as f32 * 0.7;
                tri(
                    [0.0, 0.0, 0.0],
                    [a.cos(), a.sin(), 0.1 * i as f32],
                    [(a + 0.6).cos(), (a + 0.6).sin(), 0.0],
                )
            })
            .collect();
        let m = from_tris(&fan);
        let rays = mixed_rays(&m, 300, s + n as u64);
        cases.push(Case::new(&format!("fan-{n}"), s, m, rays));
    }

    // Every triangle with the same centroid (concentric, rotated): degenerate SAH input
    // (docs/validation.md, B5).
    let m = from_tris(&concentric_triangles());
    cases.push(Case::new(
        "one-centroid",
        s,
        m.clone(),
        mixed_rays(&m, 1000, s),
    ));

    // Many identical triangles: ties on every hit (docs/validation.md, G7).
    let same = vec![tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]); 300];
    let m = from_tris(&same);
    cases.push(Case::new(
        "identical-triangles",
        s,
        m.clone(),
        mixed_rays(&m, 500, s),
    ));

    // A flat scene: zero extent on z (docs/validation.md, G9), with axis-parallel rays and
    // rays in the plane.
    let flat: Vec<Triangle> = soup_tris(500, s, Vec3::ZERO)
        .into_iter()
        .map(|t| {
            Triangle::new(
                t.v0 * Vec3::new(1.0, 1.0, 0.0),
                t.v1 * Vec3::new(1.0, 1.0, 0.0),
                t.v2 * Vec3::new(1.0, 1.0, 0.0),
            )
        })
        .collect();
    let m = from_tris(&flat);
    let mut rays = axis_rays(&m, 100, s);
    rays.extend(mixed_rays(&m, 500, s));
    cases.push(Case::new("flat-scene", s, m, rays));

    // Axis-parallel rays with ±0 components through a soup (docs/validation.md, B1 and B3).
    let m = from_tris(&soup_tris(1000, s, Vec3::ZERO));
    cases.push(Case::new(
        "axis-parallel-rays",
        s,
        m.clone(),
        axis_rays(&m, 200, s),
    ));

    // Rays starting on a surface (t_min = 0): the hit at t = 0 is excluded (t_min < t).
    let starts: Vec<Ray> = {
        let mut rng = seeded_rng(s);
        m.triangles()
            .take(500)
            .map(|t| {
                let d = centred_direction(&mut rng);
                Ray::infinite(t.centroid(), if d == Vec3::ZERO { Vec3::X } else { d })
            })
            .collect()
    };
    cases.push(Case::new("rays-from-surfaces", s, m, starts));

    // Far from the origin (1e5): precision regime of Embree's watertight tests
    // (docs/validation.md, R15).
    let far = from_tris(&soup_tris(1000, s, Vec3::splat(1e5)));
    cases.push(Case::new(
        "offset-1e5",
        s,
        far.clone(),
        mixed_rays(&far, 1000, s),
    ));

    // Zero-area triangles mixed in: never hit (docs/validation.md, G3).
    let mut with_degenerate = soup_tris(500, s, Vec3::ZERO);
    for t in with_degenerate.clone().iter().take(200) {
        with_degenerate.push(Triangle::new(t.v0, t.v1, t.v0 * 0.5 + t.v1 * 0.5));
        with_degenerate.push(Triangle::new(t.v2, t.v2, t.v2));
    }
    let m = from_tris(&with_degenerate);
    cases.push(Case::new(
        "zero-area-mixed",
        s,
        m.clone(),
        mixed_rays(&m, 1000, s),
    ));

    cases.extend(adversarial::adversarial_cases(s));
    cases
}

/// 300 triangles of growing size, rotated, every one centred exactly on the origin: the
/// one-centroid input (docs/validation.md, B5) of the ray and the point conformance suites.
pub(crate) fn concentric_triangles() -> Vec<Triangle> {
    (0..300)
        .map(|i| {
            let r = 0.01 + i as f32 * 0.01;
            let a = i as f32 * 0.37;
            let p = |k: f32| {
                Vec3::new(
                    (a + k).cos() * r,
                    (a + k).sin() * r,
                    ((a + k) * 3.0).sin() * r * 0.3,
                )
            };
            let (p0, p1, p2) = (p(0.0), p(2.1), p(4.2));
            let c = (p0 + p1 + p2) / 3.0;
            Triangle::new(p0 - c, p1 - c, p2 - c)
        })
        .collect()
}
