//! The named cases of the conformance suite: seeded scenes, then the edge cases of
//! ARCHITECTURE.md ("Examples to follow", 3) and reliability.md §5.

use crate::mesh;
use crate::rays::{centroid_rays, random_rays_in, seeded_rng};
use rand_core::Rng;
use raybench_geom::{Ray, RayError, Triangle, TriangleMesh, Vec3};
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

fn generated(spec: &str, seed: u64) -> Arc<TriangleMesh> {
    raybench_scenes::generate(spec, seed)
        .unwrap_or_else(|e| panic!("generating {spec}: {e}"))
        .mesh
}

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

fn from_tris(tris: &[Triangle]) -> Arc<TriangleMesh> {
    Arc::new(
        TriangleMesh::from_triangles(tris)
            .expect("small test mesh")
            .0,
    )
}

fn soup_tris(n: usize, seed: u64, offset: Vec3) -> Vec<Triangle> {
    let mut rng = seeded_rng(seed);
    let mut f = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
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
    let mut f = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
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

    // Every triangle with the same centroid (concentric, rotated): degenerate SAH input (B5).
    let m = from_tris(&concentric_triangles());
    cases.push(Case::new(
        "one-centroid",
        s,
        m.clone(),
        mixed_rays(&m, 1000, s),
    ));

    // Many identical triangles: ties on every hit (G7).
    let same = vec![tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]); 300];
    let m = from_tris(&same);
    cases.push(Case::new(
        "identical-triangles",
        s,
        m.clone(),
        mixed_rays(&m, 500, s),
    ));

    // A flat scene: zero extent on z (G9), with axis-parallel rays and rays in the plane.
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

    // Axis-parallel rays with ±0 components through a soup (B1, B3).
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
                let d = Vec3::new(
                    rng.next_u32() as f32,
                    rng.next_u32() as f32,
                    rng.next_u32() as f32,
                ) / u32::MAX as f32
                    - 0.5;
                Ray::infinite(t.centroid(), if d == Vec3::ZERO { Vec3::X } else { d })
            })
            .collect()
    };
    cases.push(Case::new("rays-from-surfaces", s, m, starts));

    // Far from the origin (1e5): precision regime of Embree's watertight tests (R15).
    let far = from_tris(&soup_tris(1000, s, Vec3::splat(1e5)));
    cases.push(Case::new(
        "offset-1e5",
        s,
        far.clone(),
        mixed_rays(&far, 1000, s),
    ));

    // Zero-area triangles mixed in: never hit (G3).
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

    cases.extend(issue_9_cases(s));
    cases
}

/// The adversarial cases of issue 9 not covered above: rays along edges and in triangles'
/// planes, empty and zero-length intervals, NaN and infinite rays, coplanar axis-aligned
/// triangles, and geometry near Embree's 1.844e18 limit.
fn issue_9_cases(s: u64) -> Vec<Case> {
    let soup = from_tris(&soup_tris(500, s, Vec3::ZERO));
    let plane = generated("plane:quads=16", SEED_PLANE);
    let coplanar = generated("coplanar:triangles=2000", s);
    let mut coplanar_rays = axis_rays(&coplanar, 100, s);
    coplanar_rays.extend(grazing_rays_in_planes(&coplanar, 200, s));
    coplanar_rays.extend(edge_and_plane_rays(&coplanar, 200));
    coplanar_rays.extend(mixed_rays(&coplanar, 500, s));
    let far = near_embree_limit(300, s);
    // Unit directions keep Möller–Trumbore's products (edge² × distance) inside f32 there.
    let far_rays = mixed_rays(&far, 600, s)
        .into_iter()
        .map(|r| Ray::infinite(r.origin(), r.dir().normalize()))
        .filter(|r| r.check().is_ok())
        .collect();
    let invalid = non_finite_rays(&soup, s)
        .into_iter()
        .map(|(r, _)| r)
        .collect();
    vec![
        Case::new(
            "edges-and-planes-soup",
            s,
            soup.clone(),
            edge_and_plane_rays(&soup, 500),
        ),
        Case::new(
            "edges-and-planes-grid",
            s,
            plane.clone(),
            edge_and_plane_rays(&plane, 512),
        ),
        Case::new(
            "empty-intervals",
            s,
            soup.clone(),
            empty_interval_rays(&soup, 300, s),
        ),
        Case::new(
            "empty-intervals-exact",
            s,
            unit_triangle(),
            exact_interval_rays(),
        ),
        Case::new("nan-and-inf-rays", s, soup, invalid),
        Case::new("coplanar-axis-aligned", s, coplanar, coplanar_rays),
        Case::new("near-1.8e18", s, far, far_rays),
    ]
}

