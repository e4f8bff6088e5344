//! The SAH k-d tree in O(N log N): Wald and Havran 2006, "On building fast kd-trees for ray
//! tracing, and on doing that in O(N log N)" (IEEE Symposium on Interactive Ray Tracing).
//!
//! Split candidates are the faces of each triangle's bounds *clipped to the node's cell*
//! ("perfect splits": a triangle crossing the cell only counts with the part inside it). For
//! each axis the candidates are kept as a sorted list of events — start (`+`), end (`−`) or
//! planar (`|`, the clipped bounds are flat on that axis) — ordered by position, then `−`, `|`,
//! `+`. One sweep per axis then knows, at every plane, how many triangles lie below, above and
//! in the plane, and evaluates the SAH there
//! `λ (K_T + K_I (P_below N_below + P_above N_above))` with the triangles in the plane put on
//! the cheaper side and `λ` the empty-space bonus when a side is empty. A node is a leaf when no
//! plane is cheaper than `K_I N`. The lists are sorted once, at the root: splitting a node
//! classifies its triangles as below-only, above-only or both in one pass over the split axis's
//! events, the one-sided triangles' events are filtered into the children keeping their order,
//! and only the straddling triangles (typically O(√N) of them) are re-clipped to each child and
//! have their new events sorted and merged in. So every level costs O(N) and the whole build
//! O(N log N), where re-sorting at every node would cost O(N log² N).
//!
//! Trade-off: the best k-d trees the SAH knows (Wald and Havran measured them as the fastest to
//! trace among k-d trees), at the price of an event list of up to six 8-byte entries per
//! reference and a build several times slower than a binned BVH's. Caveat: the SAH's
//! assumptions (uniform rays, no early termination) reward cutting off empty space, which
//! `λ` makes explicit; it is a knob, not a law.

use super::{Ctx, LARGE_LEAF, Out, Share, Stop};
use crate::KdParams;
use crate::clip::{halves, straddler_bounds};
use raybench_geom::Aabb;
use rayon::prelude::*;
mod events;

use events::{
    END, Events, PLANAR, START, kind_of, merge_into, ord, pos_of, push_events, radix_sort, tri_of,
    unord,
};

pub(crate) fn build(ctx: &Ctx, ids: &[u32], root: &Aabb, share: Share, out: &mut Out) {
    let mut ev: Events = Default::default();
    for list in ev.iter_mut() {
        list.reserve(2 * ids.len());
    }
    for &i in ids {
        push_events(&mut ev, &ctx.tris[i as usize].bounds(), i);
    }
    ev.par_iter_mut().for_each(radix_sort);
    let mut scratch = Scratch::new(ctx.tris.len());
    node(ctx, ev, ids.len(), *root, 0, share, &mut scratch, out);
}

/// Per-task working memory, reused by every node the task builds: the side table indexed by
/// triangle id, and the straddlers' new events before they are merged (no allocation per node
/// for either; measured: see docs/experiments.md, k-d tree, per-task scratch).
pub(crate) struct Scratch {
    side: Vec<u8>,
    straddlers: Vec<u32>,
    new_below: Events,
    new_above: Events,
}

impl Scratch {
    pub(crate) fn new(triangles: usize) -> Scratch {
        Scratch {
            side: vec![0u8; triangles],
            straddlers: Vec::new(),
            new_below: Default::default(),
            new_above: Default::default(),
        }
    }
}

/// Whether more than [`LARGE_LEAF`] of the node's triangles pass near one point, where no plane
/// can cut them apart ([`super::is_pile`]).
fn is_pile(ctx: &Ctx, ev: &Events) -> bool {
    super::is_pile(ctx.tris, &triangles(ev))
}

/// The node's triangles: one start or planar event each on any axis (an end event follows
/// its start).
fn triangles(ev: &Events) -> Vec<u32> {
    ev[0]
        .iter()
        .filter(|&&e| kind_of(e) != END)
        .map(|&e| tri_of(e))
        .collect()
}

/// A chosen split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Split {
    pub axis: usize,
    pub pos: f32,
    /// Triangles lying in the plane go below (else above).
    pub planar_below: bool,
    pub cost: f64,
    pub n_below: usize,
    pub n_above: usize,
}

