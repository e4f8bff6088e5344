//! Closest point on a triangle to a query point, after the Voronoi-region method of Ericson,
//! *Real-Time Collision Detection* (2005), §5.1.5, evaluated in f64 with the region
//! decisions rearranged for thin triangles.
//!
//! Ericson splits the plane of the triangle into seven regions (three vertices, three edges,
//! the face) and decides which holds the query point from six dot products and three
//! differences of their products (`va`, `vb`, `vc`). Those differences cancel badly for thin
//! triangles: in f32 a needle 1e-4 wide gets a face point 4e-3 away from the true answer
//! (found by the dense-sampling test below). So this version keeps Ericson's vertex tests
//! (robust: the sign of one dot product each), then decides face versus edges with edge
//! functions `(edge × (p - start)) · n` built from cross products, whose error is a few f64
//! ulps of `|p - start|` whatever the triangle's shape, and answers with the plane projection
//! (inside) or the nearest of the edges the point lies outside of. Everything runs in f64:
//! differences of f32 coordinates and their products are exact there, and scalar f64
//! arithmetic costs the same as f32 on x86-64, so the price is the conversions and a few more
//! operations than Ericson's original (one extra cross product per edge). Zero-area triangles
//! have no normal and are answered by their nearest edge.

use crate::{Aabb, EMBREE_LARGE, Triangle};
use glam::{DVec3, Vec3};

/// The squared search radius of a closest-point query, or `None` when the query has no answer
/// by definition: a non-finite query point or one beyond Embree's coordinate limit
/// ([`EMBREE_LARGE`], where Embree's own arithmetic is undefined), or a negative or NaN radius.
///
/// Every structure starts its search from this value and accepts a triangle whose squared
/// distance `d2` (computed from [`closest_point_on_triangle`]) satisfies `d2 <= radius²`, so all
/// structures and Embree agree exactly on which triangles are inside the (inclusive) radius.
/// An infinite radius gives `+inf`; a radius whose square overflows also gives `+inf`.
#[inline]
pub fn query_radius_squared(p: Vec3, max_radius: f32) -> Option<f32> {
    let valid_point = p.is_finite() && p.abs().max_element() <= EMBREE_LARGE;
    (valid_point && max_radius >= 0.0).then_some(max_radius * max_radius)
}

/// The point of `tri` nearest to `p` (on its boundary or interior), rounded to f32. Exact for
/// vertex answers; otherwise within a few f32 ulps of the largest coordinate involved.
#[inline]
pub fn closest_point_on_triangle(p: Vec3, tri: &Triangle) -> Vec3 {
    let [p, a, b, c] = [p, tri.v0, tri.v1, tri.v2].map(Vec3::as_dvec3);
    closest_point_f64(p, a, b, c).as_vec3()
}

#[inline(always)]
fn closest_point_f64(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    // Vertex regions (Ericson): p sees no point of the triangle in front of the vertex.
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    if !(n2 > 0.0 && n2.is_finite()) {
        return nearest_on_edges(p, [(a, b), (b, c), (c, a)].map(Some));
    }
    // Which edge lines p lies outside of (negative edge function), seen along the normal.
    let outside =
        |s: DVec3, e: DVec3, sp: DVec3| ((e - s).cross(sp).dot(n) < 0.0).then_some((s, e));
    let edges = [outside(a, b, ap), outside(b, c, bp), outside(c, a, cp)];
    if edges.iter().all(Option::is_none) {
        return p - n * (n.dot(ap) / n2); // face region: the projection onto the plane
    }
    // Outside a convex polygon, the nearest point lies on an edge whose line separates it.
    nearest_on_edges(p, edges)
}

/// The nearest point to `p` on the given segments (at least one is `Some`).
#[inline(always)]
fn nearest_on_edges(p: DVec3, edges: [Option<(DVec3, DVec3)>; 3]) -> DVec3 {
    let mut best = (f64::INFINITY, p);
    for (s, e) in edges.into_iter().flatten() {
        let q = nearest_on_segment(p, s, e);
        let dist2 = q.distance_squared(p);
        if dist2 < best.0 {
            best = (dist2, q);
        }
    }
    best.1
}

