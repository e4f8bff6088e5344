//! The one traversal loop, for closest hit and any hit, counted and not: front to back with a
//! fixed stack of (node, entry t, exit t).
//!
//! At an interior node the ray's distances to the three centre planes, `tm = (mid - o) / d`,
//! decide everything (the parametric view of Revelles, Ureña and Lastra, "An Efficient
//! Parametric Algorithm for Octree Traversal", WSCG 2000): the octant containing the entry
//! point has bit `a` set when the ray is past plane `a` at the entry (`tm <= t0`, mirrored for
//! a negative direction), and each plane crossed inside `(t0, t1)` flips one bit, in order of
//! `tm`. That gives up to four children with their own `[t, t']` sub-intervals, pushed farthest
//! first. A `±0` direction component gives `tm = ±inf` (never crossed; the side follows the
//! origin) or NaN when the origin is on the plane (the sign bit picks a side; both sides hold
//! the plane's triangles), and the sign bit, not `< 0`, mirrors the rule (docs/validation.md, B3).
//!
//! The closest hit so far is kept across leaves (a triangle straddling octants may be hit
//! beyond the current one); a popped node starting beyond it is skipped, and the walk ends at
//! the first leaf whose exit is at or beyond it. The mailbox is the grid's: a direct-mapped
//! table of recently tested triangle ids on the stack.

use crate::Octree;
use crate::node::STACK;
use raybench_accel::{CounterSink, Hit};
use raybench_geom::{Ray, TriHit, Vec3};

/// Mailbox slots (a power of two), as the grid's: 32 ids, 128 bytes per query, not tuned.
const MAILBOX: usize = 32;

/// The per-query record of tested triangles, for rays and closest points alike.
pub(crate) type Mailbox = raybench_accel::Mailbox<MAILBOX>;

impl Octree {
    pub(crate) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.refs.is_empty() {
            return None;
        }
        let (t0, t1) = self.root_box.intersect(ray)?;
        let o = ray.origin();
        let inv = ray.inv_dir();
        let neg = [
            inv.x.is_sign_negative(),
            inv.y.is_sign_negative(),
            inv.z.is_sign_negative(),
        ];
        let mut stack = [(0u32, 0f32, 0f32); STACK];
        stack[0] = (0, t0, t1);
        let mut sp = 1;
        let mut best_t = ray.t_max();
        let mut best: Option<(u32, TriHit)> = None;
        let mut mailbox = Mailbox::new();
        while sp > 0 {
            sp -= 1;
            let (at, t_in, t_out) = stack[sp];
            if t_in > best_t {
                continue;
            }
            let node = &self.nodes[at as usize];
            if node.is_leaf() {
                c.leaf();
                for &prim in &self.refs[node.refs()] {
                    if mailbox.seen(prim) {
                        c.mailbox_skip();
                        continue;
                    }
                    c.prim_tests(1);
                    if let Some(h) =
                        self.triangles[prim as usize].intersect(&ray.with_t_max(best_t))
                    {
                        best_t = h.t;
                        best = Some((prim, h));
                        if ANY_HIT {
                            break;
                        }
                    }
                }
                // Front to back: every node still on the stack starts at or after this exit.
                if best_t <= t_out || (ANY_HIT && best.is_some()) {
                    break;
                }
                continue;
            }
            c.node();
            let tm = (Vec3::from_array(node.mid) - o) * inv;
            let mut octant = 0u32;
            // Crossings strictly inside (t_in, t_out), as (t, axis), sorted below.
            let mut cross = [(0f32, 0u32); 3];
            let mut k = 0;
            for a in 0..3 {
                if (tm[a] <= t_in) != neg[a] {
                    octant |= 1 << a;
                }
                if t_in < tm[a] && tm[a] < t_out {
                    cross[k] = (tm[a], a as u32);
                    k += 1;
                }
            }
            if k > 1 {
                if cross[1].0 < cross[0].0 {
                    cross.swap(0, 1);
                }
                if k > 2 {
                    if cross[2].0 < cross[1].0 {
                        cross.swap(1, 2);
                    }
                    if cross[1].0 < cross[0].0 {
                        cross.swap(0, 1);
                    }
                }
            }
            // Segment i runs from ts[i] to ts[i + 1] in octant octs[i].
            let mut ts = [t_in, t_out, t_out, t_out, t_out];
            let mut octs = [octant; 4];
            for i in 0..k {
                ts[i + 1] = cross[i].0;
                octs[i + 1] = octs[i] ^ (1 << cross[i].1);
            }
            ts[k + 1] = t_out;
            for i in (0..=k).rev() {
                if ts[i] > best_t {
                    continue;
                }
                if let Some(child) = node.child(octs[i]) {
                    stack[sp] = (child, ts[i], ts[i + 1]);
                    sp += 1;
                }
            }
        }
        best.map(|(prim, h)| Hit::from_tri_hit(prim, h))
    }
}
