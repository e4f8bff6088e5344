//! Split BVH (SBVH; Stich, Friedrich and Dietrich 2009, "Spatial Splits in Bounding Volume
//! Hierarchies"): at each node the binned object split is weighed against a spatial split, a
//! plane that cuts the triangles crossing it into one reference per side, each with the box of
//! its piece ([`bins`], [`mod@divide`]). Where long or diagonal triangles make the object split's
//! children overlap, cutting them shrinks the boxes a ray must enter, at the price of more
//! references (a triangle may be tested twice on a ray) and a slower build. Two limits keep
//! the price down: a spatial split is only tried where the object split's children overlap by
//! more than `alpha` × the root's area and by at least `overlap_share` × the node's own area
//! (as in Embree's spatial-split builder), and the references may grow to at most
//! `1 + max_reference_growth` times the triangles, a budget shared top-down between the
//! children in proportion to their references (as Embree's spatial-split builder shares its
//! extra space), so the tree does not depend on which task builds what first. Below a node
//! whose own area is under the `alpha` limit (no children of it can overlap more) or whose
//! budget is spent, the plain binned builder takes over the range. Caveats: a duplicated
//! triangle is tested once per reference a ray reaches, with the same answer (no mailbox: the
//! closest hit does not change); a ray finds a triangle only because its pieces' boxes cover
//! it, which the outward rounding of the cuts ([`chop`]) guarantees and the validators check;
//! and the choice is greedy, node by node, with an SAH that does not price memory, so on a
//! scene such as `grass` the tree can have the lower SAH cost and still run slower than the
//! binned one (its splits of small nodes add wide nodes that miss the caches); a triangle
//! spanning the scene (the ground of `city`) is cut at most `max_cuts` times along any line of
//! cuts, so its pieces no longer fill the budget.

mod bins;
pub(crate) mod chop;
mod divide;

pub use bins::MAX_SPATIAL_BINS;

use super::split::{PARALLEL_BINNING, Scratch, Split, binned_split, leaf_beats_any_split};
use super::split::{split_cost, worth_splitting};
use super::{Flat, Part, Ranged, build_local, build_part, interior, task_grain};
use crate::BvhParams;
use crate::build::{Box3, PrimRef};
use crate::node::{ChildRef, MAX_DEPTH, Node};
use bins::{Limits, SlabBins, SpatialSplit, best_spatial_split};
use divide::divide;
use raybench_geom::{Aabb, TriangleMesh};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};

