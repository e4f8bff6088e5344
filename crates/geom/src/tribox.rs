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
    /// `axis` (and whose bounding box meets the box), that is the whole overlap test.
    #[inline]
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
mod tests {
    use super::*;
    use glam::Vec3;

    use crate::rng::SplitMix64 as Rng;

    fn t(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(a.into(), b.into(), c.into())
    }

    fn unit() -> (DVec3, DVec3) {
        (DVec3::ZERO, DVec3::ONE)
    }

    fn ov(tri: &Triangle, (lo, hi): (DVec3, DVec3)) -> bool {
        TriBox::new(tri).overlaps(lo, hi)
    }

    /// Sutherland–Hodgman in f64: clips the triangle (as a polygon, degenerate ones included)
    /// against the six half-spaces of the closed box; a non-empty result means overlap.
    fn clip_nonempty(tri: &Triangle, lo: DVec3, hi: DVec3) -> bool {
        let mut poly: Vec<DVec3> = [tri.v0, tri.v1, tri.v2]
            .iter()
            .map(|p| p.as_dvec3())
            .collect();
        for axis in 0..3 {
            for (bound, keep_above) in [(lo[axis], true), (hi[axis], false)] {
                let inside = |p: DVec3| {
                    if keep_above {
                        p[axis] >= bound
                    } else {
                        p[axis] <= bound
                    }
                };
                let mut out = Vec::with_capacity(poly.len() + 2);
                for i in 0..poly.len() {
                    let a = poly[i];
                    let b = poly[(i + 1) % poly.len()];
                    match (inside(a), inside(b)) {
                        (true, true) => out.push(b),
                        (true, false) => out.push(cross_at(a, b, axis, bound)),
                        (false, true) => {
                            out.push(cross_at(a, b, axis, bound));
                            out.push(b);
                        }
                        (false, false) => {}
                    }
                }
                poly = out;
                if poly.is_empty() {
                    return false;
                }
            }
        }
        true
    }

    /// The point of segment a→b on the plane `p[axis] == bound`, snapped onto the plane.
    fn cross_at(a: DVec3, b: DVec3, axis: usize, bound: f64) -> DVec3 {
        let s = (bound - a[axis]) / (b[axis] - a[axis]);
        let mut p = a + (b - a) * s;
        p[axis] = bound;
        p
    }

    fn grow(lo: DVec3, hi: DVec3, f: f64) -> (DVec3, DVec3) {
        let pad = (hi - lo) * f + DVec3::splat(f);
        (lo - pad, hi + pad)
    }

    /// Random boxes and triangles of mixed sizes around them: SAT agrees with clipping, up to
    /// an ε band (clipping itself rounds): overlap ⇒ the ε-enlarged box clips non-empty, and no
    /// overlap ⇒ the ε-shrunk box clips empty. Also the sampled points of the triangle inside
    /// the box imply overlap.
    #[test]
    fn agrees_with_clipping_on_seeded_random_cases() {
        let mut rng = Rng::new(0x5eed_7b0c);
        let (mut hits, mut misses) = (0, 0);
        for case in 0..100_000 {
            let lo = rng.unit_vec() * 2.0 - 1.0;
            let hi = lo + rng.unit_vec() * 0.8 + 0.01;
            let size = [0.05f32, 0.3, 1.5][case % 3];
            // Centred around the box, from well inside to well outside it.
            let c = lo + (hi - lo) * (rng.unit_vec() * 2.0 - 0.5) + (rng.unit_vec() - 0.5) * size;
            let tri = Triangle::new(
                c + (rng.unit_vec() - 0.5) * size,
                c + (rng.unit_vec() - 0.5) * size,
                c + (rng.unit_vec() - 0.5) * size,
            );
            let (blo, bhi) = (lo.as_dvec3(), hi.as_dvec3());
            let sat = ov(&tri, (blo, bhi));
            let (glo, ghi) = grow(blo, bhi, 1e-9);
            let (slo, shi) = grow(blo, bhi, -1e-9);
            if sat {
                hits += 1;
                assert!(clip_nonempty(&tri, glo, ghi), "case {case}: {tri:?}");
            } else {
                misses += 1;
                assert!(!clip_nonempty(&tri, slo, shi), "case {case}: {tri:?}");
                for i in 0..=8 {
                    for j in 0..=8 - i {
                        let p = tri.point_at(i as f32 / 8.0, j as f32 / 8.0).as_dvec3();
                        assert!(
                            !(p.cmpge(blo).all() && p.cmple(bhi).all()),
                            "case {case}: sample {p} inside the box but no overlap"
                        );
                    }
                }
            }
        }
        // Both answers are well represented.
        assert!(hits > 10_000 && misses > 10_000, "{hits} / {misses}");
    }

