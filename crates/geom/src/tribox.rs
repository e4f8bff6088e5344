//! Triangle–box overlap: the separating-axis test of Akenine-Möller ("Fast 3D Triangle-Box
//! Overlap Testing", JGT 6(1), 2001), the test uniform grids and octrees use to put a triangle
//! only into the cells it really touches.
//!
//! A triangle and an axis-aligned box are disjoint exactly when their projections onto one of
//! 13 axes are disjoint: the 3 box axes (the triangle's bounding box misses the box), the
//! triangle's normal (the box lies wholly on one side of the triangle's plane), and the 9 cross
//! products of a triangle edge with a box axis. The trade-off against the cheap alternative
//! (insert into every cell of the triangle's bounding box) is about 100 flops per tested cell
//! against far fewer references for long or slanted triangles, which then cost nothing during
//! traversal.
//!
//! Semantics, chosen for insertion:
//! * **Closed box, touching counts.** A triangle that only touches the box — a vertex on a
//!   face, an edge along an edge, the triangle lying in a face's plane — overlaps it. An axis
//!   separates only when the projections are *strictly* apart (as in Akenine-Möller's
//!   `tribox3.c`), so a triangle on a cell boundary goes into both neighbours and a ray running
//!   along the boundary finds it from either side (docs/validation.md, G11 and B16).
//! * **Evaluated in f64.** The f32 vertices are widened exactly; differences of f32 values are
//!   exact in f64 and their products nearly so, so the answer is exact for practical purposes
//!   (the tests check touching cases built on dyadic coordinates, one f32 step apart).
//! * **Degenerate triangles** (zero area: a segment or a point) have a zero normal, so the plane
//!   axis never separates them and they are placed by the box axes and the edge axes alone,
//!   which is the exact segment–box (or point–box) test.
//! * **NaN** makes every comparison false and is treated as separated, so a triangle with a NaN
//!   vertex overlaps no box (never every box, which would blow up an octree;
//!   docs/validation.md, B16).
//!
//! Structures do not call it on the bare cell: they call it on [`conservative_box`], the cell
//! enlarged by [`MARGIN_REL`] of its coordinates' magnitude, so that the f32 arithmetic of a
//! traversal that decides which cell a ray is in can never disagree with insertion by more than
//! the margin (a few f32 steps). A slightly enlarged box only adds references; it never loses a
//! triangle from a cell a ray could hit it in.

use crate::{Aabb, Triangle};
use glam::DVec3;

/// Relative margin of [`conservative_box`]: 2^-20, eight f32 steps of the box's largest
/// coordinate magnitude (f32 has 2^-23 relative spacing). Traversals compute cell crossings in
/// f32 from planes rounded to f32, so they see a boundary at most a few steps from where
/// insertion put it; eight steps cover that with room to spare and add almost no references
/// (at the origin the margin is 1e-6 of a cell).
pub const MARGIN_REL: f64 = 1.0 / (1u64 << 20) as f64;

/// The closed box `[lo, hi]` enlarged on every side by [`MARGIN_REL`] times the largest
/// coordinate magnitude of its corners. A child box's margin is never larger than its
/// parent's, so enlarged children stay inside their enlarged parent.
#[inline]
pub fn conservative_box(lo: DVec3, hi: DVec3) -> (DVec3, DVec3) {
    let m = lo.abs().max(hi.abs()).max_element() * MARGIN_REL;
    (lo - DVec3::splat(m), hi + DVec3::splat(m))
}

/// True when the triangle overlaps (or touches) the closed box. One-off form of [`TriBox`].
pub fn tri_box_overlap(tri: &Triangle, b: &Aabb) -> bool {
    TriBox::new(tri).overlaps(b.min.as_dvec3(), b.max.as_dvec3())
}

/// A triangle prepared for many overlap tests against different boxes: vertices, edges, normal
/// and bounds in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriBox {
    v: [DVec3; 3],
    e: [DVec3; 3],
    n: DVec3,
    lo: DVec3,
    hi: DVec3,
}

impl TriBox {
    pub fn new(t: &Triangle) -> TriBox {
        let v = [t.v0, t.v1, t.v2].map(|p| p.as_dvec3());
        let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
        TriBox {
            v,
            e,
            n: e[0].cross(e[1]),
            lo: v[0].min(v[1]).min(v[2]),
            hi: v[0].max(v[1]).max(v[2]),
        }
    }