/// The knobs of spatial splits (`BvhParams::spatial_splits`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpatialSplits {
    /// A spatial split is tried at a node only when the boxes of its best object split's
    /// children overlap by more than this fraction of the root box's surface area (the
    /// paper's α; 1e-5 there). 1e-4: against 1e-5, the same SAH cost within 0.7 % on Sponza,
    /// the dragon, conference and hair, for 20–40 % less build time; 1e-3 builds the dragon
    /// in half the time again but costs 1.5 % SAH on conference (`examples/sbvh_tune`,
    /// 2 threads, 2026-11-26, with `intersection_cost` at 0.15).
    pub alpha: f32,
    /// The references may number at most `(1 + max_reference_growth)` × the triangles. 0.5:
    /// hair uses all of it (SAH 8835 binned, 8130 at 0.25, 7389 at 0.5, 6870 at 1.0, build
    /// 462, 403 and 685 ms); the real scenes stop short of it (growth 1.02 to 1.21; measured
    /// with `intersection_cost` at 0.15).
    pub max_reference_growth: f32,
    /// The SAH cost of a triangle test (a node step costing 1) in the choice between the object
    /// and the spatial split, and between a spatial split and a leaf; the object splits keep
    /// the binary builder's `intersection_cost`. The higher it is, the more the small nodes the
    /// object split leaves as leaves are cut by spatial splits into smaller leaves: more leaves
    /// a ray visits for fewer triangle tests (the bunny: 8,379 spatial splits at 1, 1,247 at
    /// 0.3). 0.3: against 1, the race suite's traversal within noise and its build 7 % faster;
    /// nine generated scenes at seed 7 random rays +4 %, shadow +2.5 %, diffuse +3 %, whitted
    /// +2 % (see docs/experiments.md, "0.3 per triangle test in the spatial split's choices").
    pub intersection_cost: f32,
    /// Slabs per axis in the spatial split's binning (at most [`MAX_SPATIAL_BINS`]). 16: on
    /// hair (50,000 triangles) the same SAH cost as 32 (7389 against 7394) in 403 ms instead of
    /// 644; 8 gives 7399 in 302 ms (`examples/sbvh_tune`, 2 threads, 2026-11-26, with
    /// `intersection_cost` at 0.15). With `overlap_share` at 0.3, 8 slabs leave city's SAH cost
    /// above the binned tree's (docs/experiments.md, "8 slabs instead of 16").
    pub spatial_bins: u32,
    /// A spatial split is tried at a node only when, besides `alpha`, the boxes of its best
    /// object split's children overlap by at least this share of the node's own surface area
    /// (Embree's spatial-split builder makes the same test, with 0.1). Where the children
    /// barely overlap, a cut through their triangles has little to win, while the search —
    /// every reference that crosses a candidate plane clipped there, on three axes — is still
    /// the largest part of the node's work (60 % of soup 200k's build in a profile).
    /// 0.3 (from 0 to 1): see docs/experiments.md, "spatial splits searched only where the
    /// object split's children overlap by a share of the node".
    pub overlap_share: f32,
    /// A reference is cut at most this many times from its triangle (from 0 to 64),
    /// so a triangle ends in at most `2^max_cuts` pieces; a reference at the limit that
    /// crosses a split's plane stays whole on the cheaper side. Counted along each piece's own
    /// line of cuts, not per triangle over the build, so the tree does not depend on the order
    /// the tasks run in. 6 (at most 64 pieces): city's two ground triangles were cut over a
    /// thousand times each without it; at 6 its SAH cost falls from 29.55 to 27.66 (the binned
    /// tree 28.26) and its build from 105 to 62 ms, while Sponza, hair, conference and seven of
    /// nine generated scenes at other sizes keep the same trees and grass all but one split; 4
    /// changes those (docs/experiments.md, "at most `max_cuts` cuts").
    pub max_cuts: u32,
}

impl Default for SpatialSplits {
    fn default() -> Self {
        SpatialSplits {
            alpha: 1e-4,
            max_reference_growth: 0.5,
            spatial_bins: 16,
            intersection_cost: 0.3,
            overlap_share: 0.3,
            max_cuts: 6,
        }
    }
}

/// What a build with spatial splits did, for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SpatialReport {
    pub spatial_splits: u64,
    /// Nodes where a spatial split was searched for (taken or not): what the build time
    /// follows.
    pub spatial_searches: u64,
}

/// The fixed inputs of every node.
struct Ctx<'a> {
    p: &'a BvhParams,
    s: &'a SpatialSplits,
    mesh: &'a TriangleMesh,
    /// `alpha` × the root's half area.
    min_overlap: f64,
    /// Nodes of more references than this split their children on two rayon tasks.
    grain: usize,
    /// The binary builder's knobs with the spatial splits' `intersection_cost`.
    priced: BvhParams,
    /// Spatial splits searched for so far, on every task: a count of a set of nodes that does
    /// not depend on the tasks, so the total does not either.
    searches: AtomicU64,
}

/// A subtree as the spatial builder returns it, before flattening. Its references stay in
/// the build's one array, at the positions the build gave them.
enum Tree {
    /// A leaf of `count` references from position `at`.
    Leaf { at: usize, count: usize },
    Node {
        bounds: [Aabb; 2],
        spatial: bool,
        children: Box<(Tree, Tree)>,
    },
    /// A range of `count` references from position `at` that the binned builder built in
    /// place, its leaves numbered from 0 within the range.
    Binned { part: Part, at: usize, count: usize },
}