fn unit_triangle() -> Arc<TriangleMesh> {
    from_tris(&[tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])])
}

/// Rays along triangle edges and in triangles' planes (R9–R11): from a vertex along an edge,
/// from outside along an edge's line, through the interior within the plane, and from the
/// interior within the plane. The triangle itself is never hit (Möller–Trumbore's determinant
/// is 0, and a grazing hit is edge-ambiguous at most); its neighbours may be.
fn edge_and_plane_rays(mesh: &TriangleMesh, n: usize) -> Vec<Ray> {
    let mut rays = Vec::new();
    for t in mesh.triangles().take(n) {
        let (e1, e2) = (t.v1 - t.v0, t.v2 - t.v0);
        let inside = e1 + e2 * 0.5;
        rays.push(Ray::infinite(t.v0, e1));
        rays.push(Ray::infinite(t.v0 - e1, e1));
        rays.push(Ray::infinite(t.v2 + (t.v2 - t.v1), t.v1 - t.v2));
        rays.push(Ray::infinite(t.centroid() - inside, inside));
        rays.push(Ray::infinite(t.centroid(), -inside));
    }
    rays.retain(|r| r.dir() != Vec3::ZERO);
    rays
}

/// For the axis-aligned `coplanar` scene: rays lying exactly in the planes x = 0.5, y = 0.25 and
/// z ∈ {-1, 0, 1}, from outside the scene, in seeded in-plane directions.
fn grazing_rays_in_planes(mesh: &TriangleMesh, per_plane: usize, seed: u64) -> Vec<Ray> {
    let mut rng = seeded_rng(seed ^ 0x9a2e);
    let mut f = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0;
    let b = mesh.bounds();
    let planes = [(0, 0.5f32), (1, 0.25), (2, -1.0), (2, 0.0), (2, 1.0)];
    let mut rays = Vec::new();
    for (axis, level) in planes {
        for _ in 0..per_plane {
            let mut d = Vec3::new(f(), f(), f());
            d[axis] = 0.0;
            let mut o = b.center() - d * b.diagonal();
            o[axis] = level;
            if d != Vec3::ZERO {
                rays.push(Ray::infinite(o, d));
            }
        }
    }
    rays
}

/// Empty and degenerate hit intervals on rays aimed at triangles (hits near t = 1): t_max = 0,
/// t_min = t_max (at the hit, before it, after it), t_min > t_max, the smallest positive t_max,
/// and t_min = -0 (the same as 0 to Embree).
fn empty_interval_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rays = Vec::new();
    for r in centroid_rays(mesh, n, seed) {
        let (o, d) = (r.origin(), r.dir());
        for (t_min, t_max) in [
            (0.0, 0.0),
            (1.0, 1.0),
            (0.5, 0.5),
            (2.0, 2.0),
            (1.0, 0.5),
            (0.0, f32::from_bits(1)),
            (-0.0, 1.0),
            (-0.0, 0.0),
        ] {
            rays.push(Ray::new(o, d, t_min, t_max));
        }
    }
    rays
}

/// The unit triangle in z = 0 hit from z = 1 straight down at exactly t = 1 (and from its own
/// surface): every empty interval misses, `(0, 1]` hits at its end.
fn exact_interval_rays() -> Vec<Ray> {
    let down = Vec3::new(0.0, 0.0, -1.0);
    let above = Vec3::new(0.25, 0.25, 1.0);
    let on = Vec3::new(0.25, 0.25, 0.0);
    let mut rays = Vec::new();
    for (t_min, t_max) in [(0.0, 0.0), (1.0, 1.0), (-0.0, -0.0), (1.0, 0.0), (0.0, 1.0)] {
        rays.push(Ray::new(above, down, t_min, t_max));
        rays.push(Ray::new(above, -down, t_min, t_max));
        rays.push(Ray::new(on, down, t_min, t_max));
        rays.push(Ray::new(on, Vec3::new(1.0, 1.0, 0.0), t_min, t_max));
    }
    rays
}

