//! Packets of sixteen coherent rays walked through a wide BVH together, one ray per
//! AVX-512 lane: for camera rays in scanline order, which enter the same nodes and leaves.
//!
//! A single-ray walk is a chain of dependent steps: each node's test waits for the child the test
//! before it chose (about 45 cycles a step on the bunny's primary rays: docs/experiments.md,
//! "Profiles behind the tables"). A packet turns that chain into independent work: at each node,
//! every child's box is tested against all sixteen rays (one broadcast plane against sixteen
//! origins), and at each leaf every triangle against all sixteen. The visits are shared, so the
//! per-ray cost is the packet's cost divided by how many rays needed it: low for a packet whose
//! rays hit one surface, high where they scatter (silhouettes, triangles smaller than the spacing
//! of the rays), since a test costs the same for one lane as for sixteen. This is the classic
//! packet traversal of Wald, Slusallek, Benthin and Wagner (2001), on a BVH as in Wald, Boulos and
//! Shirley (2007, "Ray tracing deformable scenes using dynamic bounding volume hierarchies").
//! As there, bounds over the whole packet (`frustum.rs`) first rule out, in one pass over the
//! node's planes, the children no ray can enter, so only the others are tested ray by ray: 5–20 %
//! faster on camera rays (measured: see docs/experiments.md, "packet bounds before the per-ray box
//! tests"). Where a few lanes reach a node that leaves more children than lanes, the test is
//! turned around (`packet_node.rs`): each lane against all the node's children in one pass, as
//! the single-ray walk tests a node, with the same arithmetic, so the same children are entered:
//! about 2 % faster on camera rays, shadow rays within the noise (docs/experiments.md, "a node
//! reached by few lanes tested lane by lane"). The trade-off, measured over the default suite's
//! primary rays (docs/results/): 1.5–2.8× the single-ray walk on scenes of large triangles
//! (Sponza, the teapots, Sibenik), little or less where triangles are smaller than the rays'
//! spacing (the stadium from afar, San Francisco).
//! Handing sparse subtrees or leaves back to the single-ray walk, as Embree's hybrid traversal
//! does, did not measurably help (docs/experiments.md, "Packets for coherent rays"); handing
//! whole packets over does, where the rays share little (`packet_switch.rs`, the `packet_floors`
//! knob):
//! a packet walk that carried few rays per node and per `Tri4` sends the next packets of its
//! window ray by ray.
//!
//! Exactness: every lane computes what the single-ray walk computes for its ray, operation for
//! operation — the slab test with the near planes chosen by the direction's signs
//! ([`super::avx2`]), Möller–Trumbore as in [`raybench_geom::Tri4::test`] (no fused
//! multiply-add) — so each ray's hit, `t`, `u` and `v` are the single-ray walk's, bit for bit.
//! Only the order in which triangles are met differs, so on an exact tie (two triangles at
//! the same `t`) the reported triangle may be the other one, as between any two structures.
//! The near planes are per packet, so a packet whose rays point into different octants is
//! walked once per octant present, each time with only that octant's lanes active (Embree's
//! stream mode sorts rays by octant for the same reason).
//!
//! A subtree pushed for later keeps the smallest entry distance among its rays and is skipped
//! when that is beyond every active ray's closest hit so far.
//!
//! Any hit (shadow rays from primary hits towards one light, coherent in the same way): a lane
//! is done at its first hit and leaves every subtree still to visit; the packet ends when all
//! its lanes are done or the stack is empty. Children are pushed in slot order, unsorted, as in
//! the single-ray any-hit walk (no hit shortens a ray, so no distance would ever cull one). A
//! lane tests exactly the boxes and triangles of its single-ray any-hit walk that come before
//! its first hit in the packet's order, with the same arithmetic, so its answer is the single-ray
//! walk's: occluded exactly when one of the leaves its ray enters holds a triangle hit within
//! `t_min < t <= t_max`.

use super::avx2;
use super::frustum::Frustum;
use super::node::WideNode;
use super::packet_node::{children_by_lane, lanes_entering};
use super::packet_switch::{Usage, each_packet};
use super::walk::with_stack;
use crate::node::ChildRef;
use crate::wide::{BvhWide, STACK};
use raybench_accel::Hit;
use raybench_geom::packet::{self, Avx512Packets, Best, PACKET, Packet, RayBlock};
use raybench_geom::{NO_PRIM, Ray};
use std::arch::x86_64::*;

/// A subtree still to visit: its reference, the smallest entry distance among the lanes that
/// entered its box, and those lanes.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Entry {
    pub(super) r: ChildRef,
    pub(super) t_entry: f32,
    pub(super) lanes: u16,
}

pub(super) type PacketStack = [Entry; STACK];

raybench_accel::per_thread_stack!(
    /// Runs `f` with this thread's packet stack (a fresh one inside another walk).
    pub(super) fn with_packet_stack -> PacketStack = Box::new([Entry::default(); STACK])
);

