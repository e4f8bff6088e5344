//! `kd-packets`: sixteen coherent rays walked through the k-d tree together, one ray per
//! AVX-512 lane (Wald's packet traversal of kd-trees, 2004, on camera rays in scanline order).
//!
//! The packet walks the lanes of one direction octant at a time ([`packet::octant_groups`]),
//! so at every split plane the near child is the same for all of them. Each lane keeps its own
//! interval `[t0, t1]` and makes exactly its single-ray walk's choice (`traverse.rs`): near
//! only when the plane lies beyond its interval, far only when before it, both otherwise (also
//! when the ray lies in the plane: the comparisons are unordered-true on NaN). The packet goes
//! near with the lanes that need it and pushes the far child with the lanes that need that; a
//! child no lane needs is skipped, so a packet costs one node fetch and one sixteen-lane step
//! where sixteen rays each paid a dependent load. A lane's interval is cut at the plane exactly
//! as its single-ray walk cuts it (`max_keep` and `min_keep` are `max_ps` and `min_ps` with the
//! plane's distance first). A popped subtree keeps only the lanes whose interval still starts
//! at or before their closest hit, and their intervals end there.
//!
//! Leaves test each of their triangles against the active lanes
//! ([`raybench_geom::packet::Best::test_tri4`], bit for bit the scalar test), without the
//! mailbox: a triangle met again in a later leaf gives the same answer again, so re-testing it
//! costs time, never correctness. Every lane therefore meets exactly the leaves and triangles its
//! single-ray walk meets, in the same order; its hit, `t`, `u` and `v` are the single-ray
//! walk's. Any hit (the shadow rays, coherent in the same way): a lane is done at the first leaf
//! where it hits and leaves every subtree still on the stack; the packet ends when all its lanes
//! are done. Its leaves up to that one are its single-ray any-hit walk's, in the same order, so
//! its answer is that walk's. Incoherent batches take the single-ray walk.
#![allow(unsafe_code)]

use crate::KdTree;
use crate::node::MAX_DEPTH;
use raybench_accel::Hit;
use raybench_geom::packet::{self, Avx512Packets, Best, PACKET, Packet, RayBlock};
use raybench_geom::tri4::LANES;
use raybench_geom::{NO_PRIM, Ray};
use std::arch::x86_64::*;

/// A subtree still to visit: the lanes that need it and their intervals.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Entry {
    t0: [f32; PACKET],
    t1: [f32; PACKET],
    node: u32,
    lanes: u16,
}

/// One entry per level: the walk pushes at most one per node on its path.
type PacketStack = [Entry; MAX_DEPTH + 1];

/// Traces a coherent batch (closest hit), one packet per block: `rays` are the batch's rays
/// from the first block's first one, `out` gets the first `out.len()` of them.
pub(crate) fn intersect_coherent(
    _k: Avx512Packets,
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx512Packets` exists only after `detect` saw AVX-512F on this CPU.
        unsafe { intersect_packets(kd, rays, blocks, out, stack) }
    })
}

#[target_feature(enable = "avx512f")]
fn intersect_packets(
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
    stack: &mut PacketStack,
) {
    for (block, rays, out) in packet::each_block(blocks, rays, out) {
        let (p, mut best) = packet::load(block);
        walk_packet::<false>(kd, &p, rays, out.len(), &mut best, stack);
        for (o, (prim, h)) in out.iter_mut().zip(best.hits()) {
            *o = (prim != NO_PRIM).then(|| Hit::from_tri_hit(prim, h));
        }
    }
}

/// Traces a coherent batch (any hit), one packet per block, as [`intersect_coherent`].
pub(crate) fn occluded_coherent(
    _k: Avx512Packets,
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [bool],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx512Packets` exists only after `detect` saw AVX-512F on this CPU.
        unsafe { occluded_packets(kd, rays, blocks, out, stack) }
    })
}

#[target_feature(enable = "avx512f")]
fn occluded_packets(
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [bool],
    stack: &mut PacketStack,
) {
    for (block, rays, out) in packet::each_block(blocks, rays, out) {
        let (p, mut best) = packet::load(block);
        let done = walk_packet::<true>(kd, &p, rays, out.len(), &mut best, stack);
        for (lane, o) in out.iter_mut().enumerate() {
            *o = done >> lane & 1 == 1;
        }
    }
}

