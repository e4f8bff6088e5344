//! BVH construction over one array of 32-byte primitive records (`prim::PrimRef`: a
//! triangle's box and its mesh index) that every node reorders in place, each node owning a
//! contiguous range.
//!
//! Three ways to choose a split, each a function in `split` with its own note:
//! * `median_split` — object median on the longest centroid axis;
//! * `sweep_split` — full-sweep SAH;
//! * `binned_split` — binned SAH.
//!
//! Termination and degenerate input are handled once, in `decide`: a range of one triangle,
//! at [`MAX_DEPTH`], or so small that its leaf costs no more than one node step (no split can
//! then be cheaper), is a leaf; a split function returns `None` when it finds no way (or no
//! profitable way) to separate the centroids, and then a range that fits in a leaf becomes
//! one, while a larger range is cut in half in its current order — all centroids equal, say —
//! so recursion always shrinks the range and always ends.
//!
//! Shape of the build: ranges above a grain (`parallel_threshold`, finer on small meshes when
//! there are several threads: see `grain.rs`) are split on two rayon tasks (`Part::Split`);
//! each range at or below it is built sequentially straight into its own depth-first node
//! vector (`Part::Local`), all its nodes sharing one `split::Scratch` (which the left side of
//! each `Part::Split` takes over from its parent). Flattening then copies every node exactly
//! once, relocating child indices — no node is boxed or allocated on its own.

mod prim;
pub mod reinsert;
mod spatial;
mod split;

pub use spatial::{MAX_SPATIAL_BINS, SpatialSplits};
pub(crate) use spatial::{SpatialReport, spatial_stats};
pub use split::MAX_BINS;

use crate::node::{ChildRef, MAX_DEPTH, Node};
use crate::{Builder, BvhParams};
pub(crate) use prim::{Box3, PrimRef};
use prim::{MAX_CUTS, MAX_PRIMS, Ranged};
use raybench_accel::{BuildError, BuildStats, SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST};
use raybench_geom::{Aabb, TriangleMesh};
use rayon::prelude::*;
pub(crate) use split::blocks;
use split::{
    PARALLEL_BINNING, Scratch, Split, binned_split, leaf_beats_any_split, median_split, sweep_split,
};

/// A built and flattened tree.
pub(crate) struct Flat {
    pub nodes: Vec<Node>,
    /// Every triangle's record (box and mesh index), in leaf order: leaf `{ index, count }`
    /// holds `refs[index..index + count]`.
    pub refs: Vec<PrimRef>,
    pub root: ChildRef,
    pub root_bounds: Aabb,
    /// What spatial splits did, when the build used them.
    pub spatial: Option<SpatialReport>,
}

/// Peak bytes per triangle of a build: its 32-byte record, up to one 64-byte node in the
/// per-task vectors and again in the flattened array, its id, and its 48-byte triangle copy
/// (or its share of a wide tree's `Tri4`s and nodes, no more than that).
const PEAK_BYTES_PER_TRIANGLE: u64 = 32 + 2 * 64 + 4 + 48;