    #[test]
    fn agrees_with_clipping_on_degenerate_triangles() {
        let mut rng = Rng::new(0x5eed_de9e);
        let (mut hits, mut misses) = (0, 0);
        for case in 0..50_000 {
            let (blo, bhi) = unit();
            let a = rng.unit_vec() * 3.0 - 1.0;
            let b = rng.unit_vec() * 3.0 - 1.0;
            let tri = match case % 3 {
                0 => Triangle::new(a, a, a),                 // point
                1 => Triangle::new(a, b, b),                 // segment (repeated vertex)
                _ => Triangle::new(a, b, a * 0.5 + b * 0.5), // collinear, midpoint third
            };
            let sat = ov(&tri, (blo, bhi));
            let (glo, ghi) = grow(blo, bhi, 1e-9);
            let (slo, shi) = grow(blo, bhi, -1e-9);
            if sat {
                hits += 1;
                assert!(clip_nonempty(&tri, glo, ghi), "case {case}: {tri:?}");
            } else {
                misses += 1;
                assert!(!clip_nonempty(&tri, slo, shi), "case {case}: {tri:?}");
            }
        }
        assert!(hits > 5_000 && misses > 5_000, "{hits} / {misses}");
    }

    /// One f32 step: 2^-23 at 1.0 (coordinates below are in [0.5, 4), so it is exact there).
    const STEP: f32 = 1.0 / (1u32 << 21) as f32;

    /// A triangle as a function of how far it is moved off the box.
    type MovedTriangle = Box<dyn Fn(f32) -> Triangle>;

    #[test]
    fn touching_counts_and_one_step_away_does_not() {
        let b = unit();
        // (touching triangle, the same moved STEP away)
        let cases: Vec<(&str, MovedTriangle)> = vec![
            (
                "vertex on a face",
                Box::new(|s| t([1.0 + s, 0.5, 0.5], [2.0, 0.25, 0.5], [2.0, 0.75, 0.75])),
            ),
            (
                "edge along a face",
                Box::new(|s| t([1.0 + s, 0.25, 0.5], [1.0 + s, 0.75, 0.5], [2.0, 0.5, 0.5])),
            ),
            (
                "triangle in a face's plane",
                Box::new(|s| {
                    t(
                        [1.0 + s, 0.25, 0.25],
                        [1.0 + s, 0.75, 0.25],
                        [1.0 + s, 0.5, 3.0],
                    )
                }),
            ),
            (
                "vertex on a box corner",
                Box::new(|s| {
                    let c = 1.0 + s;
                    t([c, c, c], [2.0, 3.0, 2.0], [3.0, 2.0, 3.0])
                }),
            ),
            (
                // The line x + y = 2 (+s) in z = 0.5 touches the box edge x = y = 1 at one point;
                // the triangle lies beyond it. Only an edge-cross axis separates the moved one.
                "edge across a box edge",
                Box::new(|s| t([2.0 + s, 0.0, 0.5], [0.0, 2.0 + s, 0.5], [2.0, 2.0, 0.5])),
            ),
            (
                // Plane x + y + z = 3 (+s) through the corner (1,1,1): only the normal separates.
                "plane through a box corner",
                Box::new(|s| {
                    let k = 3.0 + s;
                    t([k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k])
                }),
            ),
            (
                "segment touching an edge",
                Box::new(|s| {
                    t(
                        [2.0 + s, 0.0, 0.5],
                        [0.0, 2.0 + s, 0.5],
                        [0.0, 2.0 + s, 0.5],
                    )
                }),
            ),
            (
                "point on a corner",
                Box::new(|s| {
                    let c = 1.0 + s;
                    t([c, c, c], [c, c, c], [c, c, c])
                }),
            ),
        ];
        for (name, make) in &cases {
            // 4 STEPs: the smallest distance still exact after the sums above (e.g. 2 + s).
            assert!(ov(&make(0.0), b), "{name}: touching must count as overlap");
            assert!(
                !ov(&make(4.0 * STEP), b),
                "{name}: {} away must not",
                4.0 * STEP
            );
            assert!(
                ov(&make(-4.0 * STEP), b),
                "{name}: {} inside must",
                4.0 * STEP
            );
        }
    }