    /// The corners (f64, exact).
    #[inline]
    pub fn vertices(&self) -> &[DVec3; 3] {
        &self.v
    }

    /// The triangle's bounding box (f64, exact).
    #[inline]
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// The full 13-axis test against the closed box `[lo, hi]`.
    #[inline]
    pub fn overlaps(&self, lo: DVec3, hi: DVec3) -> bool {
        self.bounds_overlap(lo, hi) && self.plane_and_edges_overlap(lo, hi)
    }

    /// The 3 box axes alone: the triangle's bounding box meets the closed box.
    #[inline]
    pub fn bounds_overlap(&self, lo: DVec3, hi: DVec3) -> bool {
        self.lo.cmple(hi).all() && self.hi.cmpge(lo).all()
    }

    /// The 10 remaining axes (normal, 9 edge cross products), for callers that already know the
    /// bounding boxes meet. Together with [`TriBox::bounds_overlap`] it is [`TriBox::overlaps`].
    #[inline]
    pub fn plane_and_edges_overlap(&self, lo: DVec3, hi: DVec3) -> bool {
        let c = lo * 0.5 + hi * 0.5;
        let h = hi * 0.5 - lo * 0.5;
        let [v0, v1, v2] = self.v.map(|p| p - c);
        // Normal: the box's projection radius against the plane's offset. Written so NaN
        // separates.
        let d = self.n.dot(v0);
        let r = h.dot(self.n.abs());
        if !(d <= r && d >= -r) {
            return false;
        }
        self.edges_overlap([v0, v1, v2], h, [true; 3])
    }

    /// The 3 axes `edge × unit(axis)` alone: the projections of the triangle and the box along
    /// `axis` overlap, as 2D shapes. For a triangle known to lie within the box's slab on
    /// `axis` (and whose bounding box meets the box), that is the whole overlap test. Always
    /// inlined: grid insertion calls it for every candidate cell, from two loops (the full scan
    /// and the clipped one), and a call costs about as much as the test of a flat triangle.
    #[inline(always)]
    pub fn edges_overlap_along(&self, lo: DVec3, hi: DVec3, axis: usize) -> bool {
        let c = lo * 0.5 + hi * 0.5;
        let h = hi * 0.5 - lo * 0.5;
        let mut which = [false; 3];
        which[axis] = true;
        self.edges_overlap(self.v.map(|p| p - c), h, which)
    }

    /// The edge × box-axis tests for the box axes selected by `which`, on vertices relative to
    /// the box centre and the box's half size `h`.
    #[inline(always)]
    fn edges_overlap(&self, verts: [DVec3; 3], h: DVec3, which: [bool; 3]) -> bool {
        // Edge × box axis. For edge k the two vertices of the edge project to the same value,
        // so the projections are of its start vertex and the opposite vertex.
        for k in 0..3 {
            let e = self.e[k];
            let p = verts[k];
            let q = verts[(k + 2) % 3];
            // e × x = (0, e.z, -e.y)
            if which[0]
                && separated(
                    e.z * p.y - e.y * p.z,
                    e.z * q.y - e.y * q.z,
                    h.y * e.z.abs() + h.z * e.y.abs(),
                )
            {
                return false;
            }
            // e × y = (-e.z, 0, e.x)
            if which[1]
                && separated(
                    e.x * p.z - e.z * p.x,
                    e.x * q.z - e.z * q.x,
                    h.x * e.z.abs() + h.z * e.x.abs(),
                )
            {
                return false;
            }
            // e × z = (e.y, -e.x, 0)
            if which[2]
                && separated(
                    e.y * p.x - e.x * p.y,
                    e.y * q.x - e.x * q.y,
                    h.x * e.y.abs() + h.y * e.x.abs(),
                )
            {
                return false;
            }
        }
        true
    }
}

/// The projections `a`, `b` of the triangle and `[-r, r]` of the box are strictly apart (NaN:
/// apart).
#[inline(always)]
fn separated(a: f64, b: f64, r: f64) -> bool {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    !(lo <= r && hi >= -r)
}

#[cfg(test)]
mod tests;
