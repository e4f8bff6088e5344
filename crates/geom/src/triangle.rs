use crate::watertight::WatertightRay;
use crate::{Aabb, Ray};
use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

/// Which ray–triangle test a structure uses: a named knob written into reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TriangleTest {
    /// Möller–Trumbore in the arrangement of Embree's fast mode (same edge and depth tests).
    #[default]
    MollerTrumbore,
    /// Woop, Benthin and Wald 2013: watertight along shared edges and at vertices.
    Watertight,
}

/// A hit on one triangle: distance and the barycentric weights of `v1` (`u`) and `v2` (`v`),
/// Embree's convention (`p = (1-u-v) v0 + u v1 + v v2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v0: Vec3,
    pub v1: Vec3,
    pub v2: Vec3,
}

/// A triangle in the layout Embree's fast mode stores (`Triangle4`: `v0`, `e1 = v0 - v1`,
/// `e2 = v2 - v0`, `Ng = e2 × e1`), precomputed once so each test skips two subtractions and a
/// cross product. [`Triangle::intersect_moller`] goes through this type, so both give
/// bit-identical answers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MollerTriangle {
    pub v0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    pub ng: Vec3,
}

impl MollerTriangle {
    #[inline(always)]
    pub fn new(t: &Triangle) -> MollerTriangle {
        let e1 = t.v0 - t.v1;
        let e2 = t.v2 - t.v0;
        MollerTriangle {
            v0: t.v0,
            e1,
            e2,
            ng: e2.cross(e1),
        }
    }

    /// Möller–Trumbore (1997) arranged as Embree's fast mode does it: edge tests on the
    /// unnormalised `U`, `V` against `|den|` and the depth test `|den| t_min < T <= |den| t_max`
    /// (strict at `t_min`, inclusive at `t_max`). Only `den == 0` is rejected — no absolute
    /// epsilon, so tiny triangles are hit (tinybvh #283) and zero-area triangles never are.
    /// Every comparison is false on NaN.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<TriHit> {
        let c = self.v0 - ray.origin();
        let r = c.cross(ray.dir());
        let den = self.ng.dot(ray.dir());
        let abs_den = den.abs();
        let flip = |x: f32| if den.is_sign_negative() { -x } else { x };
        let u = flip(r.dot(self.e2));
        let v = flip(r.dot(self.e1));
        if !(den != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= abs_den) {
            return None;
        }
        let t = flip(self.ng.dot(c));
        if !(abs_den * ray.t_min() < t && t <= abs_den * ray.t_max()) {
            return None;
        }
        let inv = 1.0 / abs_den;
        Some(TriHit {
            t: t * inv,
            u: u * inv,
            v: v * inv,
        })
    }
}

/// A double-precision look at where a ray meets a triangle's plane, used to arbitrate disputed
/// rays: `edge_distance` is the signed distance from that point to the nearest edge
/// (positive inside), `scale` the largest coordinate magnitude involved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneCrossing {
    pub t: f64,
    pub edge_distance: f64,
    pub scale: f64,
}

impl Triangle {
    #[inline]
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Triangle {
        Triangle { v0, v1, v2 }
    }

    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.v0.min(self.v1).min(self.v2),
            max: self.v0.max(self.v1).max(self.v2),
        }
    }

    pub fn centroid(&self) -> Vec3 {
        (self.v0 + self.v1 + self.v2) * (1.0 / 3.0)
    }

    /// Unnormalised normal `(v1 - v0) × (v2 - v0)`: counter-clockwise front face.
    pub fn geometric_normal(&self) -> Vec3 {
        (self.v1 - self.v0).cross(self.v2 - self.v0)
    }

    /// Area in f64, so tiny and huge triangles are both measured without underflow.
    pub fn area(&self) -> f64 {
        let a = self.v0.as_dvec3();
        (self.v1.as_dvec3() - a)
            .cross(self.v2.as_dvec3() - a)
            .length()
            * 0.5
    }

    /// The point with Embree's barycentrics `(u, v)`.
    pub fn point_at(&self, u: f32, v: f32) -> Vec3 {
        self.v0 * (1.0 - u - v) + self.v1 * u + self.v2 * v
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, test: TriangleTest) -> Option<TriHit> {
        match test {
            TriangleTest::MollerTrumbore => self.intersect_moller(ray),
            TriangleTest::Watertight => self.intersect_watertight(ray),
        }
    }

    /// Möller–Trumbore in Embree's fast-mode arrangement; see [`MollerTriangle::intersect`].
    #[inline(always)]
    pub fn intersect_moller(&self, ray: &Ray) -> Option<TriHit> {
        MollerTriangle::new(self).intersect(ray)
    }

    /// The watertight test of Woop, Benthin and Wald (JCGT 2(1), 2013); see
    /// [`WatertightRay::intersect`], which a scan over many triangles sets up once per ray.
    #[inline(always)]
    pub fn intersect_watertight(&self, ray: &Ray) -> Option<TriHit> {
        WatertightRay::new(ray).intersect(self)
    }

    /// Where the ray meets the triangle's plane, in f64, with the signed distance to the nearest
    /// edge. `None` when the ray is parallel to the plane or the triangle has no area.
    pub fn plane_crossing_f64(&self, ray: &Ray) -> Option<PlaneCrossing> {
        let [p0, p1, p2] = [self.v0, self.v1, self.v2].map(Vec3::as_dvec3);
        let o = ray.origin().as_dvec3();
        let d = ray.dir().as_dvec3();
        let n = (p1 - p0).cross(p2 - p0);
        let n_len = n.length();
        let den = n.dot(d);
        if n_len == 0.0 || den == 0.0 {
            return None;
        }
        let t = n.dot(p0 - o) / den;
        let hit = o + d * t;
        let n_hat = n / n_len;
        let edge_distance = [(p0, p1), (p1, p2), (p2, p0)]
            .into_iter()
            .map(|(a, b)| signed_edge_distance(a, b, hit, n_hat))
            .fold(f64::INFINITY, f64::min);
        let scale = [p0, p1, p2, o, hit]
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f64::max);
        Some(PlaneCrossing {
            t,
            edge_distance,
            scale,
        })
    }
}

