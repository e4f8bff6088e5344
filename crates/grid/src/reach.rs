//! The cells a large triangle can reach, found by clipping it to slabs of cells.
//!
//! A long, slanted triangle (a hair strand, a ground plane, one of many copies of a large
//! triangle) overlaps a thin sheet of the cells of its bounding box. Testing every cell of the
//! box costs a test per box cell for a reference per sheet cell: for triangles that span the
//! grid that is quadratic in the resolution, and with many such triangles the build spends
//! minutes on tests that fail. Clipping the triangle to the slab of one layer of cells along
//! z gives the part of it in that layer; that part's vertices within the slab of one row along
//! y and its edges' crossings with the row's planes give the x extent the triangle has in the
//! row (without building the row's part), so the candidates number about the references plus
//! a few per row.
//!
//! The clip only narrows the candidates; the triangle–box test still decides every one, so the
//! references are exactly those of the full scan (the unit tests compare the two). To leave out
//! no cell the test accepts, the slabs are the enlarged cells' widened by one more insertion
//! margin, and every clipped extent is widened by a margin again before it picks cells: the
//! clip's f64 rounding (about 2^-52 of a coordinate) is far below the margin (2^-20 of the
//! largest coordinate).

use crate::build::{Layout, f32_down, f32_up};
use raybench_geom::DVec3;
use raybench_geom::tribox::TriBox;

/// Candidate cells in a triangle's bounding box from which insertion clips the triangle to
/// each layer and row of cells instead of testing every cell of the box: below it, the
/// clipping costs more than the tests it saves.
pub(crate) const REACH_FROM: u64 = 256;

impl Layout {
    /// The tests of [`Layout::insert`] for a triangle whose bounding box covers many cells:
    /// only the cells the triangle's part in each layer and row can reach (see
    /// [`crate::reach`]). Out of line, so the common small case keeps its tight loop.
    #[inline(never)]
    pub(crate) fn insert_reached(
        &self,
        tb: &TriBox,
        r: [(u32, u32); 3],
        flat: Option<usize>,
        mut emit: impl FnMut(usize),
    ) {
        let whole = Piece::triangle(tb.vertices());
        for z in r[2].0..=r[2].1 {
            let (lo, hi) = self.slab(2, z);
            let layer = match r[2].0 == r[2].1 {
                true => whole,
                false => whole.clip(2, lo, hi).unwrap_or(whole),
            };
            let Some(ys) = self.reach(layer.extent(1), 1, r[1]) else {
                continue;
            };
            for y in ys.0..=ys.1 {
                let (lo, hi) = self.slab(1, y);
                let row = match ys.0 == ys.1 {
                    true => layer.extent(0),
                    false => layer.extent_within(1, lo, hi, 0),
                };
                let Some(xs) = self.reach(row, 0, r[0]) else {
                    continue;
                };
                for x in xs.0..=xs.1 {
                    if self.overlaps(tb, flat, [x, y, z]) {
                        emit(self.index([x, y, z]));
                    }
                }
            }
        }
    }

    /// Cell `c`'s slab along `axis` for clipping: the enlarged cell's, widened by one more
    /// margin (see [`crate::reach`]).
    #[inline]
    fn slab(&self, axis: usize, c: u32) -> (f64, f64) {
        let p = &self.planes[axis];
        let m = 2.0 * self.margin;
        (p[c as usize] - m, p[c as usize + 1] + m)
    }

    /// The cells along `axis`, within `within`, that a clipped part with the extent `e` along
    /// it can reach (the extent widened by a margin: see [`crate::reach`]); `None` for none.
    #[inline]
    fn reach(&self, e: Option<(f64, f64)>, axis: usize, within: (u32, u32)) -> Option<(u32, u32)> {
        let (lo, hi) = e?;
        let m = self.margin;
        let (first, last) = self.range(axis, f32_down(lo - m), f32_up(hi + m));
        let (first, last) = (first.max(within.0), last.min(within.1));
        (first <= last).then_some((first, last))
    }
}

/// The most vertices a piece holds. A triangle clipped to one slab has at most five: its
/// vertices beyond either plane form one run around it, replaced by two crossings, so each
/// plane adds at most one vertex. The room beyond that is for safety; a piece that would
/// still overflow is reported and its caller keeps the unclipped candidates.
const CAPACITY: usize = 8;

