//! Closest-point queries: the triangle nearest to a point, within a radius.
//!
//! Nearest-neighbour search in a k-d tree (Friedman, Bentley and Finkel, "An Algorithm for
//! Finding Best Matches in Logarithmic Expected Time", ACM TOMS 3(3), 1977) with the
//! incremental cell distance of Arya and Mount ("Algorithms for fast vector quantization",
//! DCC 1993). At each node the child on the point's side of the plane is entered first and the
//! other one is pushed with the squared distance from the point to its cell (the node's cell
//! clipped by the plane); a pushed cell is entered only if that distance is still within the
//! best squared distance found so far when it is popped. Leaves test their triangles with the
//! exact point–triangle distance ([`raybench_geom::closest_point_on_triangle`]).
//!
//! The cell is carried on the stack as the point's per-axis offsets from it (how far the point
//! lies outside the cell's slab on each axis, 0 inside): the far child differs from its parent
//! only on the split axis, where the offset becomes `|p - split|`, so one subtraction replaces
//! a box clip and an entry is 20 bytes, not 28. The sum of the squared offsets is exactly
//! [`raybench_geom::box_distance_squared`] of the clipped box.
//!
//! Why it is exact: every leaf a triangle's clipped bounds reach references it (`validate.rs`),
//! so the triangle's nearest point lies in a leaf that references it, and that leaf's cell is
//! no farther from the query than the triangle; pruning cells farther than the best triangle
//! never drops the answer. Cells exactly as far as the best are still entered, and the shared
//! [`Nearest`] keeps the lowest id among equally near triangles, so the answer is brute
//! force's bit for bit whatever order the walk meets them in.
//!
//! Trade-off: cells do not overlap and the SAH cut away empty space, so the first leaf usually
//! holds a close triangle and the bound tightens at once; the price is that a triangle crossing
//! several leaves is met several times, which the mailbox turns into one test. Triangles are
//! read from the mesh (an index and three vertex loads), as Embree's point-query callback
//! does, so the distances are the same f32 values brute force computes.
//!
//! Zero-area triangles are not in the tree rays walk; they sit in a side tree of their own
//! (see [`crate::build`]) that is searched afterwards with the best distance so far as its
//! radius, which costs one box test when none of them is close.

use crate::KdTree;
use crate::node::{MAX_DEPTH, Node};
use crate::traverse::SMALL_STACK;
use raybench_accel::{CounterSink, Mailbox, Nearest, PointHit};
use raybench_geom::{Aabb, Vec3};

/// Mailbox slots for point queries, a power of two. A point query visits more leaves than a
/// ray (every leaf within the best distance), so it gets a larger table than the ray walk's 8.
pub const POINT_MAILBOX_SLOTS: usize = 32;

/// How far `p` lies outside `b` on each axis (0 inside the slab).
#[inline(always)]
fn outside_offsets(p: Vec3, b: &Aabb) -> [f32; 3] {
    (b.min - p).max(p - b.max).max(Vec3::ZERO).to_array()
}

/// Squared length of the offsets, summed in [`Vec3::length_squared`]'s order.
#[inline(always)]
fn squared(o: [f32; 3]) -> f32 {
    o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
}

impl KdTree {
    /// [`raybench_accel::Walk::walk_point`] over both trees: the tree rays walk, then the
    /// zero-area side tree with the best distance so far as its radius.
    pub(crate) fn closest<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<PointHit> {
        let mut best = Nearest::within(p, max_radius)?;
        self.search(p, &mut best, c);
        if let Some(side) = &self.zero_area {
            side.search(p, &mut best, c);
        }
        best.into_hit()
    }

    /// Picks the stack size (as the ray walk does) and the mailbox setting.
    fn search<C: CounterSink>(&self, p: Vec3, best: &mut Nearest, c: &mut C) {
        match (
            self.params.mailbox,
            self.depth_limit as usize <= SMALL_STACK,
        ) {
            (true, true) => self.search_with::<true, SMALL_STACK, C>(p, best, c),
            (true, false) => self.search_with::<true, MAX_DEPTH, C>(p, best, c),
            (false, true) => self.search_with::<false, SMALL_STACK, C>(p, best, c),
            (false, false) => self.search_with::<false, MAX_DEPTH, C>(p, best, c),
        }
    }

    /// The one walk. A descent pushes at most one far child per level, so the stack never
    /// holds more entries than the tree is deep (at most `depth_limit <= STACK`).
    fn search_with<const MAILBOX: bool, const STACK: usize, C: CounterSink>(
        &self,
        p: Vec3,
        best: &mut Nearest,
        c: &mut C,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut off = outside_offsets(p, &self.bounds);
        if squared(off) > best.bound_d2() {
            return;
        }
        let pa = p.to_array();
        let mut mailbox = Mailbox::<POINT_MAILBOX_SLOTS>::new();
        let mut stack = [(0u32, 0f32, [0f32; 3]); STACK];
        let mut sp = 0;
        let mut at = 0u32;
        loop {
            let mut node = self.nodes[at as usize];
            while !node.is_leaf() {
                c.node();
                let a = node.axis();
                let diff = pa[a] - node.split();
                let (below, above) = (at + 1, node.above());
                // On the plane (diff == 0) both cells touch the point; either is "near".
                let (near, far) = if diff < 0.0 {
                    (below, above)
                } else {
                    (above, below)
                };
                let mut far_off = off;
                far_off[a] = diff.abs();
                let far_d2 = squared(far_off);
                if far_d2 <= best.bound_d2() {
                    stack[sp] = (far, far_d2, far_off);
                    sp += 1;
                }
                at = near;
                node = self.nodes[at as usize];
            }
            c.leaf();
            self.test_leaf::<MAILBOX, C>(node, p, best, &mut mailbox, c);
            // The next pending cell still within the best distance, if any.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (next, d2, next_off) = stack[sp];
                if d2 <= best.bound_d2() {
                    at = next;
                    off = next_off;
                    break;
                }
            }
        }
    }

    #[inline(always)]
    fn test_leaf<const MAILBOX: bool, C: CounterSink>(
        &self,
        leaf: Node,
        p: Vec3,
        best: &mut Nearest,
        mailbox: &mut Mailbox<POINT_MAILBOX_SLOTS>,
        c: &mut C,
    ) {
        let first = leaf.first() as usize;
        for &r in &self.refs[first..first + leaf.count() as usize] {
            if MAILBOX && mailbox.seen(r) {
                c.mailbox_skip();
                continue;
            }
            c.prim_tests(1);
            let prim = self.prim_ids[r as usize];
            best.test_triangle(p, prim, &self.mesh.triangle(prim as usize));
        }
    }
}
