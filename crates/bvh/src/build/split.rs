//! The three ways to choose a split. Each takes a node's range of [`PrimRef`]s, reorders it so
//! that the left child's triangles come first, and returns where the right child starts with
//! both children's bounds — or `None` when it finds no way (or no profitable way) to separate
//! the centroids; `build` then decides between a leaf and a forced cut.

use super::prim::{Box3, PrimRef, Ranged};
use crate::BvhParams;
use crate::simd::F4;
use glam::{BVec3A, Vec3A};
use rayon::prelude::*;

/// Binning passes, and the centroid passes after a partition, over at least this many
/// triangles run on rayon: below that the fork-join overhead outweighs the pass (measured: see
/// docs/experiments.md, "parallel binning passes only from 65,536 records").
pub(crate) const PARALLEL_BINNING: usize = 65_536;

/// Upper bound of the `bins` knob: bins live in fixed arrays, one set per sequential task that
/// all its nodes reuse, so binning a node allocates nothing.
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
pub(crate) fn split_cost(
    p: &BvhParams,
    parent: f64,
    left: (f64, usize),
    right: (f64, usize),
) -> f64 {
    p.traversal_cost as f64
        + p.intersection_cost as f64 * (left.0 * blocks(p, left.1) + right.0 * blocks(p, right.1))
            / parent
}

/// The triangle tests a leaf of `n` costs: `n` rounded up to whole blocks of `leaf_block`
/// (a mask for the usual power of two: the binned sweep calls this six times a boundary).
#[inline(always)]
pub(crate) fn blocks(p: &BvhParams, n: usize) -> f64 {
    let block = p.leaf_block.max(1) as usize;
    if block.is_power_of_two() {
        ((n + block - 1) & !(block - 1)) as f64
    } else {
        n.div_ceil(block) as f64 * block as f64
    }
}

/// Whether the best split is worth taking: always when the range is too big for a leaf,
/// otherwise only when it is cheaper than intersecting every triangle.
pub(crate) fn worth_splitting(p: &BvhParams, n: usize, best_cost: f64) -> bool {
    n > p.max_leaf_size as usize || best_cost < p.intersection_cost as f64 * blocks(p, n)
}

/// Whether no split of `n` triangles can be worth taking, whatever the split: when they fit
/// in a leaf that costs no more than one node step (with the wide tree's knobs, up to one
/// `Tri4`), since a split's cost is at least the traversal cost. Such a range becomes a leaf
/// without binning.
pub(crate) fn leaf_beats_any_split(p: &BvhParams, n: usize) -> bool {
    n <= p.max_leaf_size as usize
        && p.intersection_cost >= 0.0
        && p.intersection_cost as f64 * blocks(p, n) <= p.traversal_cost as f64
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

/// Maps a (doubled) centroid to its bin on each axis; the same mapping bins and (one lane of
/// it, in scalar) partitions.
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

    /// Clamped: the largest centroid would land one past the last bin (docs/validation.md, B10).
    /// The lanes lie in `[0, bins]` (centroids are inside the centroid box), so one SIMD truncation
    /// converts all three: Rust's saturating `as usize` per lane was a quarter of the build.
    #[inline(always)]
    fn bins_of(&self, c: Vec3A) -> [i32; 4] {
        let f = ((c - self.min) * self.scale).min(Vec3A::splat((self.bins - 1) as f32));
        F4::from_vec3a(f).trunc_i32()
    }

    /// Adds one record to the first `self.bins` bins of `bins`.
    #[inline(always)]
    fn add(&self, p: &PrimRef, bins: &mut Bins) {
        let b = p.bounds();
        let slots = self.bins_of(p.centroid2());
        for (axis, &slot) in slots[..3].iter().enumerate() {
            // `bins_of` keeps the slot below `self.bins`, so the mask changes nothing; it
            // lets the compiler drop the bounds check.
            let slot = slot as usize & (MAX_BINS - 1);
            bins.boxes[slot][axis] = bins.boxes[slot][axis].union(&b);
            bins.counts[slot][axis] += 1;
        }
    }

    /// Adds `refs` to the first `self.bins` bins of `bins`. Above [`PAIRED_FILL`] records,
    /// every other record goes to `spare` (reset here), merged in at the end: in a mesh
    /// stored in spatial order, consecutive records mostly land in the same bins, and each
    /// update of a bin then waited for the previous one's store. Min, max and counts give the
    /// same bins in any order.
    fn fill(&self, refs: &[PrimRef], bins: &mut Bins, spare: &mut Bins) {
        if refs.len() < PAIRED_FILL {
            for p in refs {
                self.add(p, bins);
            }
            return;
        }
        spare.reset(self.bins);
        let (pairs, rest) = refs.as_chunks::<2>();
        for [a, b] in pairs {
            self.add(a, bins);
            self.add(b, spare);
        }
        for p in rest {
            self.add(p, bins);
        }
        bins.merge(spare, self.bins);
    }
}

