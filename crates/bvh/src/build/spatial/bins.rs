//! The search for the best spatial split of a node: per axis, `spatial_bins` equal slabs of the
//! node's box (not of its centroids), each reference chopped into the slabs it crosses (its
//! triangle clipped at every slab plane, [`split_estimate`]), counting where it enters and where it
//! leaves; then one sweep over the slab boundaries evaluates the SAH of cutting every
//! reference at that plane (Stich, Friedrich and Dietrich 2009, section 4.2). A boundary whose
//! cut would duplicate more references than the node's budget allows is not a candidate.

use super::chop::{Corners, corners, is_empty, split_estimate};
use crate::BvhParams;
use crate::build::split::split_cost;
use crate::build::{Box3, PrimRef};
use raybench_geom::TriangleMesh;

/// Upper bound of the `spatial_bins` knob: the slabs live in fixed arrays reused by every node
/// of a task.
pub const MAX_SPATIAL_BINS: usize = 64;

/// A chosen plane `axis = pos`, with the SAH cost and the children's boxes and reference
/// counts the binning estimated (references crossing the plane counted on both sides).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpatialSplit {
    pub axis: usize,
    pub pos: f32,
    pub cost: f64,
    pub left: Box3,
    pub right: Box3,
    pub left_count: usize,
    pub right_count: usize,
}

/// Per axis and slab: the box of the pieces of references inside it, how many references
/// start in it and how many end in it; and the sweep's right-hand sides.
pub(crate) struct SlabBins {
    boxes: [Box3; MAX_SPATIAL_BINS],
    enter: [u32; MAX_SPATIAL_BINS],
    exit: [u32; MAX_SPATIAL_BINS],
    right: [(Box3, u32); MAX_SPATIAL_BINS],
}

impl SlabBins {
    pub(crate) fn new() -> Box<SlabBins> {
        Box::new(SlabBins {
            boxes: [Box3::EMPTY; MAX_SPATIAL_BINS],
            enter: [0; MAX_SPATIAL_BINS],
            exit: [0; MAX_SPATIAL_BINS],
            right: [(Box3::EMPTY, 0); MAX_SPATIAL_BINS],
        })
    }
}

/// The cheapest spatial split of `refs` (whose box is `bounds`) duplicating at most `budget`
/// references; `None` when the box is flat or no plane leaves both sides a reference within
/// the budget. Ties go to the first axis and the leftmost plane, so the result depends on the
/// references alone.
pub(crate) fn best_spatial_split(
    refs: &[PrimRef],
    mesh: &TriangleMesh,
    bounds: &Box3,
    p: &BvhParams,
    slabs: usize,
    budget: usize,
    bins: &mut SlabBins,
) -> Option<SpatialSplit> {
    let parent = bounds.half_area();
    if parent <= 0.0 {
        return None;
    }
    let nb = slabs.clamp(2, MAX_SPATIAL_BINS);
    let n = refs.len();
    let mut best: Option<SpatialSplit> = None;
    for axis in 0..3 {
        let lo = bounds.lo[axis];
        let extent = bounds.hi[axis] - lo;
        if extent <= 0.0 {
            continue;
        }
        let step = extent / nb as f32;
        let plane = |b: usize| lo + step * b as f32;
        let slab = |x: f32| (((x - lo) / step) as usize).min(nb - 1);
        bins.boxes[..nb].fill(Box3::EMPTY);
        bins.enter[..nb].fill(0);
        bins.exit[..nb].fill(0);
        for r in refs {
            let b = r.bounds();
            let (first, last) = (slab(b.lo[axis]), slab(b.hi[axis]));
            bins.enter[first] += 1;
            bins.exit[last] += 1;
            if first == last {
                bins.boxes[first] = bins.boxes[first].union(&b);
                continue;
            }
            chop_into_slabs(
                &corners(&mesh.triangle(r.id() as usize)),
                axis,
                b,
                first..=last,
                &plane,
                &mut bins.boxes,
            );
        }
        let (mut acc, mut count) = (Box3::EMPTY, 0u32);
        for b in (1..nb).rev() {
            acc = acc.union(&bins.boxes[b]);
            count += bins.exit[b];
            bins.right[b] = (acc, count);
        }
        let (mut left, mut left_count) = (Box3::EMPTY, 0u32);
        for b in 1..nb {
            left = left.union(&bins.boxes[b - 1]);
            left_count += bins.enter[b - 1];
            let (right, right_count) = bins.right[b];
            let (lc, rc) = (left_count as usize, right_count as usize);
            if lc == 0 || rc == 0 || lc + rc - n > budget {
                continue;
            }
            let cost = split_cost(p, parent, (left.half_area(), lc), (right.half_area(), rc));
            if best.is_none_or(|s| cost < s.cost) {
                best = Some(SpatialSplit {
                    axis,
                    pos: plane(b),
                    cost,
                    left,
                    right,
                    left_count: lc,
                    right_count: rc,
                });
            }
        }
    }
    best
}

/// Adds the pieces of one reference (box `b`, triangle `tri`) to the slabs `range` it spans
/// on `axis`, cutting it at each plane between them in turn.
fn chop_into_slabs(
    tri: &Corners,
    axis: usize,
    b: Box3,
    range: std::ops::RangeInclusive<usize>,
    plane: &impl Fn(usize) -> f32,
    boxes: &mut [Box3; MAX_SPATIAL_BINS],
) {
    let (first, last) = (*range.start(), *range.end());
    let mut rest = b;
    for (s, slab) in boxes.iter_mut().enumerate().take(last).skip(first) {
        let (piece, beyond) = split_estimate(tri, axis, plane(s + 1), &rest);
        if !is_empty(&piece) {
            *slab = slab.union(&piece);
        }
        if is_empty(&beyond) {
            return;
        }
        rest = beyond;
    }
    boxes[last] = boxes[last].union(&rest);
}