pub(crate) fn build(mesh: &TriangleMesh, params: &BvhParams) -> Result<Flat, BuildError> {
    let n = mesh.len();
    // Duplicated references take a record, a leaf slot and a triangle copy each.
    let growth = params
        .spatial_splits
        .map_or(0.0, |s| s.max_reference_growth.max(0.0) as f64);
    let needed_bytes = (n as f64 * (1.0 + growth)) as u64 * PEAK_BYTES_PER_TRIANGLE;
    if needed_bytes > params.memory_limit_bytes {
        return Err(BuildError::TooLarge {
            needed_bytes,
            limit_bytes: params.memory_limit_bytes,
        });
    }
    if n > MAX_PRIMS {
        return Err(BuildError::Unsupported(format!(
            "{n} triangles; the BVH builder holds at most {MAX_PRIMS}"
        )));
    }
    if n == 0 {
        return Ok(Flat {
            nodes: Vec::new(),
            refs: Vec::new(),
            root: ChildRef::default(),
            root_bounds: Aabb::EMPTY,
            spatial: params.spatial_splits.map(|_| SpatialReport::default()),
        });
    }
    if let Some(s) = &params.spatial_splits {
        if !(2..=MAX_SPATIAL_BINS as u32).contains(&s.spatial_bins) {
            return Err(BuildError::Unsupported(format!(
                "spatial_bins from 2 to {MAX_SPATIAL_BINS} (got {})",
                s.spatial_bins
            )));
        }
        if !(0.0..=1.0).contains(&s.overlap_share) {
            return Err(BuildError::Unsupported(format!(
                "overlap_share from 0 to 1 (got {})",
                s.overlap_share
            )));
        }
        if s.max_cuts > MAX_CUTS {
            return Err(BuildError::Unsupported(format!(
                "max_cuts from 0 to {MAX_CUTS} (got {})",
                s.max_cuts
            )));
        }
        return Ok(spatial::build(mesh, params, s));
    }
    let mut refs: Vec<PrimRef> = (0..n)
        .into_par_iter()
        .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
        .collect();
    let whole = Ranged::of(&refs, PARALLEL_BINNING);
    let grain = task_grain(params, n);
    let part = build_part(params, grain, &mut refs, 0, whole, 0, &mut Scratch::new());
    // At most n - 1 interior nodes in a binary tree with n or fewer leaves.
    let mut nodes = Vec::with_capacity(n - 1);
    let root = part.flatten(&mut nodes);
    let root_bounds = whole.bounds.to_aabb();
    Ok(Flat {
        refs,
        nodes,
        root,
        root_bounds,
        spatial: None,
    })
}

/// A piece of the tree as the parallel build returns it.
enum Part {
    /// Built by one task: a leaf (`nodes` empty), or nodes depth-first from local index 0 whose
    /// interior child references are local too.
    Local { nodes: Vec<Node>, root: ChildRef },
    /// A node split above the parallel threshold, with its two pieces.
    Split {
        bounds: [Aabb; 2],
        children: Box<(Part, Part)>,
    },
}

impl Flat {
    /// The mesh index of every triangle, in leaf order.
    pub fn prim_ids(&self) -> Vec<u32> {
        self.refs.iter().map(PrimRef::id).collect()
    }
}

impl Part {
    /// Appends this piece to `out` depth-first and returns the reference to its root.
    fn flatten(self, out: &mut Vec<Node>) -> ChildRef {
        match self {
            Part::Local { root, .. } if root.is_leaf() => root,
            Part::Local { nodes, .. } => {
                let base = out.len() as u32;
                out.extend(nodes.into_iter().map(|mut node| {
                    for c in node.child.iter_mut().filter(|c| !c.is_leaf()) {
                        c.index += base;
                    }
                    node
                }));
                interior(base as usize)
            }
            Part::Split { bounds, children } => {
                let at = out.len();
                out.push(Node::new(
                    [&bounds[0], &bounds[1]],
                    [ChildRef::default(); 2],
                ));
                let (a, b) = *children;
                out[at].child = [a.flatten(out), b.flatten(out)];
                interior(at)
            }
        }
    }
}

fn interior(index: usize) -> ChildRef {
    ChildRef {
        index: index as u32,
        count: 0,
    }
}

/// Ranges of more triangles than this, in a build of `n`, are split on two rayon tasks: the
/// `parallel_threshold` on large meshes or one thread, finer on small ones (see `grain.rs`).
fn task_grain(p: &BvhParams, n: usize) -> usize {
    crate::grain::grain(n, MIN_TASK, p.parallel_threshold as usize)
}

/// The fewest triangles a range built on its own task has (unless `parallel_threshold` is
/// lower): below this the fork and the task's own node vector cost more than they balance.
const MIN_TASK: usize = 256;