/// A convex polygon: a triangle, or the part of one within a slab.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    v: [DVec3; CAPACITY],
    n: usize,
}

impl Piece {
    pub fn triangle(v: &[DVec3; 3]) -> Piece {
        let mut p = Piece {
            v: [DVec3::ZERO; CAPACITY],
            n: 3,
        };
        p.v[..3].copy_from_slice(v);
        p
    }

    /// The part of the piece with `lo <= p[axis] <= hi` (Sutherland–Hodgman against the
    /// slab's two planes); `None` when it has more vertices than a piece holds.
    pub fn clip(&self, axis: usize, lo: f64, hi: f64) -> Option<Piece> {
        self.clip_plane(axis, lo, false)?.clip_plane(axis, hi, true)
    }

    fn clip_plane(&self, axis: usize, at: f64, keep_below: bool) -> Option<Piece> {
        let inside = |p: DVec3| {
            if keep_below {
                p[axis] <= at
            } else {
                p[axis] >= at
            }
        };
        let mut out = Piece {
            v: [DVec3::ZERO; CAPACITY],
            n: 0,
        };
        let mut push = |p: DVec3| -> Option<()> {
            *out.v.get_mut(out.n)? = p;
            out.n += 1;
            Some(())
        };
        for i in 0..self.n {
            let a = self.v[i];
            let b = self.v[(i + 1) % self.n];
            let (ia, ib) = (inside(a), inside(b));
            if ia {
                push(a)?;
            }
            if ia != ib {
                // The crossing, put exactly on the plane.
                let mut p = crossing(a, b, axis, at);
                p[axis] = at;
                push(p)?;
            }
        }
        Some(out)
    }

    /// The piece's extent along `axis`, or `None` when it is empty.
    pub fn extent(&self, axis: usize) -> Option<(f64, f64)> {
        self.v[..self.n]
            .iter()
            .fold(None, |e, p| Some(grow(e, p[axis])))
    }

    /// The extent along `along` of the piece's part with `lo <= p[axis] <= hi`, or `None` when
    /// that part is empty; without building the part: its vertices are the piece's vertices
    /// within the slab and the crossings of its edges with the two planes.
    pub fn extent_within(&self, axis: usize, lo: f64, hi: f64, along: usize) -> Option<(f64, f64)> {
        let mut e = None;
        for i in 0..self.n {
            let a = self.v[i];
            let b = self.v[(i + 1) % self.n];
            if lo <= a[axis] && a[axis] <= hi {
                e = Some(grow(e, a[along]));
            }
            for at in [lo, hi] {
                if (a[axis] < at && at < b[axis]) || (b[axis] < at && at < a[axis]) {
                    e = Some(grow(e, crossing(a, b, axis, at)[along]));
                }
            }
        }
        e
    }
}

/// Where the segment from `a` to `b` crosses the plane `p[axis] = at` (their coordinates on
/// `axis` lie on either side of it, so they differ: no division by zero).
#[inline]
fn crossing(a: DVec3, b: DVec3, axis: usize, at: f64) -> DVec3 {
    let t = (at - a[axis]) / (b[axis] - a[axis]);
    a + (b - a) * t
}