/// The nearest point to `p` on the segment from `s` to `e` (`s` itself when the segment is a
/// point).
#[inline(always)]
fn nearest_on_segment(p: DVec3, s: DVec3, e: DVec3) -> DVec3 {
    let d = e - s;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - s).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    s + d * t
}

/// Squared distance from `p` to the nearest point of `b` (0 inside). An empty box
/// ([`Aabb::EMPTY`]) is infinitely far away: its `min - p` is `+inf`.
#[inline(always)]
pub fn box_distance_squared(p: Vec3, b: &Aabb) -> f32 {
    (b.min - p).max(p - b.max).max(Vec3::ZERO).length_squared()
}

/// Distance from `p` to `tri` in f64, for checking answers (testkit classifies ties with it): the
/// distance to the plane when the projection of `p` falls inside the triangle, otherwise the
/// nearest of all three edges. A different route from [`closest_point_on_triangle`] (no vertex
/// shortcuts, no edge selection, no rounding to f32); the dense-sampling test below checks
/// both. Zero-area triangles are their edges (or their single point). Not a query path.
pub fn distance_to_triangle_f64(p: Vec3, tri: &Triangle) -> f64 {
    let (p, a, b, c) = (
        p.as_dvec3(),
        tri.v0.as_dvec3(),
        tri.v1.as_dvec3(),
        tri.v2.as_dvec3(),
    );
    let n = (b - a).cross(c - a);
    let n2 = n.length_squared();
    if n2 > 0.0 {
        let q = p - n * (n.dot(p - a) / n2);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(s, e)| (e - s).cross(q - s).dot(n) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(s, e)| segment_distance_f64(p, s, e))
        .fold(f64::INFINITY, f64::min)
}

