//! The adversarial ray cases: rays along edges and in triangles' planes, empty and
//! zero-length intervals, NaN and infinite rays, coplanar axis-aligned triangles, and geometry
//! near Embree's 1.844e18 limit.

use super::{Case, SEED_PLANE, axis_rays, from_tris, mixed_rays, soup_tris, tri};
use crate::generated;
use crate::rays::{centroid_rays, seeded_rng, unit_f32};
use raybench_geom::{Ray, RayError, Triangle, TriangleMesh, Vec3};
use std::sync::Arc;

/// The adversarial cases the basic edge cases leave out: rays along edges and in triangles'
/// planes, empty and zero-length intervals, NaN and infinite rays, coplanar axis-aligned
/// triangles, and geometry near Embree's 1.844e18 limit.
pub(super) fn adversarial_cases(s: u64) -> Vec<Case> {
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

/// Rays along triangle edges and in triangles' planes (docs/validation.md, R9, R10 and R11): from a
/// vertex along an edge, from outside along an edge's line, through the interior within the plane,
/// and from the interior within the plane. The triangle itself is never hit (Möller–Trumbore's
/// determinant is 0, and a grazing hit is edge-ambiguous at most); its neighbours may be.
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
    let mut f = move || unit_f32(&mut rng) * 2.0 - 1.0;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases::SEED_EDGE;
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

    /// Every adversarial case is present, non-trivial, and made of the rays it claims.
    #[test]
    fn the_adversarial_cases_exercise_what_they_name() {
        let cases = adversarial_cases(SEED_EDGE);
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
