//! The three ways to choose a split. Each takes a node's range of [`PrimRef`]s, reorders it so
//! that the left child's triangles come first, and returns where the right child starts with
//! both children's bounds — or `None` when it finds no way (or no profitable way) to separate
//! the centroids; `build` then decides between a leaf and a forced cut.

use super::prim::{Box3, PrimRef, Ranged};
use crate::BvhParams;
use crate::simd::F4;
use glam::Vec3A;
use rayon::prelude::*;

/// Binning passes over at least this many triangles run on rayon (measured on the dragon:
/// below ~64k the fork-join overhead outweighs the pass).
pub(crate) const PARALLEL_BINNING: usize = 65_536;

/// Upper bound of the `bins` knob: bins live in fixed arrays on the stack, so binning a node
/// allocates nothing.
pub const MAX_BINS: usize = 64;

/// A chosen split: `refs[..mid]` go left.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Split {
    pub mid: usize,
    pub left: Ranged,
    pub right: Ranged,
}

impl Split {
    /// Cuts `refs` at `mid` as they are ordered, measuring both sides.
    pub(crate) fn at(refs: &[PrimRef], mid: usize) -> Split {
        Split {
            mid,
            left: Ranged::of(&refs[..mid], PARALLEL_BINNING),
            right: Ranged::of(&refs[mid..], PARALLEL_BINNING),
        }
    }
}

/// The SAH cost of splitting a range with box area `parent` into `(area, count)` halves,
/// relative to intersecting every triangle (MacDonald and Booth 1990). Areas may be half
/// areas: only their ratios matter.
fn split_cost(p: &BvhParams, parent: f64, left: (f64, usize), right: (f64, usize)) -> f64 {
    p.traversal_cost as f64
        + p.intersection_cost as f64 * (left.0 * blocks(p, left.1) + right.0 * blocks(p, right.1))
            / parent
}

/// The triangle tests a leaf of `n` costs: `n` rounded up to whole packets of `leaf_block`.
fn blocks(p: &BvhParams, n: usize) -> f64 {
    let block = p.leaf_block.max(1) as usize;
    n.div_ceil(block) as f64 * block as f64
}

/// Whether the best split is worth taking: always when the range is too big for a leaf,
/// otherwise only when it is cheaper than intersecting every triangle.
fn worth_splitting(p: &BvhParams, n: usize, best_cost: f64) -> bool {
    n > p.max_leaf_size as usize || best_cost < p.intersection_cost as f64 * blocks(p, n)
}

/// Object median: the textbook baseline. Splits any range larger than a leaf at the median
/// centroid along the longest axis of the centroid bounds (`select_nth_unstable`, O(n) per
/// level, O(n log n) in all). Ignores triangle sizes entirely, so it makes balanced trees whose
/// boxes overlap more than SAH trees'. `None` when the range fits in a leaf or every centroid is
/// the same point.
pub(crate) fn median_split(refs: &mut [PrimRef], r: &Ranged, p: &BvhParams) -> Option<Split> {
    let extent = r.centroids.extent();
    if refs.len() <= p.max_leaf_size as usize || extent.max_element() <= 0.0 {
        return None;
    }
    let axis = largest_axis(extent);
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| by_centroid(a, b, axis));
    Some(Split::at(refs, mid))
}