fn segment_distance_f64(p: DVec3, s: DVec3, e: DVec3) -> f64 {
    (p - nearest_on_segment(p, s, e)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rng::SplitMix64 as Rng;

    /// The shapes the region method must survive, each a function of the stream.
    #[derive(Clone, Copy, Debug)]
    enum Shape {
        Ordinary,
        /// One vertex within 1e-4 of the opposite edge: a needle.
        Thin,
        /// 1e-5 across, 1 away from the origin.
        Tiny,
        /// Unit size at 1e6 from the origin: coordinates with an ulp of 0.0625.
        HugeCoordinates,
        /// 1e5 across.
        Huge,
        /// Third vertex on the line through the first two.
        Collinear,
        /// Two equal vertices.
        RepeatedVertex,
        /// All three vertices equal.
        Point,
    }

    const SHAPES: [Shape; 8] = [
        Shape::Ordinary,
        Shape::Thin,
        Shape::Tiny,
        Shape::HugeCoordinates,
        Shape::Huge,
        Shape::Collinear,
        Shape::RepeatedVertex,
        Shape::Point,
    ];

    fn random_triangle(rng: &mut Rng, shape: Shape) -> Triangle {
        let (a, b) = (rng.signed_vec(), rng.signed_vec());
        let c = match shape {
            Shape::Thin => a.lerp(b, rng.signed() * 0.5 + 0.5) + rng.signed_vec() * 1e-4,
            Shape::Collinear => a.lerp(b, rng.signed() * 1.5),
            Shape::RepeatedVertex => a,
            _ => rng.signed_vec(),
        };
        let t = Triangle::new(a, b, c);
        let (scale, offset) = match shape {
            Shape::Tiny => (1e-5, Vec3::ONE),
            Shape::HugeCoordinates => (1.0, Vec3::new(1e6, -1e6, 5e5)),
            Shape::Huge => (1e5, Vec3::ZERO),
            _ => (1.0, Vec3::ZERO),
        };
        let place = |v: Vec3| v * scale + offset;
        match shape {
            Shape::Point => Triangle::new(place(a), place(a), place(a)),
            _ => Triangle::new(place(t.v0), place(t.v1), place(t.v2)),
        }
    }

    /// A query point around the triangle: in its box enlarged by its size, or in its plane.
    fn random_query(rng: &mut Rng, t: &Triangle) -> Vec3 {
        let b = t.bounds();
        let size = b.diagonal().max(1e-6 * b.max.abs().max_element().max(1.0));
        let near = b.center() + rng.signed_vec() * size;
        if rng.next_u64().is_multiple_of(4) {
            // Exactly in the plane of (v0, v1): the in-plane regions, where signs are closest to 0.
            t.v0 + (t.v1 - t.v0) * (rng.signed() * 2.0) + (t.v2 - t.v0) * rng.signed()
        } else {
            near
        }
    }

    /// One f32 ulp (machine epsilon) of the largest coordinate involved.
    fn ulp(p: Vec3, t: &Triangle) -> f64 {
        let scale = [p, t.v0, t.v1, t.v2]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(0.0f32, f32::max);
        f32::EPSILON as f64 * scale.max(f32::MIN_POSITIVE) as f64
    }

    /// Rounding allowance: 4 ulps (measured worst case 0.63 with these seeds: the f64 answer
    /// rounded to f32 once).
    fn tolerance(p: Vec3, t: &Triangle) -> f64 {
        4.0 * ulp(p, t)
    }

    /// The nearest of `n × n` barycentric samples (the vertices and the edges included), in
    /// f64, and how far the true nearest point can be from its nearest sample.
    fn best_sample(p: Vec3, t: &Triangle, n: u32) -> (f64, f64) {
        let (p, a, b, c) = (
            p.as_dvec3(),
            t.v0.as_dvec3(),
            t.v1.as_dvec3(),
            t.v2.as_dvec3(),
        );
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let s = a + (b - a) * u + (c - a) * v;
                best = best.min((s - p).length());
            }
        }
        let longest = [(a, b), (b, c), (c, a)]
            .iter()
            .map(|(x, y)| (*x - *y).length())
            .fold(0.0, f64::max);
        (best, longest / n as f64)
    }

    /// Thousands of seeded triangles of every shape: the region answer lies on the triangle,
    /// is no farther than any sample, within the sample spacing of the best sample, and agrees
    /// with the f64 reference. The reference passes the same sampling test.
    #[test]
    fn region_method_matches_dense_sampling() {
        let mut rng = Rng::new(0x5eed_9001);
        let mut worst_ulps = 0.0f64;
        for shape in SHAPES {
            for _ in 0..150 {
                let t = random_triangle(&mut rng, shape);
                for _ in 0..4 {
                    let p = random_query(&mut rng, &t);
                    let q = closest_point_on_triangle(p, &t);
                    let tol = tolerance(p, &t);
                    let got = (q.as_dvec3() - p.as_dvec3()).length();
                    let (sampled, spacing) = best_sample(p, &t, 96);
                    let reference = distance_to_triangle_f64(p, &t);
                    let what = format!("{shape:?} {t:?} p={p} q={q}");
                    assert!(q.is_finite(), "{what}");
                    assert!(
                        distance_to_triangle_f64(q, &t) <= tol,
                        "off the triangle: {what}"
                    );
                    assert!(
                        got <= sampled + tol,
                        "farther than a sample: {got} > {sampled}: {what}"
                    );
                    assert!(
                        got >= sampled - spacing - tol,
                        "{got} < {sampled} - {spacing}: {what}"
                    );
                    assert!(reference <= sampled + 1e-9 * sampled.max(1.0), "{what}");
                    assert!(reference >= sampled - spacing * 1.0001, "{what}");
                    assert!(
                        (got - reference).abs() <= tol,
                        "{got} vs {reference}: {what}"
                    );
                    worst_ulps = worst_ulps.max((got - reference).abs() / ulp(p, &t));
                }
            }
        }
        eprintln!("worst |region - reference| = {worst_ulps:.2} ulps of the coordinate scale");
    }

    #[test]
    fn exact_regions_of_a_right_triangle() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let cases = [
            (Vec3::new(-1.0, -1.0, 0.5), Vec3::ZERO), // vertex A
            (Vec3::new(3.0, -0.5, 0.0), Vec3::X),     // vertex B
            (Vec3::new(-0.5, 3.0, -2.0), Vec3::Y),    // vertex C
            (Vec3::new(0.5, -2.0, 0.0), Vec3::new(0.5, 0.0, 0.0)), // edge AB
            (Vec3::new(-2.0, 0.25, 1.0), Vec3::new(0.0, 0.25, 0.0)), // edge AC
            (Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0)), // edge BC
            (Vec3::new(0.25, 0.5, 3.0), Vec3::new(0.25, 0.5, 0.0)), // face
            (Vec3::new(0.0, 0.0, 0.0), Vec3::ZERO),   // on vertex A
        ];
        for (p, expected) in cases {
            assert_eq!(closest_point_on_triangle(p, &t), expected, "p = {p}");
        }
    }

    #[test]
    fn zero_area_triangles_give_their_nearest_point() {
        let a = Vec3::new(1.0, 2.0, 3.0);
        let point = Triangle::new(a, a, a);
        assert_eq!(closest_point_on_triangle(Vec3::ZERO, &point), a);
        let segment = Triangle::new(
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        );
        for (p, expected) in [
            (Vec3::new(1.0, 5.0, 0.0), Vec3::new(1.0, 0.0, 0.0)),
            (Vec3::new(3.0, 0.0, -2.0), Vec3::new(3.0, 0.0, 0.0)),
            (Vec3::new(9.0, 1.0, 0.0), Vec3::new(4.0, 0.0, 0.0)),
            (Vec3::new(-9.0, 1.0, 0.0), Vec3::ZERO),
        ] {
            assert_eq!(closest_point_on_triangle(p, &segment), expected, "p = {p}");
        }
    }

    #[test]
    fn box_distance_outside_inside_and_on_the_boundary() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(box_distance_squared(Vec3::new(0.5, 1.0, 1.0), &b), 0.0);
        assert_eq!(box_distance_squared(Vec3::new(1.0, 2.0, 3.0), &b), 0.0);
        assert_eq!(box_distance_squared(Vec3::new(-2.0, 1.0, 1.0), &b), 4.0);
        assert_eq!(box_distance_squared(Vec3::new(2.0, 4.0, 1.0), &b), 5.0);
        assert_eq!(box_distance_squared(Vec3::new(-1.0, -1.0, 4.0), &b), 3.0);
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0));
        assert_eq!(box_distance_squared(Vec3::new(0.5, 0.5, -1.0), &flat), 4.0);
        assert_eq!(
            box_distance_squared(Vec3::ZERO, &Aabb::EMPTY),
            f32::INFINITY
        );
    }

    /// BVH pruning relies on the box distance being a lower bound of every triangle's distance:
    /// checked against the f64 reference on random boxes and triangles inside them.
    #[test]
    fn box_distance_is_a_lower_bound_of_the_contents() {
        let mut rng = Rng::new(0x5eed_9002);
        for shape in SHAPES {
            for _ in 0..500 {
                let t = random_triangle(&mut rng, shape);
                let p = random_query(&mut rng, &t) + rng.signed_vec() * t.bounds().diagonal();
                let boxed = box_distance_squared(p, &t.bounds()) as f64;
                let exact = distance_to_triangle_f64(p, &t);
                assert!(
                    boxed.sqrt() <= exact + tolerance(p, &t),
                    "{shape:?} {t:?} p={p}"
                );
                let q = closest_point_on_triangle(p, &t);
                let d2 = q.distance_squared(p) as f64;
                let slack = 2.0 * d2.sqrt() * tolerance(p, &t) + tolerance(p, &t).powi(2);
                assert!(boxed <= d2 + slack, "{shape:?} {t:?} p={p}");
            }
        }
    }

    #[test]
    fn query_radius_rules() {
        assert_eq!(query_radius_squared(Vec3::ONE, 2.0), Some(4.0));
        assert_eq!(query_radius_squared(Vec3::ONE, 0.0), Some(0.0));
        assert_eq!(
            query_radius_squared(Vec3::ONE, f32::INFINITY),
            Some(f32::INFINITY)
        );
        assert_eq!(query_radius_squared(Vec3::ONE, 1e30), Some(f32::INFINITY));
        assert_eq!(query_radius_squared(Vec3::ONE, -1.0), None);
        assert_eq!(query_radius_squared(Vec3::ONE, f32::NAN), None);
        assert_eq!(
            query_radius_squared(Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
            None
        );
        assert_eq!(
            query_radius_squared(Vec3::new(0.0, f32::NEG_INFINITY, 0.0), 1.0),
            None
        );
        assert_eq!(query_radius_squared(Vec3::new(0.0, 0.0, 2e18), 1.0), None);
        assert_eq!(
            query_radius_squared(Vec3::new(0.0, 0.0, EMBREE_LARGE), 1.0),
            Some(1.0)
        );
    }
}