/// Records from which [`Binner::fill`] splits its updates over two sets of bins. Not tuned:
/// smaller nodes have few bins to reset and merge, and are too short for the chains of stores
/// to matter.
const PAIRED_FILL: usize = 256;

/// Per bin and axis: the box of the triangles whose centroid falls in it, and their number.
/// 7 KiB at [`MAX_BINS`], so there is one per sequential task (in its [`Scratch`]), and a node
/// resets only the bins it uses: fresh arrays per node go through a stack temporary and a
/// `memcpy` (measured: see docs/experiments.md, "bins in per-task scratch").
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Box3; 3]; MAX_BINS],
    counts: [[u32; 3]; MAX_BINS],
}

impl Bins {
    const EMPTY: Bins = Bins {
        boxes: [[Box3::EMPTY; 3]; MAX_BINS],
        counts: [[0; 3]; MAX_BINS],
    };

    fn reset(&mut self, bins: usize) {
        self.boxes[..bins].fill([Box3::EMPTY; 3]);
        self.counts[..bins].fill([0; 3]);
    }

    /// Adds the first `bins` bins of `o`.
    fn merge(&mut self, o: &Bins, bins: usize) {
        for b in 0..bins {
            for axis in 0..3 {
                self.boxes[b][axis] = self.boxes[b][axis].union(&o.boxes[b][axis]);
                self.counts[b][axis] += o.counts[b][axis];
            }
        }
    }
}

/// Working memory of the binned builder, reused by every node a sequential task builds.
pub(crate) struct Scratch {
    bins: Bins,
    /// The second set of bins of [`Binner::fill`].
    spare: Bins,
    sweep: Sweep,
}

/// The SAH sweep's values per boundary `b` (bins `..b` left, `b..` right), one lane per axis.
struct Sweep {
    /// The right side's half area (normalised, see [`half_areas`]) weighted by its triangle
    /// tests, and its triangles.
    right: [(Vec3A, [u32; 3]); MAX_BINS],
}

impl Scratch {
    pub(crate) fn new() -> Box<Scratch> {
        Box::new(Scratch {
            bins: Bins::EMPTY,
            spare: Bins::EMPTY,
            sweep: Sweep {
                right: [(Vec3A::ZERO, [0; 3]); MAX_BINS],
            },
        })
    }
}

/// Half the areas of one box per axis (`boxes[axis]`), one lane each, with coordinates scaled
/// by `norm`. The sweep runs in f32, three axes a pass: with `norm` the inverse of the node's
/// largest extent every extent is at most 1, so the areas weighted by triangle counts (up to
/// 2^30) cannot overflow whatever the mesh's scale. An f64 sweep, one axis at a time, gives the
/// same trees but for rare near-ties and costs more (measured: see docs/experiments.md, "SAH
/// sweep over the bins in f32").
#[inline(always)]
fn half_areas(boxes: &[Box3; 3], norm: f32) -> Vec3A {
    let e = boxes.map(|b| b.extent() * norm);
    let x = Vec3A::new(e[0].x, e[1].x, e[2].x);
    let y = Vec3A::new(e[0].y, e[1].y, e[2].y);
    let z = Vec3A::new(e[0].z, e[1].z, e[2].z);
    x * (y + z) + y * z
}

/// The bins of a node of `n` triangles: one per `triangles_per_bin` triangles, at least 2 and
/// at most the `bins` knob. With one bin per triangle a small node's split candidates are all
/// covered, but the per-node cost of evaluating 3 × bins boundaries dominates small subtrees
/// (measured: see docs/experiments.md, "bins sized to the node").
fn bins_for(p: &BvhParams, n: usize) -> usize {
    (n / p.triangles_per_bin.max(1) as usize)
        .max(2)
        .min(p.bins as usize)
        .min(MAX_BINS)
}

/// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"):
/// drop centroids into `bins` equal slots of the centroid bounds per axis in one O(n) pass,
/// then evaluate only the `bins - 1` slot boundaries per axis from prefix and suffix sums.
/// O(n log n) overall and parallel-friendly (the pass is a fold over chunks); the price is
/// that a split can only fall on a slot boundary, which costs a little tree quality compared
/// with the full sweep. The children's boxes are unions of their bins' boxes; only their
/// centroid bounds take a pass after the partition.
pub(crate) fn binned_split(
    refs: &mut [PrimRef],
    r: &Ranged,
    p: &BvhParams,
    scratch: &mut Scratch,
) -> Option<Split> {
    let n = refs.len();
    let parent = r.bounds.half_area();
    if parent <= 0.0 || r.centroids.extent().max_element() <= 0.0 {
        return None;
    }
    let binner = Binner::new(&r.centroids, bins_for(p, n));
    let nb = binner.bins;
    let parallel;
    let bins = if n >= PARALLEL_BINNING {
        let fill = |c: &[PrimRef]| {
            let mut bins = Box::new(Bins::EMPTY);
            binner.fill(c, &mut bins, &mut Box::new(Bins::EMPTY));
            bins
        };
        parallel = refs.par_chunks(8192).map(fill).reduce(
            || Box::new(Bins::EMPTY),
            |mut a, b| {
                a.merge(&b, nb);
                a
            },
        );
        &*parallel
    } else {
        scratch.bins.reset(nb);
        binner.fill(refs, &mut scratch.bins, &mut scratch.spare);
        &scratch.bins
    };
    let sweep = &mut scratch.sweep;
    // The triangle tests of `count` triangles per axis.
    let tests = |count: [u32; 3]| Vec3A::from_array(count.map(|c| blocks(p, c as usize) as f32));
    let norm = 1.0 / r.bounds.extent().max_element();
    let (mut acc, mut count) = ([Box3::EMPTY; 3], [0u32; 3]);
    for b in (1..nb).rev() {
        for axis in 0..3 {
            acc[axis] = acc[axis].union(&bins.boxes[b][axis]);
            count[axis] += bins.counts[b][axis];
        }
        sweep.right[b] = (half_areas(&acc, norm) * tests(count), count);
    }
    // Left to right, keeping per axis the boundary with the least area-weighted triangle
    // tests `x` (the first of equals): the SAH cost `traversal + intersection * x / parent`
    // is least there for any positive intersection cost. No branch: a boundary that leaves a
    // side empty gets an infinite `x` (an axis of zero extent has every triangle in bin 0,
    // so all of its boundaries do), and the running minimum is a select.
    let (mut left, mut left_count) = ([Box3::EMPTY; 3], [0u32; 3]);
    let (mut best_x, mut best_b) = (Vec3A::INFINITY, Vec3A::ZERO);
    for b in 1..nb {
        for axis in 0..3 {
            left[axis] = left[axis].union(&bins.boxes[b - 1][axis]);
            left_count[axis] += bins.counts[b - 1][axis];
        }
        let (right_x, right_count) = sweep.right[b];
        let x = half_areas(&left, norm) * tests(left_count) + right_x;
        let valid = BVec3A::from_array(std::array::from_fn(|a| {
            left_count[a] > 0 && right_count[a] > 0
        }));
        let x = Vec3A::select(valid, x, Vec3A::INFINITY);
        let better = x.cmplt(best_x);
        best_x = Vec3A::select(better, x, best_x);
        best_b = Vec3A::select(better, Vec3A::splat(b as f32), best_b);
    }
    // The first axis of the least `x`.
    let axis = (1..3).fold(0, |a, b| if best_x[b] < best_x[a] { b } else { a });
    if best_x[axis] == f32::INFINITY {
        return None;
    }
    let boundary = best_b[axis] as usize;
    // `x` is in the scaled coordinates, so the parent's area is taken in them too.
    let parent_scaled = Box3 {
        lo: r.bounds.lo * norm,
        hi: r.bounds.hi * norm,
    }
    .half_area();
    let cost =
        p.traversal_cost as f64 + p.intersection_cost as f64 * best_x[axis] as f64 / parent_scaled;
    let left_count: u32 = bins.counts[..boundary].iter().map(|c| c[axis]).sum();
    if !worth_splitting(p, n, cost) {
        return None;
    }
    // `bin(c) < boundary` on one lane, in scalar: the lane is never negative and `boundary`
    // is a whole number no larger than the clamp `bins - 1`, so neither the truncation nor the
    // clamp can change the answer.
    let (lo, scale, limit) = (binner.min[axis], binner.scale[axis], boundary as f32);
    let mid = left_count as usize;
    // One loop per axis, so the lane is fixed inside it: with the axis a run-time index,
    // picking the lane is a branch per record (measured: see docs/experiments.md, "the
    // partition loop written once per axis").
    let goes_left = |c: f32| (c - lo) * scale < limit;
    match axis {
        0 => partition(refs, mid, |p| goes_left(p.centroid2_on(0))),
        1 => partition(refs, mid, |p| goes_left(p.centroid2_on(1))),
        _ => partition(refs, mid, |p| goes_left(p.centroid2_on(2))),
    }
    // Each side's box is the union of its bins' boxes; the centroid bounds take a pass, or
    // are bounded by the box (`centroids_from_boxes`).
    let side = |bins_range: std::ops::Range<usize>| {
        bins.boxes[bins_range]
            .iter()
            .fold(Box3::EMPTY, |acc, b| acc.union(&b[axis]))
    };
    let (left, right) = (side(0..boundary), side(boundary..nb));
    let centroids = |bounds: Box3, refs: &[PrimRef]| {
        if p.centroids_from_boxes
            .is_some_and(|m| refs.len() >= m as usize)
        {
            // A centroid (doubled: `lo + hi`) lies in twice its side's box, and rounding keeps
            // it there (`x + y <= 2 * max` holds in floating point as in exact arithmetic), so
            // the binner's mapping never leaves its bins.
            Box3 {
                lo: (bounds.lo * 2.0).max(r.centroids.lo),
                hi: (bounds.hi * 2.0).min(r.centroids.hi),
            }
        } else {
            Box3::centroids_of(refs, PARALLEL_BINNING)
        }
    };
    Some(Split {
        mid,
        left: Ranged {
            bounds: left,
            centroids: centroids(left, &refs[..mid]),
        },
        right: Ranged {
            bounds: right,
            centroids: centroids(right, &refs[mid..]),
        },
    })
}

