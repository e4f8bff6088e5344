//! Cutting a triangle's reference at an axis-aligned plane: the boxes of the parts of the
//! triangle on either side, each clipped to the reference's box. The binning pass chops a
//! reference at every bin plane it crosses, and the split itself cuts the straddling references
//! at the chosen plane; both go through [`split_at`].
//!
//! The part on one side of the plane is the polygon bounded by the triangle's vertices on that
//! side and the points where its edges cross the plane, so its box is the box of those points.
//! That box is intersected with the reference's box (a reference may already be a piece of its
//! triangle), which can be larger than the box of the piece itself (it is the box of the
//! triangle's half, cut to a box) but never smaller: the pieces' boxes always cover the
//! triangle. Crossing points are computed in f64 and rounded outwards to f32, so the two sides'
//! boxes still cover the triangle after rounding, with the plane coordinate itself exact.

use crate::build::Box3;
use glam::Vec3A;
use raybench_geom::Triangle;

/// The triangle's vertices as the chopping reads them.
pub(crate) type Corners = [Vec3A; 3];

pub(crate) fn corners(t: &Triangle) -> Corners {
    [t.v0.into(), t.v1.into(), t.v2.into()]
}

/// The boxes of the parts of `tri` with coordinate `axis` at most and at least `pos`, each
/// intersected with `within` (empty, `lo > hi` on some axis, when no part of the triangle
/// inside `within` lies on that side).
pub(crate) fn split_at(tri: &Corners, axis: usize, pos: f32, within: &Box3) -> (Box3, Box3) {
    let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
    for i in 0..3 {
        let (a, b) = (tri[i], tri[(i + 1) % 3]);
        if a[axis] <= pos {
            left = left.grow(a);
        }
        if a[axis] >= pos {
            right = right.grow(a);
        }
        if (a[axis] < pos && b[axis] > pos) || (a[axis] > pos && b[axis] < pos) {
            let (lo, hi) = crossing(a, b, axis, pos);
            left = left.union(&Box3 { lo, hi });
            right = right.union(&Box3 { lo, hi });
        }
    }
    (intersect(&left, within), intersect(&right, within))
}

/// [`split_at`] in f32 without the outward rounding, for the binning's estimates only (the
/// split itself goes through [`split_at`]): the binning chops every reference at every slab
/// plane it crosses, and the exact crossings were three quarters of the build (measured on
/// hair, 50,000 triangles, with `perf`).
#[inline]
pub(crate) fn split_estimate(tri: &Corners, axis: usize, pos: f32, within: &Box3) -> (Box3, Box3) {
    let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
    for i in 0..3 {
        let (a, b) = (tri[i], tri[(i + 1) % 3]);
        let (da, db) = (a[axis] - pos, b[axis] - pos);
        if da <= 0.0 {
            left = left.grow(a);
        }
        if da >= 0.0 {
            right = right.grow(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            let p = a + (b - a) * (da / (da - db));
            left = left.grow(p);
            right = right.grow(p);
        }
    }
    (intersect(&left, within), intersect(&right, within))
}

/// Where the edge `a`–`b` crosses the plane, as a box of at most one ulp per axis around the
/// exact point (the plane's own coordinate exactly `pos`).
fn crossing(a: Vec3A, b: Vec3A, axis: usize, pos: f32) -> (Vec3A, Vec3A) {
    let t = (pos as f64 - a[axis] as f64) / (b[axis] as f64 - a[axis] as f64);
    let (mut lo, mut hi) = (Vec3A::ZERO, Vec3A::ZERO);
    for k in 0..3 {
        if k == axis {
            lo[k] = pos;
            hi[k] = pos;
            continue;
        }
        let exact = a[k] as f64 + t * (b[k] as f64 - a[k] as f64);
        let near = exact as f32;
        lo[k] = if (near as f64) > exact {
            near.next_down()
        } else {
            near
        };
        hi[k] = if (near as f64) < exact {
            near.next_up()
        } else {
            near
        };
    }
    (lo, hi)
}

#[cfg(test)]
pub(crate) fn box_of(a: &raybench_geom::Aabb) -> Box3 {
    Box3 {
        lo: a.min.into(),
        hi: a.max.into(),
    }
}

pub(crate) fn intersect(a: &Box3, b: &Box3) -> Box3 {
    Box3 {
        lo: a.lo.max(b.lo),
        hi: a.hi.min(b.hi),
    }
}

/// Whether a box holds at least one point.
pub(crate) fn is_empty(b: &Box3) -> bool {
    b.lo.cmpgt(b.hi).any()
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Vec3;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Corners {
        corners(&Triangle {
            v0: Vec3::from(a),
            v1: Vec3::from(b),
            v2: Vec3::from(c),
        })
    }

    fn whole(t: &Corners) -> Box3 {
        t.iter().fold(Box3::EMPTY, |b, &v| b.grow(v))
    }

    #[test]
    fn a_diagonal_triangle_splits_into_two_tight_halves() {
        let t = tri([0.0, 0.0, 0.0], [4.0, 4.0, 0.0], [4.0, 4.0, 1.0]);
        let (l, r) = split_at(&t, 0, 1.0, &whole(&t));
        assert_eq!(l.lo, Vec3A::new(0.0, 0.0, 0.0));
        assert_eq!(l.hi, Vec3A::new(1.0, 1.0, 0.25));
        assert_eq!(r.lo, Vec3A::new(1.0, 1.0, 0.0));
        assert_eq!(r.hi, Vec3A::new(4.0, 4.0, 1.0));
    }

    #[test]
    fn a_triangle_on_one_side_leaves_the_other_empty() {
        let t = tri([2.0, 0.0, 0.0], [3.0, 1.0, 0.0], [2.5, 0.0, 1.0]);
        let (l, r) = split_at(&t, 0, 1.0, &whole(&t));
        assert!(is_empty(&l));
        assert_eq!(r, whole(&t));
        // A reference already cut to one side of a plane has nothing beyond it.
        let within = Box3 {
            lo: Vec3A::new(2.0, 0.0, 0.0),
            hi: Vec3A::new(2.4, 1.0, 1.0),
        };
        let (l, r) = split_at(&t, 0, 2.5, &within);
        assert_eq!(l.lo, Vec3A::new(2.0, 0.0, 0.0));
        assert_eq!(l.hi, Vec3A::new(2.4, 0.5, 1.0));
        assert!(is_empty(&r));
    }

    /// Crossing points off the f32 grid are rounded outwards: each side's box contains the
    /// exact (f64) crossing point.
    #[test]
    fn crossings_round_outwards() {
        let t = tri([0.0, 0.0, 0.0], [3.0, 1.0, 7.0], [0.0, 1.0, 0.0]);
        let (l, r) = split_at(&t, 0, 1.0, &whole(&t));
        for b in [l, r] {
            assert!(b.lo.y as f64 <= 1.0 / 3.0 && 1.0 / 3.0 <= b.hi.y as f64);
            assert!(b.lo.z as f64 <= 7.0 / 3.0 && 7.0 / 3.0 <= b.hi.z as f64);
        }
        assert_eq!((l.hi.x, r.lo.x), (1.0, 1.0));
    }
}