/// Per-task working memory.
struct Work {
    binned: Box<Scratch>,
    slabs: Box<SlabBins>,
    /// A spatial split's two sides, before they go back into the array.
    left: Vec<PrimRef>,
    right: Vec<PrimRef>,
}

impl Work {
    fn new() -> Work {
        Work {
            binned: Scratch::new(),
            slabs: SlabBins::new(),
            left: Vec::new(),
            right: Vec::new(),
        }
    }
}

/// Builds the tree of a non-empty mesh with spatial splits.
///
/// The references live in one array with room for the whole budget of duplicates, as in
/// Embree's spatial-split builder: a node owns a slice of it whose front holds its references
/// and whose rest is room for as many more as its budget allows. A split leaves each child's
/// references at the front of the child's own slice, so nodes neither allocate nor copy into
/// new vectors; a spatial split's pieces are written back over the node's references.
pub(crate) fn build(mesh: &TriangleMesh, p: &BvhParams, s: &SpatialSplits) -> Flat {
    let n = mesh.len();
    let budget = (n as f64 * s.max_reference_growth.max(0.0) as f64) as usize;
    let mut refs: Vec<PrimRef> = Vec::with_capacity(n + budget);
    (0..n)
        .into_par_iter()
        .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
        .collect_into_vec(&mut refs);
    let whole = Ranged::of(&refs, PARALLEL_BINNING);
    // The room past the triangles' records: never read before a split writes it.
    refs.resize(n + budget, PrimRef::new(&Aabb::EMPTY, 0));
    let ctx = Ctx {
        p,
        s,
        mesh,
        min_overlap: s.alpha as f64 * whole.bounds.half_area(),
        grain: task_grain(p, n),
        priced: BvhParams {
            intersection_cost: s.intersection_cost,
            ..p.clone()
        },
        searches: AtomicU64::new(0),
    };
    let tree = ctx.node(
        Slot::new(&mut refs, 0, n),
        whole,
        0,
        budget,
        &mut Work::new(),
    );
    let mut out = Flat {
        nodes: Vec::with_capacity(n),
        refs: Vec::with_capacity(n),
        root: ChildRef::default(),
        root_bounds: whole.bounds.to_aabb(),
        spatial: Some(SpatialReport::default()),
    };
    out.root = tree.flatten(&refs, &mut out);
    if let Some(s) = out.spatial.as_mut() {
        s.spatial_searches = ctx.searches.into_inner();
    }
    out
}

/// A node's slice of the reference array: its `count` references at the front, room for more
/// behind them; `at` is where the slice starts in the whole array.
struct Slot<'a> {
    refs: &'a mut [PrimRef],
    at: usize,
    count: usize,
}

impl<'a> Slot<'a> {
    fn new(refs: &'a mut [PrimRef], at: usize, count: usize) -> Slot<'a> {
        debug_assert!(count <= refs.len());
        Slot { refs, at, count }
    }

    fn live(&mut self) -> &mut [PrimRef] {
        &mut self.refs[..self.count]
    }
}

/// Where a split leaves its children in the node's slice: the left child's references at the
/// front, the right child's from `right_at`, each side followed by the room for its budget.
struct Placed {
    counts: [usize; 2],
    budgets: [usize; 2],
    right_at: usize,
    /// Both sides' bounds, when the split measured them already (an object split: its bins'
    /// boxes are the unions of the records' boxes), so the children need no pass over them.
    measured: Option<[Ranged; 2]>,
    spatial: bool,
}

impl Placed {
    /// Shares the budget left after `duplicates` between the sides in proportion to their
    /// references.
    fn new(counts: [usize; 2], budget: usize, duplicates: usize, spatial: bool) -> Placed {
        let [nl, nr] = counts;
        let rest = budget.saturating_sub(duplicates);
        let left = (rest as u128 * nl as u128 / (nl + nr) as u128) as usize;
        Placed {
            counts,
            budgets: [left, rest - left],
            right_at: nl + left,
            measured: None,
            spatial,
        }
    }

