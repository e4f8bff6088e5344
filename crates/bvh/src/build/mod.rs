//! BVH construction: a boxed build tree over one primitive index array that every node
//! partitions in place (each node owns a contiguous range), flattened depth-first afterwards.
//!
//! Three ways to choose a split, each a function below with its own note:
//! * [`median_split`] — object median on the longest centroid axis;
//! * [`sweep_split`] — full-sweep SAH;
//! * [`binned_split`] — binned SAH.
//!
//! Termination and degenerate input are handled once, in [`build_range`]: a range of one
//! triangle, or at [`MAX_DEPTH`], is a leaf; a split function returns `None` when it finds no
//! way (or no profitable way) to separate the centroids, and then a range that fits in a leaf
//! becomes one, while a larger range is cut in half in its current order — all centroids
//! equal, say — so recursion always shrinks the range and always ends.

use crate::node::{ChildRef, MAX_DEPTH, Node, corners};
use crate::{Builder, BvhParams};
use raybench_accel::{BuildStats, SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST};
use raybench_geom::{Aabb, TriangleMesh, Vec3};
use rayon::prelude::*;

/// Binning passes over at least this many triangles run on rayon (measured on the dragon:
/// below ~64k the fork-join overhead outweighs the pass).
const PARALLEL_BINNING: usize = 65_536;

/// Per triangle: its bounds and centroid (of the bounds, as split decisions use).
#[derive(Clone, Copy, Debug)]
struct PrimInfo {
    bounds: Aabb,
    centroid: Vec3,
}

/// The convenient shape: nodes own their children.
enum BuildNode {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[BuildNode; 2]>,
    },
}

/// A built and flattened tree.
pub(crate) struct Flat {
    pub nodes: Vec<Node>,
    pub prim_ids: Vec<u32>,
    pub stats: BuildStats,
    pub root: ChildRef,
    pub root_bounds: Aabb,
}

pub(crate) fn build(mesh: &TriangleMesh, params: &BvhParams) -> Flat {
    let infos: Vec<PrimInfo> = (0..mesh.len())
        .into_par_iter()
        .map(|i| {
            let bounds = mesh.triangle(i).bounds();
            PrimInfo {
                bounds,
                centroid: bounds.center(),
            }
        })
        .collect();
    let mut ids: Vec<u32> = (0..mesh.len() as u32).collect();
    if ids.is_empty() {
        return Flat {
            nodes: Vec::new(),
            prim_ids: ids,
            stats: BuildStats::default(),
            root: ChildRef::default(),
            root_bounds: Aabb::EMPTY,
        };
    }
    let (bounds, centroids) = range_bounds(&infos, &ids);
    let tree = build_range(&infos, &mut ids, Ranged { bounds, centroids }, 0, 0, params);
    let mut nodes = Vec::with_capacity(mesh.len());
    let root = flatten(&tree, &mut nodes);
    let mut shape = Shape::default();
    shape.visit(&tree, 0, bounds.surface_area());
    Flat {
        nodes,
        prim_ids: ids,
        stats: shape.stats(),
        root,
        root_bounds: bounds,
    }
}

/// Bounds of the triangles and of their centroids.
fn range_bounds(infos: &[PrimInfo], ids: &[u32]) -> (Aabb, Aabb) {
    let fold = |(b, c): (Aabb, Aabb), &i: &u32| {
        let p = &infos[i as usize];
        (b.union(&p.bounds), c.grow(p.centroid))
    };
    let merge = |x: (Aabb, Aabb), y: (Aabb, Aabb)| (x.0.union(&y.0), x.1.union(&y.1));
    let empty = (Aabb::EMPTY, Aabb::EMPTY);
    if ids.len() >= PARALLEL_BINNING {
        ids.par_chunks(8192)
            .map(|c| c.iter().fold(empty, fold))
            .reduce(|| empty, merge)
    } else {
        ids.iter().fold(empty, fold)
    }
}

/// A range's triangle bounds and centroid bounds, computed by whoever partitioned it.
#[derive(Clone, Copy)]
struct Ranged {
    bounds: Aabb,
    centroids: Aabb,
}

