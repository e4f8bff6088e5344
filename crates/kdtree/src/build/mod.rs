//! k-d tree construction, shared by both builders: the depth-first output (nodes written in
//! place, one reference array), the depth limit, the memory guard, the statistics and the
//! final reordering of triangles into leaf order.
//!
//! * [`sah`]: Wald and Havran's O(N log N) SAH builder with perfect splits.
//! * [`median`]: spatial median, round-robin axes.
//!
//! Both recurse on a node's cell and the triangles' bounds clipped to it, and split with the
//! one rule of [`crate::clip::side`]. Termination and degenerate input are handled the same
//! way in both: a split plane always lies strictly inside its cell (so no child is ever flat
//! on the split axis, and a flat root cell is never split on its flat axis), the depth is
//! capped ([`KdParams::max_depth`], at most [`MAX_DEPTH`]; past the default limit only cells of
//! more than [`LARGE_LEAF`] triangles are cut, while a plane separates them), and each subtree holds at most its
//! `Share` of the references the memory limit allows, so neither recursion nor memory can
//! grow without bound, whatever the input (huge triangles spanning the scene, thousands of
//! triangles in one plane or at one point). Within those guards the SAH builder stops where
//! its cost model says a leaf is cheaper than any split, which already charges a split for
//! every reference it duplicates; no global count of references decides which nodes may
//! split, so a leaf built late is as fine as one built early.
//!
//! Triangles whose precomputed normal is exactly zero in f32 can never be hit (Möller–Trumbore
//! rejects `den == 0`), so they are left out of the tree and counted in the statistics
//! (`excluded_degenerate`). Closest-point queries must still find them (a segment or a point
//! is a valid nearest feature), so when there are any the same builder makes a second tree over
//! them alone (`Selection::ZeroArea`), which only point queries walk: rays pay nothing for it,
//! and a scene full of them (conference: 54k of 331k) does not make point queries linear.

pub mod median;
pub(crate) mod pack;
pub mod sah;

use crate::node::{MAX_DEPTH, MAX_PACKED, Node};
use crate::{Builder, KdParams};
use raybench_accel::{BuildError, BuildStats, SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST};
use raybench_geom::{Aabb, MollerTriangle, Tri4, Triangle, TriangleMesh, Vec3};
use std::collections::BTreeMap;

/// Havran's default depth limit, `round(8 + 1.3 log2 N)` (Havran 2000, §4.5), within
/// [`MAX_DEPTH`].
pub fn default_max_depth(n: usize) -> u32 {
    let d = 8.0 + 1.3 * (n.max(1) as f64).log2();
    (d.round() as u32).min(MAX_DEPTH as u32)
}

/// What every node of a build needs to know.
pub(crate) struct Ctx<'a> {
    pub tris: &'a [Triangle],
    pub params: &'a KdParams,
    pub max_depth: u32,
    /// How deep a node of more than [`LARGE_LEAF`] triangles may still be split: the depth
    /// limit only ends cost-driven splitting, so a crowded cell at the limit keeps being cut
    /// (down to the traversal stack's [`MAX_DEPTH`]) while any plane separates its triangles.
    pub large_max_depth: u32,
    pub root_area: f64,
    /// Nodes above this depth may build their subtrees on two rayon tasks.
    pub fork_depth: u32,
}

impl Ctx<'_> {
    pub fn fork(&self, n: usize, depth: u32) -> bool {
        depth < self.fork_depth && n > self.params.parallel_threshold as usize
    }
}

/// The references a subtree may hold, so the whole tree fits in
/// [`KdParams::memory_limit_bytes`] whatever the input. The root gets what the memory allows. A
/// split needs its two children's references within its node's share; the children then
/// divide the share. Near the root (depth below [`Share::PROPORTIONAL_DEPTH`], where subtrees
/// may be built in parallel) they divide it in proportion to their references; deeper, the
/// child below the plane is built first with the share minus what the child above needs at
/// least, and the child above gets what the first left. Either way no subtree can exceed its
/// share, and a node's share depends only on the tree built before it in depth-first order,
/// never on the thread count or the order threads finish in, so the tree is deterministic. It
/// is a memory guard, not a tuning knob: a node it stops is counted (`memory_capped_leaves`);
/// the cost model decides where splitting stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Share(pub u64);