/// Distance from `p` to the line through `a`→`b` inside the plane with unit normal `n_hat`,
/// positive on the triangle's side (counter-clockwise winding about `n_hat`).
fn signed_edge_distance(a: DVec3, b: DVec3, p: DVec3, n_hat: DVec3) -> f64 {
    let edge = b - a;
    let len = edge.length();
    if len == 0.0 {
        return 0.0;
    }
    edge.cross(p - a).dot(n_hat) / len
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    const TESTS: [TriangleTest; 2] = [TriangleTest::MollerTrumbore, TriangleTest::Watertight];

    /// The unit right triangle in z = 0.
    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    fn down(x: f32, y: f32) -> Ray {
        Ray::infinite(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0))
    }

    #[test]
    fn interior_hit_has_embree_barycentrics() {
        for test in TESTS {
            let h = tri()
                .intersect(&down(0.25, 0.5), test)
                .expect("interior hit");
            assert_eq!(h.t, 1.0, "{test:?}");
            assert!(
                (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
                "{test:?} {h:?}"
            );
            assert!((tri().point_at(h.u, h.v) - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-6);
        }
    }

    #[test]
    fn back_face_is_hit_too() {
        for test in TESTS {
            let up = Ray::infinite(Vec3::new(0.25, 0.25, -2.0), Vec3::Z);
            assert_eq!(
                tri().intersect(&up, test).map(|h| h.t),
                Some(2.0),
                "{test:?}"
            );
        }
    }

    #[test]
    fn edges_and_vertices_are_inclusive() {
        // On the legs x = 0, y = 0, on the hypotenuse and on each vertex: exact in both tests.
        let on_boundary = [
            (0.0, 0.5),
            (0.5, 0.0),
            (0.5, 0.5),
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
        ];
        for test in TESTS {
            for (x, y) in on_boundary {
                assert!(
                    tri().intersect(&down(x, y), test).is_some(),
                    "{test:?} at ({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn just_outside_misses() {
        let outside = [
            (-1e-6, 0.5),
            (0.5, -1e-6),
            (0.5 + 1e-6, 0.5 + 1e-6),
            (1.0 + 1e-6, 0.0),
        ];
        for test in TESTS {
            for (x, y) in outside {
                assert!(
                    tri().intersect(&down(x, y), test).is_none(),
                    "{test:?} at ({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn parallel_and_in_plane_rays_miss() {
        for test in TESTS {
            let above = Ray::infinite(Vec3::new(-1.0, 0.2, 0.5), Vec3::X);
            let in_plane = Ray::infinite(Vec3::new(-1.0, 0.2, 0.0), Vec3::X);
            assert!(tri().intersect(&above, test).is_none(), "{test:?}");
            assert!(tri().intersect(&in_plane, test).is_none(), "{test:?}");
        }
    }

    #[test]
    fn t_min_is_exclusive_and_t_max_inclusive() {
        let o = Vec3::new(0.25, 0.25, 1.0);
        let d = Vec3::new(0.0, 0.0, -1.0);
        for test in TESTS {
            assert!(
                tri().intersect(&Ray::new(o, d, 1.0, 5.0), test).is_none(),
                "{test:?} t_min"
            );
            assert!(
                tri().intersect(&Ray::new(o, d, 0.5, 1.0), test).is_some(),
                "{test:?} t_max"
            );
            assert!(
                tri().intersect(&Ray::new(o, d, 0.0, 0.999), test).is_none(),
                "{test:?}"
            );
            // Origin on the surface with t_min = 0: t = 0 is not > t_min (Embree fast mode).
            let on = Ray::new(Vec3::new(0.25, 0.25, 0.0), d, 0.0, 1.0);
            assert!(
                tri().intersect(&on, test).is_none(),
                "{test:?} origin on surface"
            );
        }
    }

    #[test]
    fn unnormalised_direction_scales_t() {
        for test in TESTS {
            let r = Ray::infinite(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -4.0));
            assert_eq!(
                tri().intersect(&r, test).map(|h| h.t),
                Some(0.25),
                "{test:?}"
            );
        }
    }

    #[test]
    fn zero_area_triangles_are_never_hit() {
        let collinear = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let point = Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE);
        for test in TESTS {
            for (x, y) in [(0.5, 0.0), (1.0, 1.0), (0.0, 0.0)] {
                assert!(collinear.intersect(&down(x, y), test).is_none());
                assert!(point.intersect(&down(x, y), test).is_none());
            }
        }
    }

    #[test]
    fn tiny_triangle_is_hit() {
        let s = 2e-4;
        let small = Triangle::new(Vec3::ZERO, Vec3::X * s, Vec3::Y * s);
        for test in TESTS {
            assert!(
                small.intersect(&down(s / 4.0, s / 4.0), test).is_some(),
                "{test:?}"
            );
        }
    }

    #[test]
    fn watertight_on_shared_diagonal_far_from_origin() {
        // Two triangles of a quad at offset 1e4; rays through the shared diagonal always hit one.
        let off = Vec3::new(1e4, 1e4, 0.0);
        let a = Triangle::new(off, off + Vec3::X, off + Vec3::new(1.0, 1.0, 0.0));
        let b = Triangle::new(off, off + Vec3::new(1.0, 1.0, 0.0), off + Vec3::Y);
        // Interior points of the diagonal only: its ends are silhouette corners of the quad.
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            let p = off + Vec3::new(s, s, 0.0);
            let r = Ray::infinite(p + Vec3::new(0.3, -0.2, 1.0), Vec3::new(-0.3, 0.2, -1.0));
            let hit = a.intersect_watertight(&r).or(b.intersect_watertight(&r));
            assert!(hit.is_some(), "crack at s = {s}");
        }
    }

    /// Random triangles and rays aimed near their centroids (about half pass inside the
    /// edges), with windows that end before, at and after the plane; rays through the unit
    /// triangle's vertices and edge midpoints (edge functions exactly 0) in several
    /// directions, zero and non-finite ones included; a degenerate triangle. For the tests
    /// that hold a branch-free test to the test it stands in front of.
    pub(crate) fn random_and_edge_cases() -> Vec<(Triangle, Ray)> {
        let mut rng = crate::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut cases: Vec<(Triangle, Ray)> = Vec::new();
        for i in 0..50_000 {
            let mut v = || rng.signed_vec();
            let tri = Triangle::new(v(), v(), v());
            let o = v() * 3.0;
            let d = (tri.v0 + tri.v1 + tri.v2) / 3.0 - o + v() * 0.3;
            let t_min = [0.5, 0.0, 0.0][i % 3];
            let t_max = [f32::INFINITY, 1.0, 3.0][i % 3];
            cases.push((tri, Ray::new(o, d, t_min, t_max)));
        }
        // Aimed at points of an edge: the edge function rounds to about 0, at times to exactly
        // 0 in f32 where it is not in f64, and the others are redone in f64 too.
        for i in 0..50_000 {
            let mut v = || rng.signed_vec();
            let tri = Triangle::new(v(), v(), v());
            // A quarter of them at a vertex, where two edge functions are about 0.
            let s = if i % 4 == 0 { 0.0 } else { rng.unit() };
            let on_edge = [tri.v0, tri.v1, tri.v2][i % 3].lerp([tri.v1, tri.v2, tri.v0][i % 3], s);
            let o = rng.signed_vec() * 3.0;
            cases.push((tri, Ray::new(o, on_edge - o, 0.0, f32::INFINITY)));
        }
        let t = tri();
        let at = |p: Vec3, d: Vec3, t_max: f32| Ray::new(p - d, d, 0.0, t_max);
        let nan = Vec3::new(f32::NAN, 0.0, -1.0);
        let inf = Vec3::new(f32::INFINITY, 0.0, -1.0);
        let oblique = Vec3::new(0.3, -0.2, -1.0);
        for p in [t.v0, t.v1, t.v2, (t.v0 + t.v1) * 0.5, (t.v1 + t.v2) * 0.5] {
            for d in [-Vec3::Z, Vec3::Z, Vec3::X, oblique, Vec3::ZERO, nan, inf] {
                for t_max in [0.5, 1.0, f32::INFINITY] {
                    cases.push((t, at(p, d, t_max)));
                }
            }
        }
        let collinear = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        cases.push((collinear, down(0.5, 0.0)));
        cases
    }

    #[test]
    fn plane_crossing_reports_edge_distance() {
        let c = tri().plane_crossing_f64(&down(0.25, 0.25)).unwrap();
        assert!((c.t - 1.0).abs() < 1e-12);
        assert!((c.edge_distance - 0.25).abs() < 1e-12, "{c:?}");
        let out = tri().plane_crossing_f64(&down(-0.1, 0.5)).unwrap();
        assert!((out.edge_distance + 0.1).abs() < 1e-7, "{out:?}");
        assert!(
            tri()
                .plane_crossing_f64(&Ray::infinite(Vec3::Z, Vec3::X))
                .is_none()
        );
    }
}