fn build_range(
    infos: &[PrimInfo],
    ids: &mut [u32],
    r: Ranged,
    first: u32,
    depth: usize,
    p: &BvhParams,
) -> BuildNode {
    let n = ids.len();
    let leaf = BuildNode::Leaf {
        bounds: r.bounds,
        first,
        count: n as u32,
    };
    if n == 1 || depth + 1 >= MAX_DEPTH {
        return leaf;
    }
    let split = match p.builder {
        Builder::Median => median_split(infos, ids, &r.centroids, p),
        Builder::Sweep => sweep_split(infos, ids, &r.bounds, p),
        Builder::Binned => binned_split(infos, ids, &r.bounds, &r.centroids, p),
    };
    let mid = match split {
        Some(mid) => mid,
        None if n <= p.max_leaf_size as usize => return leaf,
        None => n / 2, // centroids indistinguishable: cut the range in half as it is
    };
    debug_assert!(0 < mid && mid < n, "a split leaves both sides non-empty");
    let (left, right) = ids.split_at_mut(mid);
    // One pass per side for the children's bounds, instead of one per node on entry.
    let (lr, rr) = (ranged(infos, left), ranged(infos, right));
    let right_first = first + mid as u32;
    let children = if n > p.parallel_threshold as usize {
        rayon::join(
            || build_range(infos, left, lr, first, depth + 1, p),
            || build_range(infos, right, rr, right_first, depth + 1, p),
        )
    } else {
        (
            build_range(infos, left, lr, first, depth + 1, p),
            build_range(infos, right, rr, right_first, depth + 1, p),
        )
    };
    BuildNode::Interior {
        bounds: r.bounds,
        children: Box::new([children.0, children.1]),
    }
}

fn ranged(infos: &[PrimInfo], ids: &[u32]) -> Ranged {
    let (bounds, centroids) = range_bounds(infos, ids);
    Ranged { bounds, centroids }
}

/// Object median: the textbook baseline. Splits any range larger than a leaf at the median
/// centroid along the longest axis of the centroid bounds (`select_nth_unstable`, O(n) per
/// level, O(n log n) in all). Ignores triangle sizes entirely, so it makes balanced trees whose
/// boxes overlap more than SAH trees'. `None` when the range fits in a leaf or every centroid is
/// the same point.
fn median_split(
    infos: &[PrimInfo],
    ids: &mut [u32],
    centroids: &Aabb,
    p: &BvhParams,
) -> Option<usize> {
    if ids.len() <= p.max_leaf_size as usize || centroids.extent().max_element() <= 0.0 {
        return None;
    }
    let axis = centroids.largest_axis();
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |&a, &b| {
        infos[a as usize].centroid[axis]
            .total_cmp(&infos[b as usize].centroid[axis])
            .then(a.cmp(&b))
    });
    Some(mid)
}

/// The SAH cost of splitting a range with box area `parent` into `(area, count)` halves,
/// relative to intersecting every triangle (MacDonald and Booth 1990).
fn split_cost(p: &BvhParams, parent: f64, left: (f64, usize), right: (f64, usize)) -> f64 {
    p.traversal_cost as f64
        + p.intersection_cost as f64 * (left.0 * left.1 as f64 + right.0 * right.1 as f64) / parent
}

/// Whether the best split is worth taking: always when the range is too big for a leaf,
/// otherwise only when it is cheaper than intersecting every triangle.
fn worth_splitting(p: &BvhParams, n: usize, best_cost: f64) -> bool {
    n > p.max_leaf_size as usize || best_cost < p.intersection_cost as f64 * n as f64
}

