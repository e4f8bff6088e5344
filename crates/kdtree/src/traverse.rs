//! The one traversal loop, for closest hit and any hit, with and without mailboxing, counted
//! and not.
//!
//! Front to back with a fixed stack of (node, t_enter, t_exit) (Havran's "TA_B^rec" sequential
//! form, as in pbrt §4.4.4): the ray segment is first clipped to the root cell; at a node, the
//! side of the plane the origin is on is "near", and the distance to the plane decides whether
//! the segment visits only the near child, only the far child, or the near child over
//! `[t_enter, t_split]` and then the far one over `[t_split, t_exit]`. Intervals are closed,
//! so a hit exactly on a split plane belongs to both cells. "Near" is decided by the sign of
//! the direction on the split axis (Wald's formulation), not by the side of the origin: a ray
//! running up the axis meets the cell below the plane first, and a plane it crossed before the
//! interval (including one behind the origin, `t_split < 0 <= t_enter`) leaves only the cell
//! above.
//!
//! Early termination, stated once. The closest hit so far (`best_t`, over every triangle
//! tested, in any leaf) is kept, and every triangle is tested with `t_max = best_t`. A pending
//! subtree whose interval starts beyond `best_t` is dropped when popped, and a popped interval
//! is cut at `best_t`. So a leaf whose hit lies inside its own interval ends the walk (every
//! pending interval starts at or after the leaf's exit), while a hit beyond the leaf's exit (a
//! triangle reaching into a later cell) does not: the cells in between are still walked, and
//! a nearer triangle there wins. Keeping the out-of-leaf hit instead of discarding it is also
//! what makes the mailbox correct: a triangle skipped because it was tested before has its
//! hit, if any, already in `best_t`.
//!
//! Corner cases. A ray parallel to a split plane (`±0` direction component, `1/d = ±inf`) gets
//! `t_split = ±inf` and stays on the origin's side: with `+0` the "near" cell is the one below,
//! and `+inf` (origin below) keeps it while `-inf` (origin above) takes the far one, and
//! symmetrically for `-0`. If its origin lies *in* the plane, `t_split` is `0 × inf = NaN`,
//! every comparison is false, and both children are visited over the whole interval (the ray
//! is in both closed cells), which the pop rule above keeps correct since neither child's
//! interval ends early. A ray starting inside the tree begins at `max(t_min, entry)`. Hits
//! count when `t_min < t <= t_max` (Möller–Trumbore's own depth test); any hit (`occluded`)
//! returns at the first triangle that reports one.
//!
//! Leaves: a leaf's triangles are its own copies, four to a `Tri4` (`build/pack.rs`), tested
//! four at a time with the same arithmetic as the scalar Möller–Trumbore test, so each lane's
//! answer is bit for bit the scalar one; among lanes that hit, the nearest wins (the lowest lane
//! on ties). Padding lanes are masked off and never counted.
//!
//! Mailbox: a direct-mapped table of [`MAILBOX_SLOTS`] mesh indices on the stack, indexed by
//! the low bits of the index; a lane whose triangle was tested before is masked off before the
//! test. A collision only evicts (the evicted triangle may be tested again), so it is never
//! wrong. Nothing is allocated per ray and `&self` is shared freely between threads.

use crate::KdTree;
use crate::node::MAX_DEPTH;
use raybench_accel::{CounterSink, Hit};
use raybench_geom::tri4::LANES;
use raybench_geom::{Ray, TriHit, max_keep, min_keep, prefetch};

/// Mailbox size, a power of two. 8 slots are 32 bytes, two stores per ray; 16 compile their
/// initialisation to a `memset` call. The mailbox saves few tests, because `kd-sah` leaves are
/// small and a ray visits only about two non-empty leaves (measured: see docs/experiments.md,
/// k-d tree).
pub const MAILBOX_SLOTS: usize = 8;

impl KdTree {
    /// Picks the traversal stack size: a tree no deeper than 32 levels (the default limit up to
    /// about 300k triangles) gets a 32-entry stack, so each ray initialises 384 bytes of stack
    /// instead of 768.
    #[inline(always)]
    pub(crate) fn trace<
        const ANY_HIT: bool,
        const MAILBOX: bool,
        const EARLY_EXIT: bool,
        C: CounterSink,
    >(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.depth_limit as usize <= SMALL_STACK {
            self.walk::<ANY_HIT, MAILBOX, EARLY_EXIT, SMALL_STACK, C>(ray, c)
        } else {
            self.walk::<ANY_HIT, MAILBOX, EARLY_EXIT, MAX_DEPTH, C>(ray, c)
        }
    }