/// Traces a coherent batch (closest hit), one packet per block; `out` gets the first
/// `out.len()` rays of `blocks`, which are `rays` (the batch from ray `first` on).
pub(crate) fn intersect_coherent<const W: usize>(
    _k: Avx512Packets,
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [Option<Hit>],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx512Packets` exists only after `detect` saw AVX-512F on this CPU.
        unsafe { intersect_packets(bvh, blocks, rays, first, out, stack) }
    })
}

#[target_feature(enable = "avx512f")]
fn intersect_packets<const W: usize>(
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [Option<Hit>],
    stack: &mut PacketStack,
) {
    let single = |k, rays: &[Ray], out: &mut [Option<Hit>]| {
        with_stack(|s| avx2::intersect_all(bvh, k, rays, out, s))
    };
    each_packet::<PACKET, W, _>(
        bvh,
        blocks,
        rays,
        first,
        out,
        single,
        |block, out, usage| {
            let (packet, mut best) = packet::load(block);
            if !bvh.tri4s().is_empty() {
                packet::octant_groups(&packet, out.len(), |lanes, octant| {
                    walk(bvh, &packet, lanes, octant, &mut best, stack, usage)
                });
            }
            for (o, (prim, h)) in out.iter_mut().zip(best.hits()) {
                *o = (prim != NO_PRIM).then(|| Hit::from_tri_hit(prim, h));
            }
        },
    );
}

/// The walk of the `active` lanes, whose directions all lie in `octant`. Each subtree is
/// walked with the lanes that entered its box, so every ray meets exactly the boxes and
/// triangles its single-ray walk would test (not those of a neighbour's leaf, where a ray
/// grazing a box it missed by rounding could find a hit its own walk never tests).
#[target_feature(enable = "avx512f")]
fn walk<const W: usize>(
    bvh: &BvhWide<W>,
    p: &Packet,
    active: u16,
    octant: u8,
    best: &mut Best,
    stack: &mut PacketStack,
    usage: &mut Usage,
) {
    let frustum = Frustum::new(p, active, octant);
    let near = frustum.near;
    let mut farthest = _mm512_mask_reduce_max_ps(active, best.t);
    let mut sp = 0;
    let mut r = bvh.root();
    let mut lanes = active;
    'walk: loop {
        if r.is_leaf() {
            let first = r.index as usize;
            let tri4s = (r.count as usize).div_ceil(4);
            usage.tri4s(tri4s as u32, lanes);
            for tri4 in &bvh.tri4s()[first..first + tri4s] {
                best.test_tri4(tri4, p, lanes);
            }
            farthest = _mm512_mask_reduce_max_ps(active, best.t);
        } else {
            usage.node(lanes);
            let n = &bvh.nodes()[r.index as usize];
            let base = sp;
            let maybe = frustum.maybe_entered(n, farthest);
            each_entered::<W, true>(p, n, near, lanes, maybe, best.t, |e| {
                push_sorted(stack, base, &mut sp, e);
            });
            if sp > base {
                sp -= 1;
                (r, lanes) = (stack[sp].r, stack[sp].lanes);
                continue 'walk;
            }
        }
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            let e = stack[sp];
            if e.t_entry <= farthest {
                (r, lanes) = (e.r, e.lanes);
                continue 'walk;
            }
        }
    }
}

/// Lanes at most this many that reach a node test its children lane by lane
/// ([`children_by_lane`]) where the packet bounds leave more children than that (2 and 8
/// measured within the noise of 4: docs/experiments.md, "a node reached by few lanes tested
/// lane by lane").
const FEW_LANES: u32 = 4;

/// Whether the `lanes` reaching a node test its children lane by lane rather than child by
/// child, `maybe` being the children the packet bounds leave: one pass a lane against one a
/// child, whichever are fewer.
#[inline(always)]
fn few_lanes(lanes: u16, maybe: u32) -> bool {
    let n = lanes.count_ones();
    n <= FEW_LANES && n < maybe.count_ones()
}

/// Calls `push` with every child of `n` among `maybe` (the children the packet bounds leave)
/// that some of the `lanes` of `p` enter with their far ends at `t_far`, in slot order, as an
/// entry carrying the lanes that enter it and, with `DISTANCE`, the least of their entry
/// distances (else 0: the any-hit walk never compares them). The node is tested lane by lane
/// where [`few_lanes`] says so, else child by child up to the first unused slot; either way
/// each lane enters the same children.
#[target_feature(enable = "avx512f")]
#[inline]
fn each_entered<const W: usize, const DISTANCE: bool>(
    p: &Packet,
    n: &WideNode<W>,
    near: [usize; 3],
    lanes: u16,
    mut maybe: u32,
    t_far: __m512,
    mut push: impl FnMut(Entry),
) {
    if few_lanes(lanes, maybe) {
        let (mut entered, lanes_of, entry_of) = children_by_lane(p, n, near, lanes, maybe, t_far);
        while entered != 0 {
            let slot = entered.trailing_zeros() as usize;
            entered &= entered - 1;
            push(Entry {
                r: n.child[slot],
                t_entry: if DISTANCE { entry_of[slot] } else { 0.0 },
                lanes: lanes_of[slot] as u16,
            });
        }
        return;
    }
    while maybe != 0 {
        let slot = maybe.trailing_zeros() as usize;
        maybe &= maybe - 1;
        let child = n.child[slot];
        if child == ChildRef::default() {
            break;
        }
        let (entered, t0) = lanes_entering(p, n, near, lanes, slot, t_far);
        if entered != 0 {
            push(Entry {
                r: child,
                t_entry: if DISTANCE {
                    _mm512_mask_reduce_min_ps(entered, t0)
                } else {
                    0.0
                },
                lanes: entered,
            });
        }
    }
}

/// Pushes `e` onto `stack[base..*sp]`, kept in decreasing entry distance so the nearest is on
/// top (a later slot goes below earlier ones at the same distance).
#[inline(always)]
pub(super) fn push_sorted(stack: &mut PacketStack, base: usize, sp: &mut usize, e: Entry) {
    let mut j = *sp;
    while j > base && stack[j - 1].t_entry <= e.t_entry {
        stack[j] = stack[j - 1];
        j -= 1;
    }
    stack[j] = e;
    *sp += 1;
}

/// Traces a coherent batch (any hit), one packet per block; `out` gets the first `out.len()`
/// rays of `blocks`, which are `rays` (the batch from ray `first` on).
pub(crate) fn occluded_coherent<const W: usize>(
    _k: Avx512Packets,
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [bool],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx512Packets` exists only after `detect` saw AVX-512F on this CPU.
        unsafe { occluded_packets(bvh, blocks, rays, first, out, stack) }
    })
}