/// One packet of the first `len` of `rays`, walked once per direction octant present; returns
/// the lanes that found a hit (any hit) or 0 (closest hit, whose answers are in `best`).
#[target_feature(enable = "avx512f")]
fn walk_packet<const ANY_HIT: bool>(
    kd: &KdTree,
    p: &Packet,
    rays: &[Ray],
    len: usize,
    best: &mut Best,
    stack: &mut PacketStack,
) -> u16 {
    let mut done = 0;
    if kd.nodes.is_empty() {
        return done;
    }
    // Each lane's segment in the root cell: its single-ray walk's own slab test.
    let (mut t0, mut t1, mut inside) = ([0.0f32; PACKET], [0.0f32; PACKET], 0u16);
    for (lane, ray) in rays.iter().enumerate().take(len) {
        if let Some((enter, exit)) = kd.bounds.intersect(ray) {
            (t0[lane], t1[lane]) = (enter, exit);
            inside |= 1 << lane;
        }
    }
    packet::octant_groups(p, len, |lanes, octant| {
        if lanes & inside != 0 {
            done |= walk::<ANY_HIT>(kd, p, lanes & inside, octant, (&t0, &t1), best, stack);
        }
    });
    done
}

raybench_accel::per_thread_stack!(
    /// Runs `f` with this thread's packet stack (a fresh one inside another walk).
    fn with_packet_stack -> PacketStack = new_stack()
);

fn new_stack() -> Box<PacketStack> {
    let empty = Entry {
        t0: [0.0; PACKET],
        t1: [0.0; PACKET],
        node: 0,
        lanes: 0,
    };
    Box::new([empty; MAX_DEPTH + 1])
}

/// The walk of the `active` lanes, whose directions all lie in `octant`, from their root
/// intervals `start`; with `ANY_HIT`, returns the lanes that found a hit (each done at its
/// first), else 0.
#[target_feature(enable = "avx512f")]
fn walk<const ANY_HIT: bool>(
    kd: &KdTree,
    p: &Packet,
    active: u16,
    octant: u8,
    start: (&[f32; PACKET], &[f32; PACKET]),
    best: &mut Best,
    stack: &mut PacketStack,
) -> u16 {
    // SAFETY: `start`'s arrays and every entry's are 16 initialised f32s; `loadu` and
    // `storeu` need no alignment.
    let load = |a: &[f32; PACKET]| unsafe { _mm512_loadu_ps(a.as_ptr()) };
    let store = |v: __m512| {
        let mut a = [0.0f32; PACKET];
        // SAFETY: as above.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), v) };
        a
    };
    let (mut t0, mut t1) = (load(start.0), load(start.1));
    let mut lanes = active;
    let mut live = active;
    let none = _mm512_set1_epi32(NO_PRIM as i32);
    let mut at = 0u32;
    let mut sp = 0;
    'walk: loop {
        let mut node = kd.nodes[at as usize];
        while !node.is_leaf() {
            let a = node.axis();
            let plane = _mm512_set1_ps(node.split());
            let t_split = _mm512_mul_ps(_mm512_sub_ps(plane, p.origin[a]), p.inv[a]);
            let (below, above) = (at + 1, node.above());
            let near = if octant >> a & 1 == 1 { above } else { below };
            let far = below ^ above ^ near;
            // Near unless the plane was crossed before the interval; far unless it comes
            // after it; both on NaN (the ray lies in the plane).
            let near_lanes = _mm512_mask_cmp_ps_mask::<_CMP_NLT_UQ>(lanes, t_split, t0);
            let far_lanes = _mm512_mask_cmp_ps_mask::<_CMP_NGT_UQ>(lanes, t_split, t1);
            if near_lanes == 0 {
                at = far;
            } else if far_lanes == 0 {
                at = near;
            } else {
                let both = near_lanes & far_lanes;
                stack[sp] = Entry {
                    t0: store(_mm512_mask_mov_ps(t0, both, _mm512_max_ps(t_split, t0))),
                    t1: store(t1),
                    node: far,
                    lanes: far_lanes,
                };
                sp += 1;
                t1 = _mm512_mask_mov_ps(t1, both, _mm512_min_ps(t_split, t1));
                lanes = near_lanes;
                at = near;
            }
            node = kd.nodes[at as usize];
        }
        let (first, count) = (node.first() as usize, node.count() as usize);
        for four in &kd.tri4s[first / LANES..(first + count).div_ceil(LANES)] {
            best.test_tri4(four, p, lanes);
        }
        if ANY_HIT {
            live &= !_mm512_mask_cmpneq_epi32_mask(lanes, best.prim, none);
            if live == 0 {
                break 'walk;
            }
        }
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            let e = &stack[sp];
            let enter = load(&e.t0);
            // Lanes whose interval starts beyond their closest hit are done with it.
            let keep = _mm512_mask_cmp_ps_mask::<_CMP_NGT_UQ>(e.lanes & live, enter, best.t);
            if keep != 0 {
                (at, lanes, t0) = (e.node, keep, enter);
                t1 = _mm512_min_ps(load(&e.t1), best.t);
                break;
            }
        }
    }
    active & !live
}