    /// `EARLY_EXIT = false` keeps walking every pending cell after a hit (each triangle still
    /// tested against the closest hit so far, so the answer is the same): the walk without
    /// early termination, measured to show what stopping saves. Any hit always stops.
    fn walk<
        const ANY_HIT: bool,
        const MAILBOX: bool,
        const EARLY_EXIT: bool,
        const STACK: usize,
        C: CounterSink,
    >(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let (mut t0, mut t1) = self.bounds.intersect(ray)?;
        let o = ray.origin().to_array();
        let inv = ray.inv_dir().to_array();
        // Per axis, whether the ray runs towards -inf (the sign bit of 1/d, so -0 counts as
        // negative): then the child above the plane is the near one.
        let negative = inv.map(f32::is_sign_negative);
        let mut best_t = ray.t_max();
        let mut best: Option<(u32, TriHit)> = None;
        let mut mailbox = raybench_accel::Mailbox::<MAILBOX_SLOTS>::new();
        let mut stack = [(0u32, 0f32, 0f32); STACK];
        let mut sp = 0;
        let mut at = 0u32;
        'walk: loop {
            let mut node = self.nodes[at as usize];
            while !node.is_leaf() {
                c.node();
                let a = node.axis();
                let t_split = (node.split() - o[a]) * inv[a];
                let (below, above) = (at + 1, node.above());
                prefetch(self.nodes.as_ptr().wrapping_add(above as usize));
                let near = if negative[a] { above } else { below };
                let far = below ^ above ^ near;
                if t_split > t1 {
                    // The ray reaches the plane after the interval (or never: +inf).
                    at = near;
                } else if t_split < t0 {
                    // The ray crossed the plane before the interval (or the plane is behind
                    // the origin, or never: -inf).
                    at = far;
                } else {
                    // Both, near first (also when t_split is NaN: the ray lies in the plane
                    // and in both closed cells over the whole interval).
                    stack[sp] = (far, max_keep(t0, t_split), t1);
                    sp += 1;
                    t1 = min_keep(t1, t_split);
                    at = near;
                }
                node = self.nodes[at as usize];
            }
            c.leaf();
            // The leaf's Tri4s: four references each, the last one padded.
            let (first, count) = (node.first() as usize, node.count() as usize);
            for (q, four) in self.tri4s[first / LANES..(first + count).div_ceil(LANES)]
                .iter()
                .enumerate()
            {
                let mut lanes = LANE_MASKS[(count - q * LANES).min(LANES)];
                if MAILBOX {
                    for l in 0..LANES {
                        if lanes >> l & 1 == 1 && mailbox.seen(four.ids[l]) {
                            lanes &= !(1 << l);
                            c.mailbox_skip();
                        }
                    }
                    if lanes == 0 {
                        continue;
                    }
                }
                c.prim_tests(lanes.count_ones() as u64);
                let hits = four.test(ray, best_t);
                let hit = hits.mask & lanes;
                if hit != 0 {
                    let (l, h) = hits.nearest(hit);
                    best_t = h.t;
                    best = Some((four.ids[l], h));
                    if ANY_HIT {
                        break 'walk;
                    }
                }
            }
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let (next, enter, exit) = stack[sp];
                if !ANY_HIT && EARLY_EXIT && enter > best_t {
                    continue;
                }
                at = next;
                t0 = enter;
                t1 = if ANY_HIT || !EARLY_EXIT {
                    exit
                } else {
                    exit.min(best_t)
                };
                break;
            }
        }
        best.map(|(prim, h)| Hit::from_tri_hit(prim, h))
    }
}

/// The lanes in use of a Tri4 holding `i` references (`i` ≤ 4).
const LANE_MASKS: [u32; LANES + 1] = [0, 0b1, 0b11, 0b111, 0b1111];

/// Stack entries for trees at most this deep (see [`KdTree::trace`]).
pub(crate) const SMALL_STACK: usize = 32;