    #[test]
    fn inside_containing_and_crossing() {
        let b = unit();
        // Wholly inside; a huge triangle containing the box's cross-section; a long needle
        // through the box with every vertex outside.
        assert!(ov(&t([0.2, 0.2, 0.2], [0.8, 0.2, 0.3], [0.3, 0.7, 0.6]), b));
        assert!(ov(
            &t(
                [-100.0, -100.0, 0.5],
                [100.0, -100.0, 0.5],
                [0.0, 100.0, 0.5]
            ),
            b
        ));
        assert!(ov(
            &t([-5.0, 0.5, 0.5], [5.0, 0.5, 0.5], [5.0, 0.5, 0.50001]),
            b
        ));
        // The same needle just above the box.
        assert!(!ov(
            &t([-5.0, 1.5, 0.5], [5.0, 1.5, 0.5], [5.0, 1.5, 0.50001]),
            b
        ));
        // A flat (zero-thickness) box is still a box.
        let flat = (DVec3::new(0.0, 0.0, 0.5), DVec3::new(1.0, 1.0, 0.5));
        assert!(ov(
            &t([0.5, 0.5, 0.0], [0.6, 0.5, 1.0], [0.5, 0.6, 1.0]),
            flat
        ));
        assert!(!ov(
            &t([0.5, 0.5, 0.6], [0.6, 0.5, 1.0], [0.5, 0.6, 1.0]),
            flat
        ));
        // A point box.
        let point = (DVec3::splat(0.25), DVec3::splat(0.25));
        assert!(ov(
            &t([0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.5, 0.0, 0.0]),
            point
        ));
        assert!(!ov(
            &t([0.0, 0.0, 0.0], [0.5, 0.5, 0.6], [0.5, 0.0, 0.0]),
            point
        ));
    }

    #[test]
    fn nan_overlaps_nothing() {
        let nan = t([f32::NAN, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.6, 0.5]);
        assert!(!ov(&nan, unit()));
        assert!(!ov(&nan, (DVec3::splat(-1e30), DVec3::splat(1e30))));
    }

    /// Scaling everything by a power of two is exact, so the answers must not change, at
    /// 2^-60 (1e-18, near the bottom of the normal f32 range once multiplied) and 2^60 (1e18,
    /// near Embree's limit).
    #[test]
    fn scale_invariant_from_tiny_to_huge() {
        let mut rng = Rng::new(0x5eed_5ca1);
        for case in 0..20_000 {
            let lo = rng.unit_vec() * 2.0 - 1.0;
            let hi = lo + rng.unit_vec() * 0.5;
            let c = rng.unit_vec() * 2.0 - 1.0;
            let tri = Triangle::new(
                c + (rng.unit_vec() - 0.5) * 0.7,
                c + (rng.unit_vec() - 0.5) * 0.7,
                c + (rng.unit_vec() - 0.5) * 0.7,
            );
            let base = ov(&tri, (lo.as_dvec3(), hi.as_dvec3()));
            for k in [-60i32, 60] {
                let s = 2f32.powi(k);
                let scaled = Triangle::new(tri.v0 * s, tri.v1 * s, tri.v2 * s);
                assert_eq!(
                    ov(&scaled, ((lo * s).as_dvec3(), (hi * s).as_dvec3())),
                    base,
                    "case {case} at 2^{k}"
                );
            }
        }
    }

