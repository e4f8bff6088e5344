//! Closest-point queries: the triangle nearest to a point, within a radius.
//!
//! Depth-first branch and bound, nearest child first (the best-match search of Friedman,
//! Bentley and Finkel, ACM TOMS 1977, on an octree; Samet, *Foundations of Multidimensional
//! and Metric Data Structures*, 2006, §4.1): at an interior node the squared distance from the
//! point to each present octant's box is computed, octants farther than the best triangle so
//! far (or the radius) are dropped, and the rest are searched in increasing order of that
//! distance, each one again only if it is still within the best distance when its turn comes.
//! Leaves test their triangles with the exact point–triangle distance
//! ([`raybench_geom::closest_point_on_triangle`]).
//!
//! The octants' distances come cheaply from the node's split point: per axis, the gaps from
//! the point to the lower and the upper half, squared, and an octant's distance is the sum of
//! the three it selects, so the eight cost six gaps and eight additions. The walk recurses
//! (depth at most [`crate::MAX_DEPTH_LIMIT`]): each level keeps its own box and its sorted
//! octants in a few registers of stack, where an explicit stack would have to hold up to
//! seven waiting octants with their boxes per level and initialise them all for every query.
//!
//! Why it is exact: a triangle is referenced by every leaf it overlaps (insertion tests the
//! octant enlarged by a margin, `build.rs`), so its nearest point lies in a leaf that
//! references it, and that leaf's box is no farther than the triangle. Octants exactly as far
//! as the best are still searched, and the shared [`Nearest`] keeps the lowest id among
//! equally near triangles, so the answer is brute force's bit for bit. Trade-off: the octree
//! adapts to where the triangles are, so near the surface the first leaf is small and holds a
//! close triangle, but every level costs a node visit; a triangle spanning several octants is
//! tested once thanks to the mailbox, and triangles are read from the mesh (an index and three
//! vertex loads), as Embree's point-query callback does, so the distances are bit-identical to
//! brute force's.

use crate::Octree;
use crate::node::{Node, child_box};
use crate::traverse::Mailbox;
use raybench_accel::{CounterSink, Nearest, PointHit};
use raybench_geom::{Vec3, box_distance_squared};

/// One query in flight: the point, the best so far, the mailbox and the counters.
struct Search<'c, C> {
    p: Vec3,
    best: Nearest,
    mailbox: Mailbox,
    counters: &'c mut C,
}

impl Octree {
    /// [`raybench_accel::Walk::walk_point`] on the octree: branch and bound from the root,
    /// nearest octant first.
    pub(crate) fn closest<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<PointHit> {
        if self.refs.is_empty() {
            return None;
        }
        let best = Nearest::within(p, max_radius)?;
        let mut s = Search {
            p,
            best,
            mailbox: Mailbox::new(),
            counters: c,
        };
        let root = self.root_box;
        if box_distance_squared(p, &root) <= s.best.bound_d2() {
            self.visit(0, root.min, root.max, &mut s);
        }
        s.best.into_hit()
    }

    /// Searches node `at`, whose box is `[lo, hi]`.
    fn visit<C: CounterSink>(&self, at: u32, lo: Vec3, hi: Vec3, s: &mut Search<C>) {
        let node = &self.nodes[at as usize];
        if node.is_leaf() {
            s.counters.leaf();
            self.test_leaf(node, s);
            return;
        }
        s.counters.node();
        let mid = Vec3::from_array(node.mid);
        let (octants, n) = octants_by_distance(node.mask(), lo, mid, hi, s);
        for &(d2, o) in &octants[..n] {
            if d2 > s.best.bound_d2() {
                break; // sorted: the rest are farther still
            }
            if let Some(child) = node.child(o) {
                let (clo, chi) = child_box(lo, hi, mid, o);
                self.visit(child, clo, chi, s);
            }
        }
    }

    #[inline(always)]
    fn test_leaf<C: CounterSink>(&self, leaf: &Node, s: &mut Search<C>) {
        let refs = &self.refs[leaf.refs()];
        s.best
            .test_unseen(s.p, &self.mesh, refs, &mut s.mailbox, s.counters);
    }
}

/// The octants present in `mask` of the box `[lo, hi]` split at `mid` that lie within the best
/// distance, as (squared distance, octant), nearest first, and how many there are.
#[inline(always)]
fn octants_by_distance<C>(
    mask: u32,
    lo: Vec3,
    mid: Vec3,
    hi: Vec3,
    s: &Search<C>,
) -> ([(f32, u32); 8], usize) {
    let p = s.p;
    let lower = (lo - p).max(p - mid).max(Vec3::ZERO);
    let upper = (mid - p).max(p - hi).max(Vec3::ZERO);
    let (lower, upper) = ((lower * lower).to_array(), (upper * upper).to_array());
    let mut sorted = [(0f32, 0u32); 8];
    let mut n = 0;
    for o in (0..8).filter(|o| mask & (1 << o) != 0) {
        let gap = |a: usize| {
            if o & (1 << a) != 0 {
                upper[a]
            } else {
                lower[a]
            }
        };
        let d2 = gap(0) + gap(1) + gap(2);
        if d2 > s.best.bound_d2() {
            continue;
        }
        // Insertion sort: at most eight entries.
        let mut i = n;
        while i > 0 && sorted[i - 1].0 > d2 {
            sorted[i] = sorted[i - 1];
            i -= 1;
        }
        sorted[i] = (d2, o);
        n += 1;
    }
    (sorted, n)
}