/// One node: a leaf, or the best split and both subtrees. `ev` holds the events of the node's
/// `n` triangles clipped to `cell`; `share` bounds the references of the subtree;
/// `scratch` is the task's working memory.
#[allow(clippy::too_many_arguments)]
fn node(
    ctx: &Ctx,
    ev: Events,
    n: usize,
    cell: Aabb,
    depth: u32,
    share: Share,
    scratch: &mut Scratch,
    out: &mut Out,
) {
    let p = ctx.params;
    let past_limit = depth >= ctx.max_depth;
    let chosen = if n <= p.leaf_size as usize {
        Err(Stop::Cost)
    } else if depth >= ctx.large_max_depth || (past_limit && (n <= LARGE_LEAF || is_pile(ctx, &ev)))
    {
        Err(Stop::Depth)
    } else {
        // Beyond LARGE_LEAF triangles a split that separates anything is made even when the
        // cost model prefers the leaf (long crossing strands, where every plane duplicates
        // many references): such a leaf costs every ray through it a dozen Tri4 passes, and the
        // stack depth and the memory share still bound the splitting. Past the depth limit only
        // crowded cells that are not piles are cut, so a pile is not peeled a triangle a level.
        best_split(&ev, n, &cell, p)
            .filter(|s| {
                s.cost < p.intersection_cost as f64 * n as f64
                    || (n > LARGE_LEAF && (s.n_below < n || s.n_above < n))
            })
            .ok_or(Stop::Cost)
            .and_then(|s| {
                if share.fits(s.n_below, s.n_above) {
                    Ok(s)
                } else {
                    Err(Stop::Memory)
                }
            })
    };
    let s = match chosen {
        Ok(s) => s,
        Err(stop) => {
            out.leaf(ctx, &cell, depth, triangles(&ev), stop);
            return;
        }
    };
    let (cb, ca) = halves(&cell, s.axis, s.pos);
    let (evb, nb, eva, na) = split_events(ctx, ev, &s, &cb, &ca, scratch);
    debug_assert_eq!((nb, na), (s.n_below, s.n_above), "sweep and split agree");
    let at = out.open_interior(ctx, &cell);
    let above_at = if depth < Share::PROPORTIONAL_DEPTH {
        let (share_b, share_a) = share.proportional(nb, na);
        if ctx.fork(n, depth) {
            let ((), sub) = rayon::join(
                || node(ctx, evb, nb, cb, depth + 1, share_b, scratch, out),
                || {
                    let mut sub = Out::default();
                    let mut own = Scratch::new(ctx.tris.len());
                    node(ctx, eva, na, ca, depth + 1, share_a, &mut own, &mut sub);
                    sub
                },
            );
            let above_at = out.nodes.len();
            out.append(sub);
            above_at
        } else {
            node(ctx, evb, nb, cb, depth + 1, share_b, scratch, out);
            let above_at = out.nodes.len();
            node(ctx, eva, na, ca, depth + 1, share_a, scratch, out);
            above_at
        }
    } else {
        let before = out.shape.refs;
        node(
            ctx,
            evb,
            nb,
            cb,
            depth + 1,
            Share(share.0 - na as u64),
            scratch,
            out,
        );
        let used = out.shape.refs - before;
        let above_at = out.nodes.len();
        node(
            ctx,
            eva,
            na,
            ca,
            depth + 1,
            Share(share.0 - used),
            scratch,
            out,
        );
        above_at
    };
    out.close_interior(at, s.axis, s.pos, above_at);
}