impl Share {
    /// Above this depth the share is divided in proportion and subtrees may fork.
    pub const PROPORTIONAL_DEPTH: u32 = 6;

    /// Whether a split into `below` and `above` references fits.
    pub fn fits(self, below: usize, above: usize) -> bool {
        below as u64 + above as u64 <= self.0
    }

    /// The children's shares in proportion to their references (the split fits).
    pub fn proportional(self, below: usize, above: usize) -> (Share, Share) {
        let (b, a) = (below as u128, above as u128);
        // u128: the share times a count may exceed u64.
        let sb = (self.0 as u128 * b / (b + a).max(1)) as u64;
        (Share(sb), Share(self.0 - sb))
    }
}

/// A leaf with more triangles than this is a termination failure unless more than this many
/// of its triangles pass through one point (a pile, which planes cannot cut apart near that
/// point); both kinds are counted.
pub const LARGE_LEAF: usize = 64;

/// Whether more than [`LARGE_LEAF`] of the triangles `ids` pass near one point: the bounds of
/// all of them share a point, or one of their vertices lies in the bounds of more than
/// [`LARGE_LEAF`] of them (a fan around a shared vertex, with a few strays that keep the bounds
/// of all from meeting). At most [`PILE_PROBES`] triangles' vertices are probed, spread evenly
/// over `ids`, so the test costs O(n) per call; bounds are the cheap, conservative test.
pub(crate) fn is_pile(tris: &[Triangle], ids: &[u32]) -> bool {
    if ids.len() <= LARGE_LEAF {
        return false;
    }
    let (lo, hi) = ids
        .iter()
        .fold((Vec3::NEG_INFINITY, Vec3::INFINITY), |(lo, hi), &i| {
            let b = tris[i as usize].bounds();
            (lo.max(b.min), hi.min(b.max))
        });
    if lo.cmple(hi).all() {
        return true;
    }
    let step = ids.len().div_ceil(PILE_PROBES);
    ids.iter()
        .step_by(step)
        .flat_map(|&i| {
            let t = &tris[i as usize];
            [t.v0, t.v1, t.v2]
        })
        .any(|p| {
            ids.iter()
                .filter(|&&j| tris[j as usize].bounds().contains(p))
                .count()
                > LARGE_LEAF
        })
}

/// How many triangles' vertices [`is_pile`] probes.
const PILE_PROBES: usize = 64;

/// Why a node became a leaf, for the statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stop {
    /// The cost model (or the leaf size) chose a leaf: the normal case.
    Cost,
    /// The depth limit.
    Depth,
    /// The node's reference share ([`Share`]) could not cover the split the cost chose.
    Memory,
}

/// Shape facts gathered while nodes are written.
#[derive(Clone, Debug, Default)]
pub(crate) struct Shape {
    interior: u64,
    leaves: u64,
    empty_leaves: u64,
    pub refs: u64,
    max_depth: u32,
    leaf_depth_sum: u64,
    max_leaf_size: u32,
    depth_capped: u64,
    memory_capped: u64,
    /// Leaves over [`LARGE_LEAF`] triangles: all of them, and those whose bounds share a point.
    large: u64,
    large_piles: u64,
    /// Σ area(cell)/area(root) × cost, see [`Out::leaf`] and [`Out::open_interior`].
    sah: f64,
}

impl Shape {
    fn add(&mut self, o: &Shape) {
        self.interior += o.interior;
        self.leaves += o.leaves;
        self.empty_leaves += o.empty_leaves;
        self.refs += o.refs;
        self.max_depth = self.max_depth.max(o.max_depth);
        self.leaf_depth_sum += o.leaf_depth_sum;
        self.max_leaf_size = self.max_leaf_size.max(o.max_leaf_size);
        self.depth_capped += o.depth_capped;
        self.memory_capped += o.memory_capped;
        self.large += o.large;
        self.large_piles += o.large_piles;
        self.sah += o.sah;
    }
}