/// Rays aimed at triangles with one input made NaN or infinite: origin, direction, t_min or
/// t_max. Each comes with the `RayError` [`Ray::check`] must give; every structure must
/// answer with a miss (Embree never sees them). `t_max = +inf` and `t_min = +inf` are valid
/// (the latter an empty interval) and are not here.
pub(crate) fn non_finite_rays(mesh: &TriangleMesh, seed: u64) -> Vec<(Ray, RayError)> {
    const NAMES: [&str; 6] = [
        "origin.x", "origin.y", "origin.z", "dir.x", "dir.y", "dir.z",
    ];
    let mut out = Vec::new();
    for r in centroid_rays(mesh, 50, seed) {
        for (k, name) in NAMES.iter().enumerate() {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let (mut o, mut d) = (r.origin(), r.dir());
                if k < 3 {
                    o[k] = bad
                } else {
                    d[k - 3] = bad
                }
                let error = if bad.is_nan() {
                    RayError::NaN(name)
                } else {
                    RayError::TooLarge(name, bad)
                };
                out.push((Ray::new(o, d, 0.0, f32::INFINITY), error));
            }
        }
        out.push((
            Ray::new(r.origin(), r.dir(), f32::NAN, 1e9),
            RayError::NaN("t_min"),
        ));
        out.push((
            Ray::new(r.origin(), r.dir(), 0.0, f32::NAN),
            RayError::NaN("t_max"),
        ));
    }
    out
}

/// `n` small triangles around (1.5e18, 1.5e18, 1.5e18), below Embree's 1.844e18, plus 20 that
/// the mesh must remove (a vertex at 2e18, or NaN). The f32 spacing there is 2^37 ≈ 1.4e11, so
/// the triangles (corners within 2^40 of a centre) and the scene (2^42 across) are a coarse
/// lattice of a few ulps; larger sizes would overflow f32 in any ray–triangle test.
fn near_embree_limit(n: usize, seed: u64) -> Arc<TriangleMesh> {
    let centre = Vec3::splat(1.5e18);
    let (scene, size) = ((1u64 << 42) as f32, (1u64 << 40) as f32);
    let mut tris: Vec<Triangle> = soup_tris(n, seed, Vec3::ZERO)
        .into_iter()
        .map(|t| {
            let c = t.centroid();
            let at = |v: Vec3| centre + c * scene + (v - c) * (size / 0.1);
            Triangle::new(at(t.v0), at(t.v1), at(t.v2))
        })
        .collect();
    let good = tris[0];
    for i in 0..10 {
        tris.push(Triangle::new(
            good.v0,
            good.v1,
            Vec3::new(2e18, 1.5e18, 1.5e18 + i as f32),
        ));
        tris.push(Triangle::new(good.v0, Vec3::NAN, good.v2));
    }
    let (mesh, removed) = TriangleMesh::from_triangles(&tris).expect("small test mesh");
    assert_eq!(
        (removed.too_large, removed.non_finite, mesh.len()),
        (10, 10, n),
        "the mesh must drop what Embree drops"
    );
    Arc::new(mesh)
}