fn largest_axis(e: Vec3A) -> usize {
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

/// Centroid order on `axis`, ties by mesh index, so the order (and the tree) is deterministic.
fn by_centroid(a: &PrimRef, b: &PrimRef, axis: usize) -> std::cmp::Ordering {
    a.centroid2()[axis]
        .total_cmp(&b.centroid2()[axis])
        .then(a.id().cmp(&b.id()))
}

/// Full-sweep SAH (the classic O(n log² n) builder; MacDonald and Booth 1990, as in Wald,
/// Boulos and Shirley 2007 "sweep"): for each axis, sort the range by centroid, accumulate
/// suffix box areas right to left, then sweep left to right evaluating every one of the n - 1
/// split positions. The best split the SAH can find among object partitions by sorted
/// centroid, at the price of three sorts per node; the reference the binned builder is judged
/// against ("within 3 %").
pub(crate) fn sweep_split(refs: &mut [PrimRef], r: &Ranged, p: &BvhParams) -> Option<Split> {
    let n = refs.len();
    let parent = r.bounds.half_area();
    if parent <= 0.0 {
        return None;
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, position)
    let mut sorted = refs.to_vec();
    let mut suffix = vec![0.0f64; n];
    for axis in 0..3 {
        sorted.sort_unstable_by(|a, b| by_centroid(a, b, axis));
        let mut acc = Box3::EMPTY;
        for i in (1..n).rev() {
            acc = acc.union(&sorted[i].bounds());
            suffix[i] = acc.half_area();
        }
        let mut left = Box3::EMPTY;
        for i in 1..n {
            left = left.union(&sorted[i - 1].bounds());
            let cost = split_cost(p, parent, (left.half_area(), i), (suffix[i], n - i));
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, position) = best?;
    if !worth_splitting(p, n, cost) {
        return None;
    }
    refs.sort_unstable_by(|a, b| by_centroid(a, b, axis));
    Some(Split::at(refs, position))
}

/// Maps a (doubled) centroid to its bin on each axis; the same mapping bins and partitions.
struct Binner {
    min: Vec3A,
    scale: Vec3A,
    bins: usize,
}

impl Binner {
    fn new(centroids: &Box3, bins: usize) -> Binner {
        let extent = centroids.extent();
        // A zero extent gets scale 0: every centroid in bin 0, and the axis is never chosen.
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins as f32) / extent,
            Vec3A::ZERO,
        );
        Binner {
            min: centroids.lo,
            scale,
            bins,
        }
    }

    /// Clamped: the largest centroid would land one past the last bin (bug class B10). The
    /// lanes lie in `[0, bins]` (centroids are inside the centroid box), so one SIMD truncation
    /// converts all three: Rust's saturating `as usize` per lane was a quarter of the build.
    #[inline(always)]
    fn bins_of(&self, c: Vec3A) -> [i32; 4] {
        let f = ((c - self.min) * self.scale).min(Vec3A::splat((self.bins - 1) as f32));
        F4::from_vec3a(f).trunc_i32()
    }

    #[inline(always)]
    fn bin(&self, c: Vec3A, axis: usize) -> usize {
        self.bins_of(c)[axis] as usize
    }

    fn fill<const N: usize>(&self, refs: &[PrimRef], bins: &mut Bins<N>) {
        for p in refs {
            let b = p.bounds();
            let slots = self.bins_of(p.centroid2());
            for (axis, &slot) in slots[..3].iter().enumerate() {
                let slot = slot as usize;
                bins.boxes[slot][axis] = bins.boxes[slot][axis].union(&b);
                bins.counts[slot][axis] += 1;
            }
        }
    }

    fn filled<const N: usize>(&self, refs: &[PrimRef]) -> Bins<N> {
        let mut bins = Bins::empty();
        self.fill(refs, &mut bins);
        bins
    }
}

/// Per bin and axis: the box of the triangles whose centroid falls in it, and their number.
/// `N` is the array size, the smallest of 8, 16, 32, 64 that holds the node's bins: at 64 the
/// arrays are 7 KiB, and initialising and returning them was 15 % of the bunny's build
/// instructions when every node paid for 64 (callgrind, 2026-11-21).
#[derive(Clone, Copy)]
struct Bins<const N: usize> {
    boxes: [[Box3; 3]; N],
    counts: [[u32; 3]; N],
}

impl<const N: usize> Bins<N> {
    /// Built in place: a `const` of this size was copied in with `memcpy`, twice per node.
    #[inline(always)]
    fn empty() -> Bins<N> {
        Bins {
            boxes: std::array::from_fn(|_| [Box3::EMPTY; 3]),
            counts: [[0; 3]; N],
        }
    }

    fn merge(mut self, o: Bins<N>) -> Bins<N> {
        for b in 0..N {
            for axis in 0..3 {
                self.boxes[b][axis] = self.boxes[b][axis].union(&o.boxes[b][axis]);
                self.counts[b][axis] += o.counts[b][axis];
            }
        }
        self
    }
}

/// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"):
/// drop centroids into `bins` equal slots of the centroid bounds per axis in one O(n) pass,
/// then evaluate only the `bins - 1` slot boundaries per axis from prefix and suffix sums.
/// O(n log n) overall and parallel-friendly (the pass is a fold over chunks); the price is
/// that a split can only fall on a slot boundary, which costs a little tree quality compared
/// with the full sweep. The partition that follows measures both children on the way, so no
/// node ever makes a separate pass for its bounds.
pub(crate) fn binned_split(refs: &mut [PrimRef], r: &Ranged, p: &BvhParams) -> Option<Split> {
    let n = refs.len();
    let parent = r.bounds.half_area();
    if parent <= 0.0 || r.centroids.extent().max_element() <= 0.0 {
        return None;
    }
    // No more bins than triangles: a small node's split candidates are covered by n bins,
    // and the per-node cost of evaluating 3 × bins boundaries dominated small subtrees
    // (callgrind on the bunny: 70 % of build instructions with 16 bins everywhere).
    let binner = Binner::new(&r.centroids, (p.bins as usize).min(n.max(2)).min(MAX_BINS));
    match binner.bins {
        0..=8 => binned_split_in::<8>(refs, r, p, &binner),
        9..=16 => binned_split_in::<16>(refs, r, p, &binner),
        17..=32 => binned_split_in::<32>(refs, r, p, &binner),
        _ => binned_split_in::<MAX_BINS>(refs, r, p, &binner),
    }
}

/// [`binned_split`] with `binner.bins <= N`.
fn binned_split_in<const N: usize>(
    refs: &mut [PrimRef],
    r: &Ranged,
    p: &BvhParams,
    binner: &Binner,
) -> Option<Split> {
    let n = refs.len();
    let parent = r.bounds.half_area();
    let mut bins = Bins::<N>::empty();
    if n >= PARALLEL_BINNING {
        bins = refs
            .par_chunks(8192)
            .map(|c| binner.filled(c))
            .reduce(Bins::empty, Bins::merge);
    } else {
        binner.fill(refs, &mut bins);
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, first bin on the right)
    let mut suffix = [(0.0f64, 0usize); N];
    for axis in (0..3).filter(|&a| binner.scale[a] > 0.0) {
        let (mut acc, mut count) = (Box3::EMPTY, 0);
        for b in (1..binner.bins).rev() {
            acc = acc.union(&bins.boxes[b][axis]);
            count += bins.counts[b][axis] as usize;
            suffix[b] = (acc.half_area(), count);
        }
        let (mut left, mut left_count) = (Box3::EMPTY, 0);
        for (b, &(right_area, right_count)) in suffix.iter().enumerate().take(binner.bins).skip(1) {
            left = left.union(&bins.boxes[b - 1][axis]);
            left_count += bins.counts[b - 1][axis] as usize;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = split_cost(
                p,
                parent,
                (left.half_area(), left_count),
                (right_area, right_count),
            );
            if best.is_none_or(|x| cost < x.0) {
                best = Some((cost, axis, b));
            }
        }
    }
    let (cost, axis, boundary) = best?;
    if !worth_splitting(p, n, cost) {
        return None;
    }
    Some(partition(refs, |p| {
        binner.bin(p.centroid2(), axis) < boundary
    }))
}

/// Moves the records satisfying `goes_left` to the front (two cursors closing in, Hoare
/// style: each record is read once and at most one swap per pair) while measuring both sides.
fn partition(refs: &mut [PrimRef], goes_left: impl Fn(&PrimRef) -> bool) -> Split {
    let (mut left, mut right) = (Ranged::EMPTY, Ranged::EMPTY);
    let (mut i, mut j) = (0, refs.len());
    loop {
        while i < j && goes_left(&refs[i]) {
            left.add(&refs[i]);
            i += 1;
        }
        while i < j && !goes_left(&refs[j - 1]) {
            right.add(&refs[j - 1]);
            j -= 1;
        }
        if i >= j {
            break;
        }
        refs.swap(i, j - 1);
        left.add(&refs[i]);
        right.add(&refs[j - 1]);
        i += 1;
        j -= 1;
    }
    Split {
        mid: i,
        left,
        right,
    }
}