/// A depth-first subtree being written: an interior node is followed by its subtree below the
/// plane, then the one above; leaves point into `refs` (mesh triangle ids until
/// [`pack::pack`] renumbers them).
#[derive(Debug, Default)]
pub(crate) struct Out {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub shape: Shape,
}

impl Out {
    /// Writes a leaf holding `ids` (sorted, so leaves are deterministic whatever order the
    /// builder collected them in). `stop` says why it is a leaf.
    pub fn leaf(&mut self, ctx: &Ctx, cell: &Aabb, depth: u32, mut ids: Vec<u32>, stop: Stop) {
        ids.sort_unstable();
        let count = ids.len() as u32;
        self.nodes
            .push(Node::leaf(self.refs.len() as u32, count.min(MAX_PACKED)));
        self.refs.extend_from_slice(&ids);
        let s = &mut self.shape;
        s.leaves += 1;
        s.empty_leaves += (count == 0) as u64;
        s.refs += count as u64;
        s.max_depth = s.max_depth.max(depth);
        s.leaf_depth_sum += depth as u64;
        s.max_leaf_size = s.max_leaf_size.max(count);
        s.depth_capped += (stop == Stop::Depth) as u64;
        s.memory_capped += (stop == Stop::Memory) as u64;
        if count as usize > LARGE_LEAF {
            s.large += 1;
            s.large_piles += is_pile(ctx.tris, &ids) as u64;
        }
        if ctx.root_area > 0.0 {
            s.sah += cell.surface_area() / ctx.root_area * count as f64 * SAH_INTERSECTION_COST;
        }
    }

    /// Reserves the slot of an interior node; its subtree below the plane follows it. The node
    /// is written by [`Out::close_interior`] once the subtree above has begun.
    pub fn open_interior(&mut self, ctx: &Ctx, cell: &Aabb) -> usize {
        let at = self.nodes.len();
        self.nodes.push(Node::default());
        self.shape.interior += 1;
        if ctx.root_area > 0.0 {
            self.shape.sah += cell.surface_area() / ctx.root_area * SAH_TRAVERSAL_COST;
        }
        at
    }

    pub fn close_interior(&mut self, at: usize, axis: usize, split: f32, above_at: usize) {
        self.nodes[at] = Node::interior(axis, split, (above_at as u32).min(MAX_PACKED));
    }

    /// Appends a subtree written on its own, shifting its node and reference indices.
    pub fn append(&mut self, sub: Out) {
        let (node_base, ref_base) = (self.nodes.len() as u32, self.refs.len() as u32);
        self.nodes.extend(sub.nodes.into_iter().map(|n| {
            if n.is_leaf() {
                Node::leaf(n.first() + ref_base, n.count())
            } else {
                Node::interior(n.axis(), n.split(), (n.above() + node_base).min(MAX_PACKED))
            }
        }));
        self.refs.extend_from_slice(&sub.refs);
        self.shape.add(&sub.shape);
    }
}

/// A built, flattened tree.
pub(crate) struct Flat {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub tri4s: Vec<Tri4>,
    pub prim_ids: Vec<u32>,
    pub bounds: Aabb,
    /// The deepest a leaf lies: the depth limit, or deeper where crowded cells were split on.
    pub deepest: u32,
    pub stats: BuildStats,
}

/// Largest number of triangles a build accepts: the SAH builder packs a triangle id into 30
/// bits of an event.
pub const MAX_TRIANGLES: usize = 1 << 30;

/// Which triangles of the mesh a tree holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Selection {
    /// Every triangle a ray can hit (precomputed normal not zero): the tree rays trace.
    Hittable,
    /// Only the zero-area triangles rays never hit, which closest-point queries still must
    /// find: the side tree of [`crate::KdTree`], walked by point queries only.
    ZeroArea,
}