    #[test]
    fn far_from_origin_touching_is_exact() {
        // At 1e5 an f32 step is 2^-7: a triangle one step off the face is separated.
        let lo = DVec3::splat(100_000.0);
        let hi = DVec3::splat(100_001.0);
        let x = 100_001.0f32;
        let step = 1.0 / 128.0;
        let at = |s: f32| {
            t(
                [x + s, 1e5 + 0.5, 1e5 + 0.5],
                [x + 1.0, 1e5, 1e5],
                [x + 1.0, 1e5 + 1.0, 1e5 + 1.0],
            )
        };
        assert!(ov(&at(0.0), (lo, hi)));
        assert!(!ov(&at(step), (lo, hi)));
    }

    #[test]
    fn conservative_box_grows_by_the_relative_margin() {
        let (lo, hi) = conservative_box(DVec3::new(-2.0, 0.0, 1.0), DVec3::new(4.0, 1.0, 1.0));
        let m = 4.0 * MARGIN_REL;
        assert_eq!(lo, DVec3::new(-2.0 - m, -m, 1.0 - m));
        assert_eq!(hi, DVec3::new(4.0 + m, 1.0 + m, 1.0 + m));
        // A child's enlarged box stays inside its parent's.
        let (plo, phi) = conservative_box(DVec3::splat(-8.0), DVec3::splat(8.0));
        let (clo, chi) = conservative_box(DVec3::splat(0.0), DVec3::splat(8.0));
        assert!(clo.cmpge(plo).all() && chi.cmple(phi).all());
    }

    /// For a triangle inside the box's slab on one axis, the 3 edge axes along it decide.
    #[test]
    fn edges_along_an_axis_decide_within_a_slab() {
        let mut rng = Rng::new(0x5eed_2d2d);
        let mut both = [0usize; 2];
        for case in 0..30_000 {
            let axis = case % 3;
            let lo = rng.unit_vec() * 2.0 - 1.0;
            let hi = lo + rng.unit_vec() * 0.6 + 0.01;
            let c = lo + (hi - lo) * (rng.unit_vec() * 2.0 - 0.5);
            let mut v = [0; 3].map(|_| c + (rng.unit_vec() - 0.5) * 0.8);
            for p in &mut v {
                p[axis] = lo[axis] + (hi[axis] - lo[axis]) * rng.unit();
            }
            let tb = TriBox::new(&Triangle::new(v[0], v[1], v[2]));
            let (blo, bhi) = (lo.as_dvec3(), hi.as_dvec3());
            let full = tb.overlaps(blo, bhi);
            assert_eq!(
                tb.bounds_overlap(blo, bhi) && tb.edges_overlap_along(blo, bhi, axis),
                full,
                "case {case}"
            );
            both[full as usize] += 1;
        }
        assert!(both[0] > 3000 && both[1] > 3000, "{both:?}");
    }

    #[test]
    fn aabb_form_matches() {
        let tri = t([0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [0.5, 2.0, 0.5]);
        assert!(tri_box_overlap(&tri, &Aabb::new(Vec3::ZERO, Vec3::ONE)));
        assert!(!tri_box_overlap(
            &tri,
            &Aabb::new(Vec3::splat(1.5), Vec3::splat(2.0))
        ));
    }
}