/// The scene [`crate::lattice_rays`] is made for: bounds exactly [0, 4]³, so grid cells of side
/// 0.5 and octree or k-d split planes at dyadic positions fall on multiples of 0.5; triangles
/// lying exactly on such planes (z = 2, x = 1, y = 3: bug class G11), a seeded soup, and a big
/// slanted triangle whose hits lie beyond the current cell (B11).
pub fn lattice_scene() -> Arc<TriangleMesh> {
    let mut tris = vec![
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
        ),
        Triangle::new(
            Vec3::splat(4.0),
            Vec3::new(3.9, 4.0, 4.0),
            Vec3::new(4.0, 3.9, 4.0),
        ),
        Triangle::new(
            Vec3::new(0.5, 0.5, 2.0),
            Vec3::new(3.5, 0.5, 2.0),
            Vec3::new(0.5, 3.5, 2.0),
        ),
        Triangle::new(
            Vec3::new(1.0, 0.5, 0.5),
            Vec3::new(1.0, 3.0, 0.5),
            Vec3::new(1.0, 0.5, 3.0),
        ),
        Triangle::new(
            Vec3::new(2.5, 3.0, 0.5),
            Vec3::new(3.5, 3.0, 0.5),
            Vec3::new(2.5, 3.0, 3.5),
        ),
        Triangle::new(
            Vec3::new(0.2, 0.3, 3.9),
            Vec3::new(3.9, 0.2, 0.1),
            Vec3::new(2.0, 3.9, 2.0),
        ),
    ];
    let mut rng = seeded_rng(0x5eed_6001);
    let mut f = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
    for _ in 0..400 {
        let c = Vec3::new(f(), f(), f()) * 3.6 + 0.2;
        let mut v = || c + (Vec3::new(f(), f(), f()) - 0.5) * 0.3;
        tris.push(Triangle::new(v(), v(), v()));
    }
    Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0)
}

/// 300 triangles of growing size, rotated, every one centred exactly on the origin: the
/// one-centroid input (bug class B5) of the ray and the point conformance suites.
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

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_accel::Accel;

    /// NaN and infinite rays are refused by `Ray::check` with an error naming the bad input,
    /// which is what keeps them from Embree (Debian's build aborts on them).
    #[test]
    fn nan_and_inf_rays_are_refused_naming_the_input() {
        let soup = from_tris(&soup_tris(50, SEED_EDGE, Vec3::ZERO));
        let rays = non_finite_rays(&soup, SEED_EDGE);
        assert_eq!(rays.len(), 50 * (6 * 3 + 2));
        for (ray, expected) in rays {
            assert_eq!(ray.check(), Err(expected), "{:08x?}", ray.to_bits());
        }
        let message = RayError::TooLarge("dir.y", f32::INFINITY).to_string();
        assert!(message.starts_with("dir.y = inf is infinite"), "{message}");
    }

    /// Every issue-9 case is present, non-trivial, and made of the rays it claims.
    #[test]
    fn the_issue_9_cases_exercise_what_they_name() {
        let cases = issue_9_cases(SEED_EDGE);
        let named = |name: &str| cases.iter().find(|c| c.name == name).unwrap();
        for c in &cases {
            assert!(c.rays.len() >= 20 && !c.mesh.is_empty(), "{}", c.name);
        }
        let empty = named("empty-intervals");
        assert!(empty.rays.iter().any(|r| r.t_max() == 0.0));
        assert!(
            empty
                .rays
                .iter()
                .any(|r| r.t_min() == r.t_max() && r.t_min() > 0.0)
        );
        let far = named("near-1.8e18");
        assert!(far.mesh.bounds().min.min_element() > 1.49e18);
        assert!(far.mesh.bounds().max.max_element() < raybench_geom::EMBREE_LARGE);
        assert!(far.rays.iter().all(|r| r.check().is_ok()));
        // Hits to compare (seed 0x5eed_0004: 253 of 2400 for empty-intervals, the fewest), and
        // none at all for the NaN/inf rays or in the exact case but its one t_max hit.
        for c in &cases {
            let oracle = raybench_accel::BruteForce::build(c.mesh.clone(), &Default::default());
            let oracle = oracle.unwrap();
            let hits = c
                .rays
                .iter()
                .filter(|r| oracle.intersect(r).is_some())
                .count();
            match c.name.as_str() {
                "nan-and-inf-rays" => assert_eq!(hits, 0),
                "empty-intervals-exact" => assert_eq!(hits, 1),
                _ => assert!(hits * 10 > c.rays.len(), "{}: {hits} hits", c.name),
            }
        }
        let grazing = grazing_rays_in_planes(&named("coplanar-axis-aligned").mesh, 10, 1);
        assert!(
            grazing
                .iter()
                .all(|r| [0, 1, 2].iter().any(|&a| r.dir()[a] == 0.0))
        );
    }
}