/// The sweep: the cheapest plane strictly inside the cell over the three axes (`None` when the
/// cell has no area or no plane lies strictly inside it). A plane on the cell's boundary would
/// make a flat child that separates nothing, so such events only update the counts.
pub(crate) fn best_split(ev: &Events, n: usize, cell: &Aabb, p: &KdParams) -> Option<Split> {
    let (kt, ki, bonus) = (
        p.traversal_cost as f64,
        p.intersection_cost as f64,
        p.empty_bonus as f64,
    );
    let ext = cell.max.as_dvec3() - cell.min.as_dvec3();
    let mut best: Option<Split> = None;
    for (k, e) in ev.iter().enumerate() {
        if cell.min[k] >= cell.max[k] {
            continue; // flat on this axis: no plane strictly inside
        }
        let (a, b) = (ext[(k + 1) % 3], ext[(k + 2) % 3]);
        let (cap, perim) = (a * b, a + b);
        let area = cap + perim * ext[k];
        if area <= 0.0 || area.is_nan() {
            continue;
        }
        let inv_area = 1.0 / area;
        let (lo, hi) = (ord(cell.min[k]), ord(cell.max[k]));
        let (min_k, max_k) = (cell.min[k] as f64, cell.max[k] as f64);
        let (mut nb, mut na) = (0usize, n);
        let mut i = 0;
        while i < e.len() {
            // Every event at this position, counted by kind in one pass.
            let pos = pos_of(e[i]);
            let mut counts = [0usize; 4];
            while i < e.len() && pos_of(e[i]) == pos {
                counts[kind_of(e[i]) as usize] += 1;
                i += 1;
            }
            let [ends, planars, starts, _] = counts;
            na -= planars + ends;
            if lo < pos && pos < hi {
                let x = unord(pos) as f64;
                // Area ratios (the common factor 2 cancels).
                let pb = (cap + perim * (x - min_k)) * inv_area;
                let pa = (cap + perim * (max_k - x)) * inv_area;
                let cost = |nb: usize, na: usize| {
                    let lambda = if nb == 0 || na == 0 { bonus } else { 1.0 };
                    lambda * (kt + ki * (pb * nb as f64 + pa * na as f64))
                };
                let (c_below, c_above) = (cost(nb + planars, na), cost(nb, na + planars));
                let planar_below = c_below <= c_above;
                let c = c_below.min(c_above);
                if best.is_none_or(|s| c < s.cost) {
                    best = Some(Split {
                        axis: k,
                        pos: unord(pos),
                        planar_below,
                        cost: c,
                        n_below: nb + if planar_below { planars } else { 0 },
                        n_above: na + if planar_below { 0 } else { planars },
                    });
                }
            }
            nb += starts + planars;
        }
        debug_assert_eq!(na, 0, "every triangle ends or lies in a plane on each axis");
    }
    best
}

const BOTH: u8 = 0;
const BELOW: u8 = 1;
const ABOVE: u8 = 2;

/// Splits a node's events at `s` in O(n + s log s) for s straddling triangles: classify by
/// one pass over the split axis's events, filter every axis's list into the two children (the
/// order is kept, so they stay sorted), then clip the straddlers to each child, sort their new
/// events and merge them in. Returns the children's events and triangle counts.
fn split_events(
    ctx: &Ctx,
    ev: Events,
    s: &Split,
    cb: &Aabb,
    ca: &Aabb,
    scratch: &mut Scratch,
) -> (Events, usize, Events, usize) {
    let side = &mut scratch.side;
    for &e in &ev[0] {
        side[tri_of(e) as usize] = BOTH;
    }
    let at = ord(s.pos);
    for &e in &ev[s.axis] {
        let (pos, t) = (pos_of(e), tri_of(e) as usize);
        match kind_of(e) {
            END if pos <= at => side[t] = BELOW,
            START if pos >= at => side[t] = ABOVE,
            PLANAR => {
                side[t] = if pos < at || (pos == at && s.planar_below) {
                    BELOW
                } else {
                    ABOVE
                }
            }
            _ => {}
        }
    }
    let n = s.n_below + s.n_above; // capacity hints only
    let mut below: Events = Default::default();
    let mut above: Events = Default::default();
    let straddlers = &mut scratch.straddlers;
    straddlers.clear();
    let (mut only_below, mut only_above) = (0, 0);
    for (a, list) in ev.iter().enumerate() {
        let (b, ab) = (&mut below[a], &mut above[a]);
        b.reserve(list.len() * s.n_below / n.max(1) + 4);
        ab.reserve(list.len() * s.n_above / n.max(1) + 4);
        for &e in list {
            match side[tri_of(e) as usize] {
                BELOW => b.push(e),
                ABOVE => ab.push(e),
                _ if a == 0 && kind_of(e) != END => straddlers.push(tri_of(e)),
                _ => {}
            }
        }
        if a == 0 {
            only_below = b.iter().filter(|&&e| kind_of(e) != END).count();
            only_above = ab.iter().filter(|&&e| kind_of(e) != END).count();
        }
    }
    drop(ev);
    let k = straddlers.len();
    if k > 0 {
        let (new_below, new_above) = (&mut scratch.new_below, &mut scratch.new_above);
        for a in 0..3 {
            new_below[a].clear();
            new_above[a].clear();
        }
        for &t in straddlers.iter() {
            let tri = &ctx.tris[t as usize];
            push_events(new_below, &straddler_bounds(tri, cb), t);
            push_events(new_above, &straddler_bounds(tri, ca), t);
        }
        for a in 0..3 {
            new_below[a].sort_unstable();
            new_above[a].sort_unstable();
            merge_into(&mut below[a], &new_below[a]);
            merge_into(&mut above[a], &new_above[a]);
        }
    }
    (below, only_below + k, above, only_above + k)
}

