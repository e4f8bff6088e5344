//! The named cases of the point conformance suite: seeded scenes with near-surface and
//! volume points, then the edge cases of the adversarial checklist (docs/validation.md,
//! Adversarial checklist).

use super::{PointCase, SEED_POINTS_NEAR, SEED_POINTS_VOLUME};
use super::{points_in_box, points_near_surface, surface_feature_points};
use crate::cases::{
    SEED_EDGE, SEED_PLANE, SEED_SOUP, SEED_SPHERE, concentric_triangles, soup_tris,
};
use crate::{generated, mesh};
use raybench_geom::{Aabb, Triangle, TriangleMesh, Vec3};
use std::sync::Arc;

pub(crate) use crate::cases::from_tris;

/// Points near the surface and points in the box enlarged by 10 %, `n` of each.
fn mixed_points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let b = mesh.bounds();
    let mut points = points_near_surface(mesh, n, 0.01 * b.diagonal(), seed ^ SEED_POINTS_NEAR);
    points.extend(points_in_box(
        &b.enlarged(0.1),
        n,
        seed ^ SEED_POINTS_VOLUME,
    ));
    points
}

pub(crate) const INF: f32 = f32::INFINITY;

/// Every point case: seeded procedural scenes, then the edge cases.
pub fn point_cases() -> Vec<PointCase> {
    let mut cases = seeded_point_cases();
    cases.extend(edge_point_cases());
    cases
}

/// Seeded scenes with near-surface and volume points, at an infinite radius and at a finite
/// one that leaves many points without an answer.
pub fn seeded_point_cases() -> Vec<PointCase> {
    let soup = generated("soup:triangles=3000", SEED_SOUP);
    let sphere = generated("sphere:triangles=2000", SEED_SPHERE);
    let plane = generated("plane:quads=16", SEED_PLANE);
    let small = |m: &TriangleMesh| 0.02 * m.bounds().diagonal();
    let inside = points_in_box(
        &Aabb::new(Vec3::splat(-0.3), Vec3::splat(0.3)),
        500,
        SEED_SPHERE,
    );
    vec![
        PointCase::new(
            "soup",
            SEED_SOUP,
            soup.clone(),
            mixed_points(&soup, 1500, SEED_SOUP),
            &[INF, small(&soup)],
        ),
        PointCase::new(
            "sphere",
            SEED_SPHERE,
            sphere.clone(),
            mixed_points(&sphere, 1000, SEED_SPHERE),
            &[INF, small(&sphere)],
        ),
        PointCase::new("sphere-from-inside", SEED_SPHERE, sphere, inside, &[INF]),
        PointCase::new(
            "plane",
            SEED_PLANE,
            plane.clone(),
            mixed_points(&plane, 1000, SEED_PLANE),
            &[INF, small(&plane)],
        ),
        // Shared vertices and edges of the plane's grid: ties between up to six triangles.
        PointCase::new(
            "plane-features",
            SEED_PLANE,
            plane.clone(),
            surface_feature_points(&plane, 200),
            &[INF, 0.0],
        ),
    ]
}