#[inline]
fn grow(e: Option<(f64, f64)>, x: f64) -> (f64, f64) {
    match e {
        Some((lo, hi)) => (lo.min(x), hi.max(x)),
        None => (x, x),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::rng::SplitMix64;
    use raybench_geom::{Triangle, Vec3};

    /// The cells of `tri` with the clipping from `reach_from` candidates, in emitted order.
    fn cells(layout: &Layout, tri: &Triangle, clipped: bool, reach_from: u64) -> Vec<usize> {
        let mut out = Vec::new();
        if clipped {
            layout.insert::<true>(tri, reach_from, |c| out.push(c));
        } else {
            layout.insert::<false>(tri, reach_from, |c| out.push(c));
        }
        out
    }

    /// Long, slanted, axis-aligned, degenerate and touching triangles, in grids of several
    /// shapes (one of them flat, one a cell grid the triangles cross), give the same cells in
    /// the same order with the clipping as with a test of every cell of the bounding box.
    #[test]
    fn clipping_keeps_exactly_the_cells_of_the_full_scan() {
        let mut rng = SplitMix64::new(27);
        let layouts = [
            (DVec3::ZERO, DVec3::ONE, [9, 7, 11], false),
            (
                DVec3::splat(-3.0),
                DVec3::new(5.0, 2.0, 4.0),
                [16, 5, 9],
                false,
            ),
            (
                DVec3::new(0.0, 0.0, 0.5),
                DVec3::new(1.0, 1.0, 0.5),
                [12, 12, 1],
                false,
            ),
            (DVec3::splat(0.25), DVec3::splat(0.75), [6, 8, 5], true),
        ];
        let mut narrowed = 0;
        for (lo, hi, res, clipped) in layouts {
            let margin = lo.abs().max(hi.abs()).max_element() * raybench_geom::tribox::MARGIN_REL;
            let layout = Layout::over(lo, hi, res, margin);
            let (lo, hi) = (lo.as_vec3(), hi.as_vec3());
            let (from, to) = if clipped {
                (Vec3::ZERO, Vec3::ONE)
            } else {
                (lo, hi)
            };
            let planes: [Vec<f32>; 3] = std::array::from_fn(|a| layout.f32_planes(a));
            for case in 0..3000 {
                let mut p = || rng.point_in(from, to);
                let mut t = Triangle::new(p(), p(), p());
                match case % 6 {
                    // a needle: two corners close together
                    1 => t.v2 = t.v1 + (t.v2 - t.v1) * 1e-3,
                    // in a plane of constant z
                    2 => (t.v1.z, t.v2.z) = (t.v0.z, t.v0.z),
                    // a corner exactly on a cell plane
                    3 => t.v0.x = planes[0][case % planes[0].len()],
                    // a segment: a zero-area triangle
                    4 => t.v2 = t.v0 + (t.v1 - t.v0) * 0.5,
                    _ => {}
                }
                t = Triangle::new(
                    t.v0.clamp(from, to),
                    t.v1.clamp(from, to),
                    t.v2.clamp(from, to),
                );
                // A cell grid only gets the triangles that meet its (enlarged) box.
                let m = DVec3::splat(margin);
                if clipped && !TriBox::new(&t).overlaps(lo.as_dvec3() - m, hi.as_dvec3() + m) {
                    continue;
                }
                let full = cells(&layout, &t, clipped, u64::MAX);
                let fast = cells(&layout, &t, clipped, 0);
                assert_eq!(fast, full, "layout {res:?}, triangle {case}: {t:?}");
                narrowed += usize::from(!full.is_empty());
            }
        }
        assert!(
            narrowed > 6000,
            "too few triangles reached any cell: {narrowed}"
        );
    }

    #[test]
    fn a_slab_through_a_triangle_cuts_a_quadrilateral() {
        let t = Piece::triangle(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(0.0, 4.0, 0.0),
        ]);
        let band = t.clip(1, 1.0, 2.0).unwrap();
        assert_eq!(band.n, 4);
        assert_eq!(band.extent(1), Some((1.0, 2.0)));
        // At y = 1 the triangle reaches x = 3; at y = 2, x = 2.
        assert_eq!(band.extent(0), Some((0.0, 3.0)));
    }

    #[test]
    fn a_slab_beside_a_triangle_leaves_nothing() {
        let t = Piece::triangle(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 1.0),
        ]);
        assert_eq!(t.clip(2, 1.5, 3.0).unwrap().extent(0), None);
        assert_eq!(t.clip(0, -3.0, -0.5).unwrap().extent(2), None);
    }

    #[test]
    fn a_degenerate_triangle_clips_to_its_segment() {
        // All three corners on one segment from (0,0,0) to (2,2,2).
        let t = Piece::triangle(&[DVec3::ZERO, DVec3::splat(2.0), DVec3::splat(1.0)]);
        let piece = t.clip(0, 0.5, 1.5).unwrap();
        assert_eq!(piece.extent(1), Some((0.5, 1.5)));
        assert_eq!(piece.extent(2), Some((0.5, 1.5)));
    }
}