#[cfg(test)]
mod tests {
    use super::events::{Event, event};
    use super::*;
    use crate::clip::{Side, clipped_bounds, side};
    use raybench_geom::{Triangle, Vec3};

    #[test]
    fn merge_into_merges() {
        let mut a = vec![1, 4, 4, 9];
        merge_into(&mut a, &[0, 4, 5, 10, 11]);
        assert_eq!(a, [0, 1, 4, 4, 4, 5, 9, 10, 11]);
        let mut e: Vec<Event> = vec![];
        merge_into(&mut e, &[3]);
        assert_eq!(e, [3]);
    }

    #[test]
    fn radix_sort_sorts_whole_keys() {
        let mut rng = Lcg(0x5eed_4ad1);
        let mut keys: Vec<Event> = (0..5000u32)
            .map(|i| {
                let pos = (rng.f() * 64.0).floor() - 32.0;
                let kind = (rng.f() * 3.0) as u64;
                event(pos, kind.min(2), i)
            })
            .collect();
        let mut want = keys.clone();
        want.sort_unstable();
        radix_sort(&mut keys);
        assert_eq!(keys, want);
    }

    #[test]
    fn order_preserving_bits() {
        let xs = [-3e38f32, -1.0, -1e-30, -0.0, 0.0, 1e-30, 0.5, 1.0, 3e38];
        for w in xs.windows(2) {
            assert!(ord(w[0]) <= ord(w[1]), "{} {}", w[0], w[1]);
            assert_eq!(unord(ord(w[1])), w[1]);
        }
        assert_eq!(ord(-0.0), ord(0.0));
        assert!(ord(-1.0) < ord(-0.5));
    }

    /// A small PCG-style generator with a named seed, so failures replay.
    struct Lcg(u64);
    impl Lcg {
        fn f(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        /// Coordinates on a coarse grid, so positions coincide and triangles lie in planes.
        fn grid(&mut self) -> f32 {
            (self.f() * 8.0).floor() / 8.0
        }
    }

    /// The naive O(N²) oracle: for every candidate plane (every face of every clipped box, on
    /// every axis, strictly inside the cell), count the triangles on each side with
    /// [`crate::clip::side`] directly and evaluate the same cost. Returns the lowest cost.
    fn naive_best(boxes: &[Aabb], cell: &Aabb, p: &KdParams) -> Option<(f64, usize, usize)> {
        let sa = cell.surface_area();
        let mut best: Option<(f64, usize, usize)> = None;
        for k in 0..3 {
            let mut planes: Vec<f32> = boxes.iter().flat_map(|b| [b.min[k], b.max[k]]).collect();
            planes.sort_by(f32::total_cmp);
            planes.dedup();
            for &x in planes
                .iter()
                .filter(|&&x| cell.min[k] < x && x < cell.max[k])
            {
                let (lb, la) = halves(cell, k, x);
                let (pb, pa) = (lb.surface_area() / sa, la.surface_area() / sa);
                let (mut nb, mut na, mut np) = (0, 0, 0);
                for b in boxes {
                    match side(b, k, x) {
                        Side::Below => nb += 1,
                        Side::Above => na += 1,
                        Side::Both => {
                            nb += 1;
                            na += 1
                        }
                        Side::InPlane => np += 1,
                    }
                }
                for (b, a) in [(nb + np, na), (nb, na + np)] {
                    let lambda = if b == 0 || a == 0 {
                        p.empty_bonus as f64
                    } else {
                        1.0
                    };
                    let c = lambda
                        * (p.traversal_cost as f64
                            + p.intersection_cost as f64 * (pb * b as f64 + pa * a as f64));
                    if best.is_none_or(|x| c < x.0) {
                        best = Some((c, b, a));
                    }
                }
            }
        }
        best
    }

