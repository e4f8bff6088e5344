//! Query points: uniform in a box, near a mesh's surface, and exactly on its vertices, edge
//! midpoints and centroids.

use crate::rays::{on_sphere, seeded_rng, unit_f32};
use rand_core::Rng;
use raybench_geom::{Aabb, TriangleMesh, Vec3};

/// `n` points uniform in `bounds`.
pub fn points_in_box(bounds: &Aabb, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = seeded_rng(seed);
    let e = bounds.extent();
    (0..n)
        .map(|_| {
            bounds.min + Vec3::new(unit_f32(&mut rng), unit_f32(&mut rng), unit_f32(&mut rng)) * e
        })
        .collect()
}

/// `n` points near the surface: a random triangle (uniform by index), a random point on it,
/// moved in a random direction by up to `max_offset`. Empty for an empty mesh.
pub fn points_near_surface(mesh: &TriangleMesh, n: usize, max_offset: f32, seed: u64) -> Vec<Vec3> {
    if mesh.is_empty() {
        return Vec::new();
    }
    let mut rng = seeded_rng(seed);
    (0..n)
        .map(|_| {
            let prim = (rng.next_u64() % mesh.len() as u64) as usize;
            let (mut u, mut v) = (unit_f32(&mut rng), unit_f32(&mut rng));
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let on = mesh.triangle(prim).point_at(u, v);
            on + on_sphere(&mut rng) * (max_offset * unit_f32(&mut rng))
        })
        .collect()
}

/// Points exactly on the surface features of the first `max_tris` triangles: every vertex
/// (exactly representable), every edge midpoint and the centroid (on the surface up to rounding).
pub fn surface_feature_points(mesh: &TriangleMesh, max_tris: usize) -> Vec<Vec3> {
    mesh.triangles()
        .take(max_tris)
        .flat_map(|t| {
            [
                t.v0,
                t.v1,
                t.v2,
                (t.v0 + t.v1) * 0.5,
                (t.v1 + t.v2) * 0.5,
                (t.v2 + t.v0) * 0.5,
                t.centroid(),
            ]
        })
        .collect()
}

/// Points exactly on the planes `first + step·i`, `i < count`, of a lattice (grid cells,
/// octants): every crossing of three planes (in z only every `z_stride`-th plane), then 1000
/// points uniform in `bounds` enlarged by 0.5 with one coordinate, and every other point a
/// second one, moved onto a plane. A point on a plane lies in both closed cells around it.
pub fn points_on_planes(
    first: f32,
    step: f32,
    count: u32,
    z_stride: usize,
    bounds: &Aabb,
    seed: u64,
) -> Vec<Vec3> {
    let plane = |i: u32| first + step * i as f32;
    let mut points = Vec::new();
    for z in (0..count).step_by(z_stride) {
        for y in 0..count {
            for x in 0..count {
                points.push(Vec3::new(plane(x), plane(y), plane(z)));
            }
        }
    }
    let n = count as usize;
    let random = points_in_box(&bounds.enlarged(0.5), 1000, seed);
    for (i, mut p) in random.into_iter().enumerate() {
        p[i % 3] = plane((i % n) as u32);
        if i % 2 == 0 {
            p[(i + 1) % 3] = plane((i / 3 % n) as u32);
        }
        points.push(p);
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases::SEED_SPHERE;
    use crate::points::exact_distance;
    use crate::{generated, mesh};

    #[test]
    fn generators_are_deterministic_and_where_they_say() {
        let m = generated("sphere:triangles=500", SEED_SPHERE);
        let a = points_near_surface(&m, 200, 0.01, 7);
        assert_eq!(a, points_near_surface(&m, 200, 0.01, 7));
        assert_ne!(a, points_near_surface(&m, 200, 0.01, 8));
        for p in &a {
            let d = m
                .triangles()
                .map(|t| exact_distance(*p, &t))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= 0.01 + 1e-6, "{p} is {d} from the surface");
        }
        let b = Aabb::new(Vec3::splat(-2.0), Vec3::new(1.0, 2.0, 3.0));
        assert!(points_in_box(&b, 500, 3).iter().all(|p| b.contains(*p)));
        assert!(points_near_surface(&mesh(vec![], vec![]), 10, 1.0, 1).is_empty());
    }
}
