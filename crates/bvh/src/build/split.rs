//! The three ways to choose a split. Each takes a node's range of [`PrimRef`]s, reorders it so
//! that the left child's triangles come first, and returns where the right child starts with
//! both children's bounds — or `None` when it finds no way (or no profitable way) to separate
//! the centroids; `build` then decides between a leaf and a forced cut.

use super::prim::{Box3, PrimRef, Ranged};
use crate::BvhParams;
use crate::simd::F4;
use glam::Vec3A;
use rayon::prelude::*;

/// Binning passes, and the centroid passes after a partition, over at least this many
/// triangles run on rayon (measured on the dragon: below ~64k the fork-join overhead outweighs
/// the pass).
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

    /// Clamped: the largest centroid would land one past the last bin (bug class B10). The
    /// lanes lie in `[0, bins]` (centroids are inside the centroid box), so one SIMD truncation
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
/// resets only the bins it uses. Fresh arrays per node (sized to the smallest of 8, 16, 32 or
/// 64 bins that held the node's, built with `array::from_fn`) went through a stack temporary
/// and `memcpy`: 14 % of the dragon's `leaf_block` 4 build (this VM, 2026-11-21).
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

/// The SAH sweep's values per boundary `b` (bins `..b` left, `b..` right) and axis.
struct Sweep {
    /// Half the area of the right side's box, and its triangles.
    right: [([f64; 3], [u32; 3]); MAX_BINS],
    /// Triangles on the left.
    left_count: [[u32; 3]; MAX_BINS],
    /// The areas weighted by the triangle tests of each side, NaN when a side is empty.
    x: [[f64; 3]; MAX_BINS],
}

impl Scratch {
    pub(crate) fn new() -> Box<Scratch> {
        Box::new(Scratch {
            bins: Bins::EMPTY,
            spare: Bins::EMPTY,
            sweep: Sweep {
                right: [([0.0; 3], [0; 3]); MAX_BINS],
                left_count: [[0; 3]; MAX_BINS],
                x: [[0.0; 3]; MAX_BINS],
            },
        })
    }
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
    // No more bins than triangles: a small node's split candidates are covered by n bins,
    // and the per-node cost of evaluating 3 × bins boundaries dominated small subtrees
    // (callgrind on the bunny: 70 % of build instructions with 16 bins everywhere).
    let binner = Binner::new(&r.centroids, (p.bins as usize).min(n.max(2)).min(MAX_BINS));
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
    // The weighted area sum `x` of every boundary on all three axes first, with no branch (an
    // invalid boundary, leaving a side empty, gets NaN; mesh coordinates are finite, so a
    // valid one never is): the three axes interleave and nothing mispredicts. An axis of zero
    // extent has every triangle in bin 0, so all of its boundaries are invalid.
    let block = p.leaf_block.max(1) as u64;
    let blocks = |count: u32| -> f64 {
        let count = count as u64;
        if block.is_power_of_two() {
            ((count + block - 1) & !(block - 1)) as f64
        } else {
            count.div_ceil(block) as f64 * block as f64
        }
    };
    let (mut acc, mut count) = ([Box3::EMPTY; 3], [0u32; 3]);
    for b in (1..nb).rev() {
        for axis in 0..3 {
            acc[axis] = acc[axis].union(&bins.boxes[b][axis]);
            count[axis] += bins.counts[b][axis];
        }
        sweep.right[b] = (acc.map(|a| a.half_area()), count);
    }
    let (mut left, mut left_count) = ([Box3::EMPTY; 3], [0u32; 3]);
    for b in 1..nb {
        for axis in 0..3 {
            left[axis] = left[axis].union(&bins.boxes[b - 1][axis]);
            left_count[axis] += bins.counts[b - 1][axis];
        }
        let left_area = left.map(|l| l.half_area());
        let (right_area, right_count) = sweep.right[b];
        sweep.x[b] = std::array::from_fn(|axis| {
            let x = left_area[axis] * blocks(left_count[axis])
                + right_area[axis] * blocks(right_count[axis]);
            let valid = left_count[axis] > 0 && right_count[axis] > 0;
            if valid { x } else { f64::NAN }
        });
        sweep.left_count[b] = left_count;
    }
    // Then the choice, in the order the boundaries were always compared (axis by axis, left
    // to right; the first of equal costs wins). Only `x` varies between candidates, and the
    // cost `traversal + intersection * x / parent` never falls as `x` grows (for a positive
    // intersection cost): so a boundary can only beat the best if its `x` is smaller, and
    // the cost, with its division, is computed exactly as before only then.
    let monotone = p.intersection_cost > 0.0;
    // (cost, its x, axis, first bin on the right)
    let mut best: Option<(f64, f64, usize, usize)> = None;
    for axis in (0..3).filter(|&a| binner.scale[a] > 0.0) {
        for (b, x) in sweep.x[1..nb].iter().map(|x| x[axis]).enumerate() {
            let candidate = match best {
                Some(best) if monotone => x < best.1,
                _ => !x.is_nan(),
            };
            if !candidate {
                continue;
            }
            let cost = p.traversal_cost as f64 + p.intersection_cost as f64 * x / parent;
            if best.is_none_or(|best| cost < best.0) {
                best = Some((cost, x, axis, b + 1));
            }
        }
    }
    let (cost, _, axis, boundary) = best?;
    let left_count = sweep.left_count[boundary][axis];
    if !worth_splitting(p, n, cost) {
        return None;
    }
    // `bin(c) < boundary` on one lane, in scalar: the lane is never negative and `boundary`
    // is a whole number no larger than the clamp `bins - 1`, so neither the truncation nor the
    // clamp can change the answer.
    let (lo, scale, limit) = (binner.min[axis], binner.scale[axis], boundary as f32);
    let mid = left_count as usize;
    partition(refs, mid, |p| (p.centroid2_on(axis) - lo) * scale < limit);
    // Each side's box is the union of its bins' boxes: only the centroid bounds need a pass.
    let side = |bins_range: std::ops::Range<usize>| {
        bins.boxes[bins_range]
            .iter()
            .fold(Box3::EMPTY, |acc, b| acc.union(&b[axis]))
    };
    Some(Split {
        mid,
        left: Ranged {
            bounds: side(0..boundary),
            centroids: Box3::centroids_of(&refs[..mid], PARALLEL_BINNING),
        },
        right: Ranged {
            bounds: side(boundary..nb),
            centroids: Box3::centroids_of(&refs[mid..], PARALLEL_BINNING),
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
/// (as in Edelkamp and Weiß 2016, "BlockQuicksort"), and then the noted pairs swap. Together
/// with taking the children's boxes from the bins, this made the dragon's `leaf_block` 4
/// build 12 % faster (this VM, 2026-11-21).
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
