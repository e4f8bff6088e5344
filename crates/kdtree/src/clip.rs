//! Triangle–box clipping ("perfect splits") and the one rule that decides on which side of a
//! split plane a triangle goes. Both builders and `validate()` use exactly these functions, so
//! the validator recomputes the reference sets the builders must produce from the geometry
//! alone, bit for bit.

use raybench_geom::{Aabb, DVec3, Triangle, Vec3};

/// Bounds of the part of `tri` inside the closed box `bx`, or `None` when they do not meet.
///
/// Sutherland–Hodgman in f64 against the six planes of the box (the polygon grows by at most
/// one vertex per plane, so it lives in a fixed array), then the bounds of the polygon rounded
/// *outwards* to f32 and intersected with the box. Every computed vertex gets the clipping
/// plane's coordinate exactly, and the f64 intersection points are within a few f64 ulps of
/// the exact ones, far below the f32 rounding, so the result contains the exact clipped box in
/// practice and lies inside `bx` by construction. A triangle already inside the box is returned
/// as its own bounds, unclipped.
pub fn clipped_bounds(tri: &Triangle, bx: &Aabb) -> Option<Aabb> {
    let tb = tri.bounds();
    if bx.contains_box(&tb) {
        return Some(tb);
    }
    if !overlaps(&tb, bx) {
        return None;
    }
    let mut poly = [DVec3::ZERO; 10];
    let mut tmp = [DVec3::ZERO; 10];
    poly[0] = tri.v0.as_dvec3();
    poly[1] = tri.v1.as_dvec3();
    poly[2] = tri.v2.as_dvec3();
    let mut n = 3;
    for axis in 0..3 {
        for (c, keep_above) in [(bx.min[axis] as f64, true), (bx.max[axis] as f64, false)] {
            let inside = |p: &DVec3| {
                if keep_above {
                    p[axis] >= c
                } else {
                    p[axis] <= c
                }
            };
            if poly[..n].iter().all(inside) {
                continue; // this plane cuts nothing off (the usual case)
            }
            let mut m = 0;
            for i in 0..n {
                let p = poly[i];
                let q = poly[if i + 1 == n { 0 } else { i + 1 }];
                let (pin, qin) = (inside(&p), inside(&q));
                if pin {
                    tmp[m] = p;
                    m += 1;
                }
                if pin != qin {
                    let s = (c - p[axis]) / (q[axis] - p[axis]);
                    let mut r = p + (q - p) * s;
                    r[axis] = c;
                    tmp[m] = r;
                    m += 1;
                }
            }
            n = m;
            if n == 0 {
                return None;
            }
            poly[..n].copy_from_slice(&tmp[..n]);
        }
    }
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &poly[..n] {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let down = |x: f64| {
        let f = x as f32;
        if f as f64 > x { f.next_down() } else { f }
    };
    let up = |x: f64| {
        let f = x as f32;
        if (f as f64) < x { f.next_up() } else { f }
    };
    let clipped = Aabb::new(
        Vec3::new(down(lo.x), down(lo.y), down(lo.z)).max(bx.min),
        Vec3::new(up(hi.x), up(hi.y), up(hi.z)).min(bx.max),
    );
    (!clipped.is_empty()).then_some(clipped)
}

/// Closed-box overlap (touching counts).
pub fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// The intersection of two boxes (possibly empty).
pub fn intersection(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb::new(a.min.max(b.min), a.max.min(b.max))
}

/// Where a triangle whose (clipped) bounds are `b` goes when its node splits at `axis = p`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Entirely at or below the plane (touching it from below counts as below).
    Below,
    /// Entirely at or above the plane.
    Above,
    /// Strictly on both sides: referenced by both children, re-clipped to each.
    Both,
    /// Flat on `axis` and lying in the plane: the builder puts it on the cheaper side (Wald and
    /// Havran 2006, §4.1; the median builder: below), so either side is correct.
    InPlane,
}

/// The one classification rule. A triangle touching the plane from one side is *not*
/// referenced on the other: the only points it has there lie in the plane itself, and a ray
/// reaching them is inside the closed cell on the triangle's side too (traversal intervals are
/// closed).
#[inline]
pub fn side(b: &Aabb, axis: usize, p: f32) -> Side {
    let (lo, hi) = (b.min[axis], b.max[axis]);
    if lo == hi {
        if lo < p {
            Side::Below
        } else if lo > p {
            Side::Above
        } else {
            Side::InPlane
        }
    } else if hi <= p {
        Side::Below
    } else if lo >= p {
        Side::Above
    } else {
        Side::Both
    }
}

/// The two halves of a node box split at `axis = p`.
pub fn halves(v: &Aabb, axis: usize, p: f32) -> (Aabb, Aabb) {
    let (mut below, mut above) = (*v, *v);
    below.max[axis] = p;
    above.min[axis] = p;
    (below, above)
}