    /// The slice length both sides with their room need.
    fn needs(&self) -> usize {
        self.right_at + self.counts[1] + self.budgets[1]
    }
}

impl Ctx<'_> {
    fn node(&self, mut slot: Slot, r: Ranged, depth: usize, budget: usize, w: &mut Work) -> Tree {
        let (p, n) = (self.p, slot.count);
        debug_assert!(slot.refs.len() >= n + budget, "room for the budget");
        if budget == 0 || r.bounds.half_area() <= self.min_overlap {
            return self.binned(slot, r, depth, w);
        }
        if n == 1 || depth + 1 >= MAX_DEPTH || leaf_beats_any_split(p, n) {
            return Tree::Leaf {
                at: slot.at,
                count: n,
            };
        }
        let object = binned_split(slot.live(), &r, p, &mut w.binned);
        let parent = r.bounds.half_area();
        let q = &self.priced;
        let object_cost = object.map(|o| {
            let (l, r) = (
                (o.left.bounds.half_area(), o.mid),
                (o.right.bounds.half_area(), n - o.mid),
            );
            split_cost(q, parent, l, r)
        });
        let overlap = object.map_or(f64::INFINITY, |o| {
            let both = chop::intersect(&o.left.bounds, &o.right.bounds);
            if chop::is_empty(&both) {
                0.0
            } else {
                both.half_area()
            }
        });
        if overlap > self.min_overlap
            && overlap >= self.s.overlap_share as f64 * parent
            && let Some(s) = self.search(slot.live(), &r.bounds, budget, object_cost, w)
            && object_cost.is_none_or(|c| s.cost < c)
            && worth_splitting(q, n, s.cost)
            && let Some(duplicates) = divide(
                slot.live(),
                self.mesh,
                &s,
                self.s.max_cuts,
                &mut w.left,
                &mut w.right,
            )
        {
            let placed = Placed::new([w.left.len(), w.right.len()], budget, duplicates, true);
            // Only a cut the binning misjudged can add more references than the budget
            // holds room for; the object split stands in for it.
            if placed.needs() <= slot.refs.len() {
                let [nl, nr] = placed.counts;
                slot.refs[..nl].copy_from_slice(&w.left);
                slot.refs[placed.right_at..placed.right_at + nr].copy_from_slice(&w.right);
                return self.children(slot, placed, depth, w);
            }
        }
        let split = match object {
            Some(o) => o,
            None if n <= p.max_leaf_size as usize => {
                return Tree::Leaf {
                    at: slot.at,
                    count: n,
                };
            }
            // Centroids indistinguishable and no plane worth cutting: halves as they are.
            None => Split::at(slot.live(), n / 2),
        };
        let mut placed = Placed::new([split.mid, n - split.mid], budget, 0, false);
        placed.measured = Some([split.left, split.right]);
        // The right side moves behind the left side's room.
        slot.refs.copy_within(split.mid..n, placed.right_at);
        self.children(slot, placed, depth, w)
    }

    /// The cheapest spatial split of a node's references, counted for the report.
    fn search(
        &self,
        refs: &[PrimRef],
        bounds: &Box3,
        budget: usize,
        beat: Option<f64>,
        w: &mut Work,
    ) -> Option<SpatialSplit> {
        self.searches.fetch_add(1, Ordering::Relaxed);
        let limits = Limits {
            slabs: self.s.spatial_bins as usize,
            budget,
            beat,
        };
        best_spatial_split(refs, self.mesh, bounds, &self.priced, limits, &mut w.slabs)
    }