/// The edge cases of the point suite (docs/validation.md, Adversarial checklist).
pub fn edge_point_cases() -> Vec<PointCase> {
    let s = SEED_EDGE;
    let unit_box = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let mut cases = vec![PointCase::new(
        "empty-mesh",
        s,
        mesh(vec![], vec![]),
        points_in_box(&unit_box, 50, s),
        &[INF, 1.0, 0.0],
    )];

    let one = from_tris(&[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)]);
    let mut points = surface_feature_points(&one, 1);
    points.extend([
        Vec3::new(0.25, 0.25, 0.0), // exactly on the face
        Vec3::new(0.25, 0.25, 1.0), // above the face
        Vec3::new(2.0, 2.0, 0.0),   // in the plane, beyond the hypotenuse
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1e6, -3e5, 7e5), // far outside
    ]);
    points.extend(points_in_box(&unit_box.enlarged(1.0), 300, s));
    // Radius 0 (only points on the triangle), a finite radius, one that excludes everything
    // the box points could reach, and the inclusive boundary itself (|(0.25,0.25,1)| = 1).
    cases.push(PointCase::new(
        "one-triangle",
        s,
        one,
        points,
        &[INF, 0.0, 0.5, 1.0, 1e-6],
    ));

    let a = Vec3::new(0.5, -0.25, 2.0);
    let lone_point = from_tris(&[Triangle::new(a, a, a)]);
    let around = points_in_box(&Aabb::new(a - 1.0, a + 1.0), 200, s);
    let mut pts = around.clone();
    pts.push(a);
    cases.push(PointCase::new(
        "single-point-triangle",
        s,
        lone_point,
        pts,
        &[INF, 0.0, 0.75],
    ));

    let collinear = from_tris(&[Triangle::new(
        Vec3::ZERO,
        Vec3::new(2.0, 1.0, 0.5),
        Vec3::new(1.0, 0.5, 0.25),
    )]);
    cases.push(PointCase::new(
        "single-collinear-triangle",
        s,
        collinear.clone(),
        mixed_points(&collinear, 200, s),
        &[INF, 0.1],
    ));

    cases.push(one_centroid_case());

    let same = from_tris(&vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 200]);
    cases.push(PointCase::new(
        "identical-triangles",
        s,
        same.clone(),
        mixed_points(&same, 300, s),
        &[INF],
    ));

    let flat = flat_soup(500, s);
    cases.push(PointCase::new(
        "flat-scene",
        s,
        flat.clone(),
        mixed_points(&flat, 500, s),
        &[INF, 0.05],
    ));

    let far = soup_mesh(1000, s, Vec3::splat(1e5));
    cases.push(PointCase::new(
        "offset-1e5",
        s,
        far.clone(),
        mixed_points(&far, 500, s),
        &[INF, 0.1],
    ));

    let mixed = zero_area_mixed(s);
    let mut pts = mixed_points(&mixed, 500, s);
    pts.extend(
        surface_feature_points(&mixed, mixed.len())
            .into_iter()
            .step_by(7),
    );
    cases.push(PointCase::new(
        "zero-area-mixed",
        s,
        mixed,
        pts,
        &[INF, 0.02],
    ));

    // Radius so small relative to the query points that nothing qualifies.
    let soup = soup_mesh(300, s, Vec3::ZERO);
    let beyond = points_in_box(&Aabb::new(Vec3::splat(3.0), Vec3::splat(4.0)), 200, s);
    cases.push(PointCase::new(
        "radius-excludes-everything",
        s,
        soup,
        beyond,
        &[1.0, 0.0],
    ));
    cases
}

/// Concentric triangles sharing one centroid (degenerate input for every splitting rule), with
/// the centroid itself among the points.
fn one_centroid_case() -> PointCase {
    let tris = concentric_triangles();
    let m = from_tris(&tris);
    let mut points = mixed_points(&m, 500, SEED_EDGE);
    points.push(Vec3::ZERO);
    PointCase::new("one-centroid", SEED_EDGE, m, points, &[INF, 0.05])
}

fn soup_mesh(n: usize, seed: u64, offset: Vec3) -> Arc<TriangleMesh> {
    from_tris(&soup_tris(n, seed, offset))
}

fn flat_soup(n: usize, seed: u64) -> Arc<TriangleMesh> {
    let flatten = |v: Vec3| v * Vec3::new(1.0, 1.0, 0.0);
    let tris: Vec<Triangle> = soup_tris(n, seed, Vec3::ZERO)
        .into_iter()
        .map(|t| Triangle::new(flatten(t.v0), flatten(t.v1), flatten(t.v2)))
        .collect();
    from_tris(&tris)
}

/// A soup with collinear and single-point triangles mixed in: they have points, so they count.
fn zero_area_mixed(seed: u64) -> Arc<TriangleMesh> {
    let mut tris = soup_tris(500, seed, Vec3::ZERO);
    for t in tris.clone().iter().take(200) {
        tris.push(Triangle::new(t.v0, t.v1, t.v0 * 0.5 + t.v1 * 0.5));
        tris.push(Triangle::new(t.v2 + 0.05, t.v2 + 0.05, t.v2 + 0.05));
    }
    from_tris(&tris)
}