impl Selection {
    pub(crate) fn holds(self, tri: &Triangle) -> bool {
        let hittable = MollerTriangle::new(tri).ng != Vec3::ZERO;
        hittable == (self == Selection::Hittable)
    }
}

pub(crate) fn build(
    mesh: &TriangleMesh,
    params: &KdParams,
    selection: Selection,
) -> Result<Flat, BuildError> {
    let affordable_refs = references_within_memory(mesh.len(), params)?;
    let tris: Vec<Triangle> = mesh.triangles().collect();
    let ids: Vec<u32> = (0..tris.len() as u32)
        .filter(|&i| selection.holds(&tris[i as usize]))
        .collect();
    if ids.len() >= MAX_TRIANGLES {
        return Err(BuildError::Unsupported(format!(
            "{} triangles; the k-d tree builds at most {MAX_TRIANGLES}",
            ids.len()
        )));
    }
    let excluded = tris.len() - ids.len();
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(&tris[i as usize].bounds()));
    let n = ids.len();
    let depth_limit = params
        .max_depth
        .unwrap_or_else(|| default_max_depth(n))
        .min(MAX_DEPTH as u32);
    // A limit the user set is a hard one; Havran's default only ends cost-driven splitting.
    let large_max_depth = match params.max_depth {
        Some(_) => depth_limit,
        None => MAX_DEPTH as u32,
    };
    // The packed node holds 30-bit reference offsets; leave room below that.
    let share = Share(affordable_refs.min(u32::MAX as u64 / 2));
    let threads = rayon::current_num_threads();
    let ctx = Ctx {
        tris: &tris,
        params,
        max_depth: depth_limit,
        large_max_depth,
        root_area: bounds.surface_area(),
        // A few tasks per worker (2^fork_depth ≥ 4 × threads), none with one thread, and
        // only where the reference share is divided in proportion.
        fork_depth: if threads > 1 {
            ((usize::BITS - (threads - 1).leading_zeros()) + 2).min(Share::PROPORTIONAL_DEPTH)
        } else {
            0
        },
    };
    let mut out = Out::default();
    if n > 0 {
        match params.builder {
            Builder::Sah => sah::build(&ctx, &ids, &bounds, share, &mut out),
            Builder::Median => median::build(&ctx, &ids, &bounds, share, &mut out),
        }
    }
    if out.nodes.len() > MAX_PACKED as usize || out.shape.max_leaf_size >= MAX_PACKED {
        return Err(BuildError::Unsupported(format!(
            "{} nodes (largest leaf {}): the packed node format holds at most {MAX_PACKED}",
            out.nodes.len(),
            out.shape.max_leaf_size
        )));
    }
    let stats = stats(&out.shape, n, excluded, depth_limit, bounds.surface_area());
    // The traversal stack must hold the deepest path, which may pass the cost-driven limit.
    let deepest = depth_limit.max(out.shape.max_depth);
    let packed = pack::pack(out.nodes, &out.refs, &tris);
    Ok(Flat {
        nodes: packed.nodes,
        refs: packed.refs,
        tri4s: packed.tri4s,
        prim_ids: packed.prim_ids,
        bounds,
        deepest,
        stats,
    })
}