/// Builds `refs` (which start at triangle `first`) on rayon tasks while they hold more than
/// `grain` triangles. The left side of each split goes on with `scratch` and the right side,
/// which another thread may take, makes its own.
fn build_part(
    p: &BvhParams,
    grain: usize,
    refs: &mut [PrimRef],
    first: u32,
    r: Ranged,
    depth: usize,
    scratch: &mut Scratch,
) -> Part {
    let n = refs.len();
    if n <= grain {
        let mut nodes = Vec::new();
        let root = build_local(p, refs, first, r, depth, &mut nodes, scratch);
        return Part::Local { nodes, root };
    }
    let Some(s) = decide(p, refs, &r, depth, scratch) else {
        let root = ChildRef {
            index: first,
            count: n as u32,
        };
        return Part::Local {
            nodes: Vec::new(),
            root,
        };
    };
    let (left, right) = refs.split_at_mut(s.mid);
    let right_first = first + s.mid as u32;
    let children = rayon::join(
        || build_part(p, grain, left, first, s.left, depth + 1, scratch),
        || {
            let scratch = &mut Scratch::new();
            build_part(p, grain, right, right_first, s.right, depth + 1, scratch)
        },
    );
    Part::Split {
        bounds: [s.left.bounds.to_aabb(), s.right.bounds.to_aabb()],
        children: Box::new(children),
    }
}

/// Builds `refs` sequentially into `out`, depth-first; returns the reference to the subtree.
fn build_local(
    p: &BvhParams,
    refs: &mut [PrimRef],
    first: u32,
    r: Ranged,
    depth: usize,
    out: &mut Vec<Node>,
    scratch: &mut Scratch,
) -> ChildRef {
    let Some(s) = decide(p, refs, &r, depth, scratch) else {
        return ChildRef {
            index: first,
            count: refs.len() as u32,
        };
    };
    let at = out.len();
    out.push(Node::new(
        [&s.left.bounds.to_aabb(), &s.right.bounds.to_aabb()],
        [ChildRef::default(); 2],
    ));
    let (left, right) = refs.split_at_mut(s.mid);
    let a = build_local(p, left, first, s.left, depth + 1, out, scratch);
    let b = build_local(
        p,
        right,
        first + s.mid as u32,
        s.right,
        depth + 1,
        out,
        scratch,
    );
    out[at].child = [a, b];
    interior(at)
}

/// Whether and where a range splits: `None` makes it a leaf.
fn decide(
    p: &BvhParams,
    refs: &mut [PrimRef],
    r: &Ranged,
    depth: usize,
    scratch: &mut Scratch,
) -> Option<Split> {
    let n = refs.len();
    if n == 1 || depth + 1 >= MAX_DEPTH || leaf_beats_any_split(p, n) {
        return None;
    }
    let split = match p.builder {
        Builder::Median => median_split(refs, r, p),
        Builder::Sweep => sweep_split(refs, r, p),
        Builder::Binned => binned_split(refs, r, p, scratch),
    };
    match split {
        Some(s) => {
            debug_assert!(
                0 < s.mid && s.mid < n,
                "a split leaves both sides non-empty"
            );
            Some(s)
        }
        None if n <= p.max_leaf_size as usize => None,
        // Centroids indistinguishable: cut the range in half as it is.
        None => Some(Split::at(refs, n / 2)),
    }
}

/// Facts measured on the flattened tree (what traversal walks), turned into [`BuildStats`] on
/// request (`build_stats`), outside the timed build: Embree's build computes no statistics
/// either.
#[derive(Default)]
pub(crate) struct Shape {
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
    pub(crate) fn measure(nodes: &[Node], root: ChildRef, root_bounds: &Aabb) -> BuildStats {
        let mut shape = Shape::default();
        shape.visit(nodes, root, root_bounds, 0, root_bounds.surface_area());
        shape.stats()
    }

    /// Each node's traversal cost and each leaf's triangle tests, weighted by the probability
    /// that a random ray through the root box also crosses the node's box (area ratio).
    fn visit(&mut self, nodes: &[Node], r: ChildRef, bounds: &Aabb, depth: u32, root_area: f64) {
        self.max_depth = self.max_depth.max(depth);
        let work = if r.is_leaf() {
            self.leaves += 1;
            self.refs += r.count as u64;
            self.leaf_depth_sum += depth as u64;
            self.max_leaf_size = self.max_leaf_size.max(r.count);
            SAH_INTERSECTION_COST * r.count as f64
        } else {
            self.nodes += 1;
            let node = &nodes[r.index as usize];
            for i in 0..2 {
                self.visit(
                    nodes,
                    node.child[i],
                    &node.child_bounds(i),
                    depth + 1,
                    root_area,
                );
            }
            SAH_TRAVERSAL_COST
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