/// Full-sweep SAH (the classic O(n log² n) builder; MacDonald and Booth 1990, as in Wald,
/// Boulos and Shirley 2007 "sweep"): for each axis, sort the range by centroid, accumulate
/// suffix box areas right to left, then sweep left to right evaluating every one of the n - 1
/// split positions. The best split the SAH can find among object partitions by sorted
/// centroid, at the price of three sorts per node; the reference the binned builder is judged
/// against ("within 3 %").
fn sweep_split(infos: &[PrimInfo], ids: &mut [u32], bounds: &Aabb, p: &BvhParams) -> Option<usize> {
    let n = ids.len();
    let parent = bounds.surface_area();
    if parent <= 0.0 {
        return None;
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, position)
    let mut sorted = ids.to_vec();
    let mut suffix = vec![0.0f64; n];
    for axis in 0..3 {
        sort_by_centroid(infos, &mut sorted, axis);
        let mut acc = Aabb::EMPTY;
        for i in (1..n).rev() {
            acc = acc.union(&infos[sorted[i] as usize].bounds);
            suffix[i] = acc.surface_area();
        }
        let mut left = Aabb::EMPTY;
        for i in 1..n {
            left = left.union(&infos[sorted[i - 1] as usize].bounds);
            let cost = split_cost(p, parent, (left.surface_area(), i), (suffix[i], n - i));
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, position) = best?;
    if !worth_splitting(p, n, cost) {
        return None;
    }
    sort_by_centroid(infos, ids, axis);
    Some(position)
}

/// Sorted by centroid on `axis`, ties by index, so the order (and the tree) is deterministic.
fn sort_by_centroid(infos: &[PrimInfo], ids: &mut [u32], axis: usize) {
    ids.sort_unstable_by(|&a, &b| {
        infos[a as usize].centroid[axis]
            .total_cmp(&infos[b as usize].centroid[axis])
            .then(a.cmp(&b))
    });
}

/// Per-axis bins: box and count.
#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

/// Maps a centroid to its bin on each axis; the same mapping bins and partitions.
struct Binner {
    min: Vec3,
    scale: Vec3,
    bins: usize,
}

impl Binner {
    fn new(centroids: &Aabb, bins: usize) -> Binner {
        let extent = centroids.extent();
        // A zero extent gets scale 0: every centroid in bin 0, and the axis is never chosen.
        let scale = Vec3::select(
            extent.cmpgt(Vec3::ZERO),
            Vec3::splat(bins as f32) / extent,
            Vec3::ZERO,
        );
        Binner {
            min: centroids.min,
            scale,
            bins,
        }
    }

    /// Clamped: the largest centroid would land one past the last bin (bug class B10).
    #[inline(always)]
    fn bin(&self, c: Vec3, axis: usize) -> usize {
        (((c[axis] - self.min[axis]) * self.scale[axis]) as usize).min(self.bins - 1)
    }

    /// Adds the triangles of `ids` to `bins` (only the first `self.bins` are used).
    fn fill(&self, infos: &[PrimInfo], ids: &[u32], bins: &mut Bins) {
        for &i in ids {
            let info = &infos[i as usize];
            for axis in 0..3 {
                let b = &mut bins[self.bin(info.centroid, axis)][axis];
                b.bounds = b.bounds.union(&info.bounds);
                b.count += 1;
            }
        }
    }

    fn filled(&self, infos: &[PrimInfo], ids: &[u32]) -> Bins {
        let mut bins = [[EMPTY_BIN; 3]; MAX_BINS];
        self.fill(infos, ids, &mut bins);
        bins
    }
}

/// Upper bound of the `bins` knob: bins live in fixed arrays on the stack, so binning a node
/// allocates nothing.
pub const MAX_BINS: usize = 64;

type Bins = [[Bin; 3]; MAX_BINS];

fn merge_bins(mut a: Bins, b: Bins) -> Bins {
    for (x, y) in a.iter_mut().zip(b) {
        for axis in 0..3 {
            x[axis].bounds = x[axis].bounds.union(&y[axis].bounds);
            x[axis].count += y[axis].count;
        }
    }
    a
}

/// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"):
/// drop centroids into `bins` equal slots of the centroid bounds per axis in one O(n) pass,
/// then evaluate only the `bins - 1` slot boundaries per axis from prefix and suffix sums.
/// O(n log n) overall and parallel-friendly (the pass is a fold over chunks); the price is
/// that a split can only fall on a slot boundary, which costs a little tree quality compared
/// with the full sweep.
fn binned_split(
    infos: &[PrimInfo],
    ids: &mut [u32],
    bounds: &Aabb,
    centroids: &Aabb,
    p: &BvhParams,
) -> Option<usize> {
    let n = ids.len();
    let parent = bounds.surface_area();
    if parent <= 0.0 || centroids.extent().max_element() <= 0.0 {
        return None;
    }
    // No more bins than triangles: a small node's split candidates are covered by n bins,
    // and the per-node cost of evaluating 3 × bins boundaries dominated small subtrees
    // (callgrind on the bunny: 70 % of build instructions with 16 bins everywhere).
    let binner = Binner::new(centroids, (p.bins as usize).min(n.max(2)));
    let mut bins = [[EMPTY_BIN; 3]; MAX_BINS];
    if n >= PARALLEL_BINNING {
        bins = ids
            .par_chunks(8192)
            .map(|c| binner.filled(infos, c))
            .reduce(|| [[EMPTY_BIN; 3]; MAX_BINS], merge_bins);
    } else {
        binner.fill(infos, ids, &mut bins);
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, first bin on the right)
    let mut suffix = [(0.0f64, 0usize); MAX_BINS];
    for axis in (0..3).filter(|&a| binner.scale[a] > 0.0) {
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in (1..binner.bins).rev() {
            acc = acc.union(&bins[b][axis].bounds);
            count += bins[b][axis].count;
            suffix[b] = (acc.surface_area(), count);
        }
        let (mut left, mut left_count) = (Aabb::EMPTY, 0);
        for b in 1..binner.bins {
            left = left.union(&bins[b - 1][axis].bounds);
            left_count += bins[b - 1][axis].count;
            let (right_area, right_count) = suffix[b];
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = split_cost(
                p,
                parent,
                (left.surface_area(), left_count),
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
    Some(partition_in_place(ids, |&i| {
        binner.bin(infos[i as usize].centroid, axis) < boundary
    }))
}

/// Moves the elements satisfying `left` to the front; returns how many there are.
fn partition_in_place(ids: &mut [u32], left: impl Fn(&u32) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..ids.len() {
        if left(&ids[i]) {
            ids.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

/// Facts gathered from the build tree, turned into [`BuildStats`].
#[derive(Default)]
struct Shape {
    nodes: u64,
    leaves: u64,
    refs: u64,
    max_depth: u32,
    leaf_depth_sum: u64,
    max_leaf_size: u32,
    /// SAH cost with the constants shared by every structure (None for a zero-area root).
    sah: Option<f64>,
}

impl Shape {
    /// Each node's traversal cost and each leaf's triangle tests, weighted by the probability
    /// that a random ray through the root box also crosses the node's box (area ratio).
    fn visit(&mut self, node: &BuildNode, depth: u32, root_area: f64) {
        self.max_depth = self.max_depth.max(depth);
        let (bounds, work) = match node {
            BuildNode::Leaf { bounds, count, .. } => {
                self.leaves += 1;
                self.refs += *count as u64;
                self.leaf_depth_sum += depth as u64;
                self.max_leaf_size = self.max_leaf_size.max(*count);
                (bounds, SAH_INTERSECTION_COST * *count as f64)
            }
            BuildNode::Interior { bounds, children } => {
                self.nodes += 1;
                for c in children.iter() {
                    self.visit(c, depth + 1, root_area);
                }
                (bounds, SAH_TRAVERSAL_COST)
            }
        };
        if root_area > 0.0 {
            *self.sah.get_or_insert(0.0) += work * bounds.surface_area() / root_area;
        }
    }

    fn stats(&self) -> BuildStats {
        let mut extra = std::collections::BTreeMap::new();
        let leaves = self.leaves.max(1) as f64;
        extra.insert(
            "mean_leaf_depth".into(),
            self.leaf_depth_sum as f64 / leaves,
        );
        extra.insert("mean_leaf_size".into(), self.refs as f64 / leaves);
        extra.insert("max_leaf_size".into(), self.max_leaf_size as f64);
        BuildStats {
            // Interior nodes plus leaves, as every structure counts them.
            nodes: self.nodes + self.leaves,
            leaves: self.leaves,
            max_depth: self.max_depth,
            refs: self.refs,
            sah_cost: self.sah,
            extra,
        }
    }
}

/// Depth-first: an interior node is stored before its subtrees; returns the reference to it.
fn flatten(node: &BuildNode, out: &mut Vec<Node>) -> ChildRef {
    match node {
        BuildNode::Leaf { first, count, .. } => ChildRef {
            index: *first,
            count: *count,
        },
        BuildNode::Interior { children, .. } => {
            let at = out.len();
            out.push(Node {
                bounds: [[[0.0; 3]; 2]; 2],
                child: [ChildRef::default(); 2],
            });
            let refs = [flatten(&children[0], out), flatten(&children[1], out)];
            out[at] = Node {
                bounds: [corners(children[0].bounds()), corners(children[1].bounds())],
                child: refs,
            };
            ChildRef {
                index: at as u32,
                count: 0,
            }
        }
    }
}

impl BuildNode {
    fn bounds(&self) -> &Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => bounds,
        }
    }
}