    /// The sweep's chosen split against the naive evaluation on random small inputs (named
    /// seed 0x5eed_5a4); then the event split's children against direct classification.
    #[test]
    fn sweep_matches_naive_oracle_and_split_matches_direct_classification() {
        let p = KdParams::sah();
        let mut rng = Lcg(0x5eed_05a4);
        for round in 0..300 {
            let n = 1 + (rng.f() * 40.0) as usize;
            let tris: Vec<Triangle> = (0..n)
                .map(|_| {
                    let mut v = || Vec3::new(rng.grid(), rng.grid(), rng.grid()) * 2.0 - 0.5;
                    Triangle::new(v(), v(), v())
                })
                .collect();
            let cell = Aabb::new(Vec3::splat(0.0), Vec3::new(1.0, 0.75, 1.25));
            let mut ids = Vec::new();
            let mut boxes = Vec::new();
            let mut ev: Events = Default::default();
            for (i, t) in tris.iter().enumerate() {
                if let Some(b) = clipped_bounds(t, &cell) {
                    ids.push(i as u32);
                    boxes.push(b);
                    push_events(&mut ev, &b, i as u32);
                }
            }
            for l in ev.iter_mut() {
                l.sort_unstable();
            }
            let fast = best_split(&ev, ids.len(), &cell, &p);
            let naive = naive_best(&boxes, &cell, &p);
            match (fast, naive) {
                (None, None) => continue,
                (Some(f), Some(nv)) => {
                    assert!(
                        (f.cost - nv.0).abs() <= 1e-9 * nv.0,
                        "round {round}: sweep {f:?}, naive {nv:?}"
                    );
                }
                other => panic!("round {round}: {other:?}"),
            }
            let s = fast.unwrap();
            // The event split against classifying every triangle directly.
            let ctx = Ctx {
                tris: &tris,
                params: &p,
                max_depth: 30,
                large_max_depth: 30,
                root_area: 1.0,
                fork_depth: 0,
            };
            let (cb, ca) = halves(&cell, s.axis, s.pos);
            let mut scratch = Scratch::new(tris.len());
            let (evb, nb, eva, na) = split_events(&ctx, ev, &s, &cb, &ca, &mut scratch);
            assert_eq!((nb, na), (s.n_below, s.n_above), "round {round}");
            let mut want_b: Events = Default::default();
            let mut want_a: Events = Default::default();
            for (&i, b) in ids.iter().zip(&boxes) {
                let t = &tris[i as usize];
                match side(b, s.axis, s.pos) {
                    Side::Below => push_events(&mut want_b, b, i),
                    Side::Above => push_events(&mut want_a, b, i),
                    Side::InPlane if s.planar_below => push_events(&mut want_b, b, i),
                    Side::InPlane => push_events(&mut want_a, b, i),
                    Side::Both => {
                        push_events(&mut want_b, &straddler_bounds(t, &cb), i);
                        push_events(&mut want_a, &straddler_bounds(t, &ca), i);
                    }
                }
            }
            for a in 0..3 {
                want_b[a].sort_unstable();
                want_a[a].sort_unstable();
                assert_eq!(evb[a], want_b[a], "round {round} axis {a} below");
                assert_eq!(eva[a], want_a[a], "round {round} axis {a} above");
            }
        }
    }
}