/// Records examined per refill of [`partition`]'s buffers.
const BLOCK: usize = 64;

/// Moves the `mid` records satisfying `goes_left` to the front. The permutation is the one of
/// two cursors closing in (Hoare), which the builder always used: the k-th record from the
/// front that must leave `..mid` swaps with the k-th record from the back that must leave
/// `mid..`. But instead of a branch per record, which mispredicts on a random mix of sides,
/// each cursor scans a block without branches, noting the positions of the misplaced records
/// (as in Edelkamp and Weiß 2016, "BlockQuicksort"), and then the noted pairs swap (measured:
/// see docs/experiments.md, "branch-free block partition").
fn partition(refs: &mut [PrimRef], mid: usize, goes_left: impl Fn(&PrimRef) -> bool) {
    let n = refs.len();
    // Misplaced records in `..mid` (ascending) and in `mid..` (descending), noted but not
    // yet swapped: `front[fs..fe]` and `back[bs..be]`.
    let (mut front, mut fs, mut fe) = ([0u32; BLOCK], 0, 0);
    let (mut back, mut bs, mut be) = ([0u32; BLOCK], 0, 0);
    // Next record to examine in `..mid`, and one past the next in `mid..`.
    let (mut i, mut j) = (0, n);
    loop {
        if fs == fe && i < mid {
            (fs, fe) = (0, 0);
            let end = (i + BLOCK).min(mid);
            for (k, p) in (i..end).zip(&refs[i..end]) {
                front[fe] = k as u32;
                fe += !goes_left(p) as usize;
            }
            i = end;
        }
        if bs == be && j > mid {
            (bs, be) = (0, 0);
            let start = j.saturating_sub(BLOCK).max(mid);
            for (k, p) in (start..j).zip(&refs[start..j]).rev() {
                back[be] = k as u32;
                be += goes_left(p) as usize;
            }
            j = start;
        }
        let pairs = (fe - fs).min(be - bs);
        for (&a, &b) in front[fs..fs + pairs].iter().zip(&back[bs..bs + pairs]) {
            refs.swap(a as usize, b as usize);
        }
        fs += pairs;
        bs += pairs;
        if (fs == fe && i == mid) || (bs == be && j == mid) {
            break;
        }
    }
    assert!(
        fs == fe && bs == be,
        "`mid` is the number of records that go left"
    );
    debug_assert!(refs[..mid].iter().all(&goes_left));
    debug_assert!(!refs[mid..].iter().any(&goes_left));
}

#[cfg(test)]
mod tests;