/// The statistics of a finished tree.
///
/// `sah_cost` is the cost model of a space-partitioning tree with the shared constants, the
/// way the BVH crate computes it for its tree: Σ over interior nodes of
/// `area(cell)/area(root) × C_trav` plus Σ over leaves of `area(cell)/area(root) × refs ×
/// C_isect`, where a cell is the node's region of space (not a tight box, which a k-d tree
/// does not store). Duplicated references are counted in every leaf that holds them. `None`
/// when the root cell has no area.
fn stats(s: &Shape, n: usize, excluded: usize, depth_limit: u32, root_area: f64) -> BuildStats {
    let mut extra = BTreeMap::new();
    let leaves = s.leaves.max(1) as f64;
    let full = (s.leaves - s.empty_leaves).max(1) as f64;
    extra.insert("empty_leaves".into(), s.empty_leaves as f64);
    extra.insert(
        "refs_per_triangle".into(),
        if n > 0 { s.refs as f64 / n as f64 } else { 0.0 },
    );
    extra.insert("mean_leaf_depth".into(), s.leaf_depth_sum as f64 / leaves);
    extra.insert("mean_full_leaf_size".into(), s.refs as f64 / full);
    extra.insert("max_leaf_size".into(), s.max_leaf_size as f64);
    extra.insert("depth_limit".into(), depth_limit as f64);
    extra.insert("excluded_degenerate".into(), excluded as f64);
    extra.insert("depth_capped_leaves".into(), s.depth_capped as f64);
    extra.insert("memory_capped_leaves".into(), s.memory_capped as f64);
    extra.insert(format!("leaves_over_{LARGE_LEAF}"), s.large as f64);
    extra.insert(
        format!("leaves_over_{LARGE_LEAF}_sharing_a_point"),
        s.large_piles as f64,
    );
    BuildStats {
        // Interior nodes plus leaves, as every structure counts them.
        nodes: s.interior + s.leaves,
        leaves: s.leaves,
        max_depth: s.max_depth,
        refs: s.refs,
        sah_cost: (root_area > 0.0 && n > 0).then_some(s.sah),
        extra,
    }
}

/// Bytes a build needs per triangle before any reference exists: the triangle copied twice
/// (36-byte corners, 48-byte ray layout), its id, its new index and its box.
const FIXED_BYTES_PER_TRIANGLE: u64 = 36 + 48 + 4 + 4 + 24;
/// Bytes live per reference at the peak of the SAH build: six 8-byte events and their radix
/// sort scratch, the reference itself and its share of 8-byte nodes.
const BYTES_PER_REF: u64 = 6 * 8 * 2 + 4 + 8;

/// The most references the build may make within `params.memory_limit_bytes`, estimated before
/// allocating anything (the root's [`Share`]); `TooLarge` when not even one reference per
/// triangle fits.
fn references_within_memory(n: usize, params: &KdParams) -> Result<u64, BuildError> {
    let n = n as u64;
    let fixed = n * FIXED_BYTES_PER_TRIANGLE;
    let affordable = params.memory_limit_bytes.saturating_sub(fixed) / BYTES_PER_REF;
    if affordable < n {
        return Err(BuildError::TooLarge {
            needed_bytes: fixed + n * BYTES_PER_REF,
            limit_bytes: params.memory_limit_bytes,
        });
    }
    Ok(affordable)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of triangles around one vertex is a pile even with strays that keep the bounds of
    /// all from meeting; a row of disjoint triangles is not.
    #[test]
    fn a_fan_with_strays_is_a_pile_and_a_row_is_not() {
        let fan: Vec<Triangle> = (0..80)
            .map(|i| {
                let a = i as f32 * 0.07;
                let (s, c) = a.sin_cos();
                Triangle::new(Vec3::ZERO, Vec3::new(c, s, 0.1), Vec3::new(c, s, -0.1))
            })
            .chain((0..3).map(|i| {
                let x = 5.0 + i as f32;
                Triangle::new(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, 1.0, 0.0),
                    Vec3::new(x, 0.0, 1.0),
                )
            }))
            .collect();
        let ids: Vec<u32> = (0..fan.len() as u32).collect();
        assert!(is_pile(&fan, &ids));
        assert!(!is_pile(&fan, &ids[..64]), "64 triangles are never a pile");
        let row: Vec<Triangle> = (0..100)
            .map(|i| {
                let x = i as f32;
                Triangle::new(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x + 0.5, 1.0, 0.0),
                    Vec3::new(x, 0.0, 1.0),
                )
            })
            .collect();
        let ids: Vec<u32> = (0..row.len() as u32).collect();
        assert!(!is_pile(&row, &ids));
    }
}