    /// Builds both children of a split as `placed` left them in `slot` (on two rayon tasks
    /// above the parallel threshold).
    fn children(&self, slot: Slot, placed: Placed, depth: usize, w: &mut Work) -> Tree {
        let [nl, nr] = placed.counts;
        let (left_refs, right_refs) = slot.refs.split_at_mut(placed.right_at);
        let [left, right] = placed.measured.unwrap_or_else(|| {
            [
                Ranged::of(&left_refs[..nl], PARALLEL_BINNING),
                Ranged::of(&right_refs[..nr], PARALLEL_BINNING),
            ]
        });
        let bounds = [left.bounds.to_aabb(), right.bounds.to_aabb()];
        let left_slot = Slot::new(left_refs, slot.at, nl);
        let right_slot = Slot::new(right_refs, slot.at + placed.right_at, nr);
        let [left_budget, right_budget] = placed.budgets;
        let children = if nl + nr > self.grain {
            rayon::join(
                || self.node(left_slot, left, depth + 1, left_budget, w),
                || self.node(right_slot, right, depth + 1, right_budget, &mut Work::new()),
            )
        } else {
            let a = self.node(left_slot, left, depth + 1, left_budget, w);
            (a, self.node(right_slot, right, depth + 1, right_budget, w))
        };
        Tree::Node {
            bounds,
            spatial: placed.spatial,
            children: Box::new(children),
        }
    }

    /// The plain binned builder over a node's references, in place, where no spatial split
    /// can be tried.
    fn binned(&self, mut slot: Slot, r: Ranged, depth: usize, w: &mut Work) -> Tree {
        let (at, count) = (slot.at, slot.count);
        let refs = slot.live();
        let part = if count > self.grain {
            build_part(self.p, self.grain, refs, 0, r, depth, &mut w.binned)
        } else {
            let mut nodes = Vec::new();
            let root = build_local(self.p, refs, 0, r, depth, &mut nodes, &mut w.binned);
            Part::Local { nodes, root }
        };
        Tree::Binned { part, at, count }
    }
}

impl Tree {
    /// Appends this subtree's nodes, and its references from `refs` (the build's array), to
    /// `out` depth-first; returns its root.
    fn flatten(self, refs: &[PrimRef], out: &mut Flat) -> ChildRef {
        match self {
            Tree::Leaf { at, count } => {
                let r = ChildRef {
                    index: out.refs.len() as u32,
                    count: count as u32,
                };
                out.refs.extend_from_slice(&refs[at..at + count]);
                r
            }
            Tree::Node {
                bounds,
                spatial,
                children,
            } => {
                if spatial && let Some(s) = out.spatial.as_mut() {
                    s.spatial_splits += 1;
                }
                let at = out.nodes.len();
                out.nodes.push(Node::new(
                    [&bounds[0], &bounds[1]],
                    [ChildRef::default(); 2],
                ));
                let (a, b) = *children;
                let a = a.flatten(refs, out);
                let b = b.flatten(refs, out);
                out.nodes[at].child = [a, b];
                interior(at)
            }
            Tree::Binned { part, at, count } => {
                // The binned builder numbered its leaves from 0: shift them to where its
                // references land.
                let (first_node, offset) = (out.nodes.len(), out.refs.len() as u32);
                let mut root = part.flatten(&mut out.nodes);
                for node in &mut out.nodes[first_node..] {
                    for c in node.child.iter_mut().filter(|c| c.is_leaf()) {
                        c.index += offset;
                    }
                }
                if root.is_leaf() {
                    root.index += offset;
                }
                out.refs.extend_from_slice(&refs[at..at + count]);
                root
            }
        }
    }
}

/// Adds to a tree's statistics what spatial splits did: the splits taken and the references
/// per triangle (1 without duplicates). Nothing for a tree built without them.
pub(crate) fn spatial_stats(
    stats: &mut raybench_accel::BuildStats,
    report: Option<SpatialReport>,
    triangles: usize,
) {
    let Some(r) = report else { return };
    stats
        .extra
        .insert("spatial_splits".into(), r.spatial_splits as f64);
    stats
        .extra
        .insert("spatial_searches".into(), r.spatial_searches as f64);
    stats.extra.insert(
        "reference_growth".into(),
        stats.refs as f64 / triangles.max(1) as f64,
    );
}

#[cfg(test)]
mod tests;