#[target_feature(enable = "avx512f")]
fn occluded_packets<const W: usize>(
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [bool],
    stack: &mut PacketStack,
) {
    let single = |k, rays: &[Ray], out: &mut [bool]| {
        with_stack(|s| avx2::occluded_all(bvh, k, rays, out, s))
    };
    each_packet::<PACKET, W, _>(
        bvh,
        blocks,
        rays,
        first,
        out,
        single,
        |block, out, usage| {
            let (packet, mut best) = packet::load(block);
            let mut done = 0u16;
            if !bvh.tri4s().is_empty() {
                packet::octant_groups(&packet, out.len(), |lanes, octant| {
                    done |= walk_any(bvh, &packet, lanes, octant, &mut best, stack, usage)
                });
            }
            for (lane, o) in out.iter_mut().enumerate() {
                *o = done >> lane & 1 == 1;
            }
        },
    );
}

/// The any-hit walk of the `active` lanes, whose directions all lie in `octant`; returns the
/// lanes that found a hit. `best` enters with each lane's `t_max` and is used only to test
/// triangles: a lane with a hit in it is done.
#[target_feature(enable = "avx512f")]
fn walk_any<const W: usize>(
    bvh: &BvhWide<W>,
    p: &Packet,
    active: u16,
    octant: u8,
    best: &mut Best,
    stack: &mut PacketStack,
    usage: &mut Usage,
) -> u16 {
    let t_max = best.t;
    let frustum = Frustum::new(p, active, octant);
    let near = frustum.near;
    let farthest = _mm512_mask_reduce_max_ps(active, t_max);
    let none = _mm512_set1_epi32(NO_PRIM as i32);
    let mut live = active;
    let mut sp = 0;
    let mut r = bvh.root();
    let mut lanes = active;
    'walk: loop {
        if r.is_leaf() {
            let first = r.index as usize;
            let tri4s = (r.count as usize).div_ceil(4);
            usage.tri4s(tri4s as u32, lanes);
            for tri4 in &bvh.tri4s()[first..first + tri4s] {
                best.test_tri4(tri4, p, lanes);
                let hit = _mm512_mask_cmpneq_epi32_mask(lanes, best.prim, none);
                if hit != 0 {
                    live &= !hit;
                    lanes &= !hit;
                    if live == 0 {
                        break 'walk;
                    }
                    if lanes == 0 {
                        break;
                    }
                }
            }
        } else {
            usage.node(lanes);
            let n = &bvh.nodes()[r.index as usize];
            let base = sp;
            let maybe = frustum.maybe_entered(n, farthest);
            each_entered::<W, false>(p, n, near, lanes, maybe, t_max, |e| {
                stack[sp] = e;
                sp += 1;
            });
            // The lowest slot first, as the single-ray any-hit walk.
            stack[base..sp].reverse();
        }
        // The next subtree some lane that entered it still needs.
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            let e = stack[sp];
            if e.lanes & live != 0 {
                (r, lanes) = (e.r, e.lanes & live);
                continue 'walk;
            }
        }
    }
    active & !live
}