/// The bounds a triangle that straddles a split carries into the child box `child`: its
/// clipped bounds there or, should clipping find nothing (possible only within rounding of the
/// plane, since the parent's clipped bounds straddle it), its own bounds cut to the child box,
/// which is conservative and never empty.
pub fn straddler_bounds(tri: &Triangle, child: &Aabb) -> Aabb {
    clipped_bounds(tri, child).unwrap_or_else(|| intersection(&tri.bounds(), child))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(a.into(), b.into(), c.into())
    }

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn inside_is_returned_exactly() {
        let tri = t([0.1, 0.2, 0.3], [0.9, 0.2, 0.3], [0.1, 0.7, 0.8]);
        assert_eq!(clipped_bounds(&tri, &unit()), Some(tri.bounds()));
    }

    #[test]
    fn disjoint_is_none() {
        let tri = t([2.0, 2.0, 2.0], [3.0, 2.0, 2.0], [2.0, 3.0, 2.0]);
        assert_eq!(clipped_bounds(&tri, &unit()), None);
        // Bounding boxes overlap, the triangle does not reach the box (corner cut off).
        let diag = t([0.8, 2.0, 0.5], [2.0, 0.8, 0.5], [2.0, 2.0, 0.5]);
        assert!(overlaps(&diag.bounds(), &unit()));
        assert_eq!(clipped_bounds(&diag, &unit()), None);
    }

    #[test]
    fn big_triangle_is_cut_to_its_slice() {
        // The plane z = 0.5 spanning far beyond the box: clipped to the box's z = 0.5 square.
        let tri = t([-10.0, -10.0, 0.5], [30.0, -10.0, 0.5], [-10.0, 30.0, 0.5]);
        assert_eq!(
            clipped_bounds(&tri, &unit()),
            Some(Aabb::new(
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(1.0, 1.0, 0.5)
            ))
        );
    }

    #[test]
    fn diagonal_triangle_is_tighter_than_its_box() {
        // The triangle x + y <= 1 at z = 0.5, clipped to the upper-right quarter x, y >= 0.5:
        // it only reaches the single point (0.5, 0.5).
        let tri = t([0.0, 0.0, 0.5], [1.0, 0.0, 0.5], [0.0, 1.0, 0.5]);
        let quarter = Aabb::new(Vec3::new(0.5, 0.5, 0.0), Vec3::ONE);
        let b = clipped_bounds(&tri, &quarter).expect("touches at one point");
        assert!(b.min.x >= 0.5 && b.max.x <= 0.5 + 1e-6, "{b:?}");
        assert!(b.min.y >= 0.5 && b.max.y <= 0.5 + 1e-6, "{b:?}");
        // The half x >= 0.5: the clipped part spans y in [0, 0.5].
        let half = Aabb::new(Vec3::new(0.5, 0.0, 0.0), Vec3::ONE);
        let b = clipped_bounds(&tri, &half).unwrap();
        assert_eq!(
            b,
            Aabb::new(Vec3::new(0.5, 0.0, 0.5), Vec3::new(1.0, 0.5, 0.5))
        );
    }

    #[test]
    fn clipped_bounds_contain_sampled_points_of_the_clipped_part() {
        // Property on a named seed: every sampled point of the triangle inside the box lies in
        // the clipped bounds, and the clipped bounds lie inside the box.
        let mut s = 0x5eed_c11bu64;
        let mut f = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 3.0 - 1.0
        };
        for _ in 0..2000 {
            let tri = t([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]);
            let (a, b) = (Vec3::new(f(), f(), f()), Vec3::new(f(), f(), f()));
            let bx = Aabb::new(a.min(b), a.max(b));
            let clipped = clipped_bounds(&tri, &bx);
            if let Some(c) = clipped {
                assert!(bx.contains_box(&c));
            }
            for i in 0..=20 {
                for j in 0..=(20 - i) {
                    let (u, v) = (i as f32 / 20.0, j as f32 / 20.0);
                    let p = tri.point_at(u, v);
                    if bx.contains(p) {
                        let c = clipped.unwrap_or_else(|| panic!("{tri:?} in {bx:?}: lost {p}"));
                        assert!(c.enlarged(1e-6).contains(p), "{p} outside {c:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn sides() {
        let b = Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(side(&b, 0, 1.0), Side::Below);
        assert_eq!(side(&b, 0, 0.0), Side::Above);
        assert_eq!(side(&b, 0, 0.5), Side::Both);
        assert_eq!(side(&b, 2, 0.0), Side::InPlane);
        assert_eq!(side(&b, 2, 0.5), Side::Below);
        assert_eq!(side(&b, 2, -0.5), Side::Above);
    }
}
