//! The packet walk of `packets.rs` on CPUs with AVX2 but not AVX-512F: each block of sixteen
//! coherent rays walked as two packets of eight, one ray per AVX2 lane, for closest or any
//! hit. The same walk in every other respect: the packet bounds first (`frustum.rs`'s
//! [`Frustum8`]), then each remaining child's box against the lanes that reach the node, the
//! stack kept in entry order, a subtree skipped when it starts beyond every active ray's best,
//! one walk per octant present, the same [`Switch`](super::packet_switch) handing packets to
//! the single-ray walk where their rays share little. Eight lanes halve what one visit does
//! for the rays, so a packet pays where its rays share nodes and leaves a little less than on
//! AVX-512. Where few lanes reach a node, every child is still tested against the packet:
//! with eight lanes the lane-by-lane test of `packet_node.rs` has less to save.
//!
//! Exactness as in `packets.rs`: every lane computes its ray's slab tests and triangle tests
//! with the single-ray walk's operations in the same order, so each ray's hit, `t`, `u` and
//! `v` are the single-ray walk's, bit for bit, and an any-hit lane is occluded exactly when
//! its single-ray walk finds a hit.

use super::avx2;
use super::frustum::Frustum8;
use super::node::WideNode;
use super::packet_switch::{Usage, each_packet};
use super::packets::{Entry, PacketStack, push_sorted, with_packet_stack};
use super::walk::with_stack;
use crate::node::ChildRef;
use crate::wide::BvhWide;
use raybench_accel::Hit;
use raybench_geom::packet::RayBlock;
use raybench_geom::packet8::{self, Avx2Packets, Best8, LANES, Packet8, bits};
use raybench_geom::{NO_PRIM, Ray};
use std::arch::x86_64::*;

/// Traces a coherent batch (closest hit), eight rays a packet, two packets per block; `out`
/// gets the first `out.len()` rays of `blocks`, which are `rays` (the batch from ray `first`
/// on).
pub(crate) fn intersect_coherent<const W: usize>(
    _k: Avx2Packets,
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [Option<Hit>],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 on this CPU, and every
        // AVX2 CPU has POPCNT.
        unsafe { intersect_packets(bvh, blocks, rays, first, out, stack) }
    })
}

#[target_feature(enable = "avx2,popcnt")]
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
    each_packet(
        bvh,
        blocks,
        rays,
        first,
        out,
        single,
        |block, out, usage| {
            for (half, out) in out.chunks_mut(LANES).enumerate() {
                let (packet, mut best) = packet8::load(block, half);
                if !bvh.tri4s().is_empty() {
                    packet8::octant_groups(&packet, out.len(), |lanes, octant| {
                        walk(bvh, &packet, lanes, octant, &mut best, stack, usage)
                    });
                }
                for (o, (prim, h)) in out.iter_mut().zip(best.hits()) {
                    *o = (prim != NO_PRIM).then(|| Hit::from_tri_hit(prim, h));
                }
            }
        },
    );
}

/// The walk of the `active` lanes, whose directions all lie in `octant`; each subtree is
/// walked with the lanes that entered its box.
#[target_feature(enable = "avx2,popcnt")]
fn walk<const W: usize>(
    bvh: &BvhWide<W>,
    p: &Packet8,
    active: u8,
    octant: u8,
    best: &mut Best8,
    stack: &mut PacketStack,
    usage: &mut Usage,
) {
    let frustum = Frustum8::new(p, active, octant);
    let near = frustum.near;
    let mut farthest = packet8::reduce_max(active, best.t);
    let mut sp = 0;
    let mut r = bvh.root();
    let mut lanes = active;
    'walk: loop {
        if r.is_leaf() {
            let first = r.index as usize;
            let tri4s = (r.count as usize).div_ceil(4);
            usage.tri4s(tri4s as u32, lanes.into());
            for tri4 in &bvh.tri4s()[first..first + tri4s] {
                best.test_tri4(tri4, p, lanes);
            }
            farthest = packet8::reduce_max(active, best.t);
        } else {
            usage.node(lanes.into());
            let n = &bvh.nodes()[r.index as usize];
            let base = sp;
            let maybe = frustum.maybe_entered(n, farthest);
            each_entered::<W, true>(p, n, near, lanes, maybe, best.t, |e| {
                push_sorted(stack, base, &mut sp, e);
            });
            if sp > base {
                sp -= 1;
                (r, lanes) = (stack[sp].r, stack[sp].lanes as u8);
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
                (r, lanes) = (e.r, e.lanes as u8);
                continue 'walk;
            }
        }
    }
}

/// Calls `push` with every child of `n` among `maybe` (the children the packet bounds leave)
/// that some of the `lanes` of `p` enter with their far ends at `t_far`, in slot order, as an
/// entry carrying the lanes that enter it and, with `DISTANCE`, the least of their entry
/// distances (else 0: the any-hit walk never compares them); up to the first unused slot.
#[target_feature(enable = "avx2,popcnt")]
#[inline]
fn each_entered<const W: usize, const DISTANCE: bool>(
    p: &Packet8,
    n: &WideNode<W>,
    near: [usize; 3],
    lanes: u8,
    mut maybe: u32,
    t_far: __m256,
    mut push: impl FnMut(Entry),
) {
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
                    packet8::reduce_min(entered, t0)
                } else {
                    0.0
                },
                lanes: entered.into(),
            });
        }
    }
}

/// The lanes among `lanes` of `p` that enter child `slot` of `n` with their far ends at `t_far`
/// (a lane each), and every lane's entry distance into it: `packet_node.rs`'s
/// `lanes_entering` on eight lanes, the same operations in the same order.
#[target_feature(enable = "avx2")]
#[inline]
fn lanes_entering<const W: usize>(
    p: &Packet8,
    n: &WideNode<W>,
    near: [usize; 3],
    lanes: u8,
    slot: usize,
    t_far: __m256,
) -> (u8, __m256) {
    let mut t0 = p.t_min;
    let mut t1 = t_far;
    for (a, &near) in near.iter().enumerate() {
        let lo = _mm256_set1_ps(n.planes[a][near][slot]);
        let hi = _mm256_set1_ps(n.planes[a][1 - near][slot]);
        t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(lo, p.origin[a]), p.inv[a]), t0);
        t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(hi, p.origin[a]), p.inv[a]), t1);
    }
    (bits(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) & lanes, t0)
}

/// Traces a coherent batch (any hit), eight rays a packet, two packets per block; `out` gets
/// the first `out.len()` rays of `blocks`, which are `rays` (the batch from ray `first` on).
pub(crate) fn occluded_coherent<const W: usize>(
    _k: Avx2Packets,
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [bool],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 on this CPU, and every
        // AVX2 CPU has POPCNT.
        unsafe { occluded_packets(bvh, blocks, rays, first, out, stack) }
    })
}

#[target_feature(enable = "avx2,popcnt")]
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
    each_packet(
        bvh,
        blocks,
        rays,
        first,
        out,
        single,
        |block, out, usage| {
            for (half, out) in out.chunks_mut(LANES).enumerate() {
                let (packet, mut best) = packet8::load(block, half);
                let mut done = 0u8;
                if !bvh.tri4s().is_empty() {
                    packet8::octant_groups(&packet, out.len(), |lanes, octant| {
                        done |= walk_any(bvh, &packet, lanes, octant, &mut best, stack, usage)
                    });
                }
                for (lane, o) in out.iter_mut().enumerate() {
                    *o = done >> lane & 1 == 1;
                }
            }
        },
    );
}

/// The any-hit walk of the `active` lanes, whose directions all lie in `octant`; returns the
/// lanes that found a hit. `best` enters with each lane's `t_max` and is used only to test
/// triangles: a lane with a hit in it is done.
#[target_feature(enable = "avx2,popcnt")]
fn walk_any<const W: usize>(
    bvh: &BvhWide<W>,
    p: &Packet8,
    active: u8,
    octant: u8,
    best: &mut Best8,
    stack: &mut PacketStack,
    usage: &mut Usage,
) -> u8 {
    let t_max = best.t;
    let frustum = Frustum8::new(p, active, octant);
    let near = frustum.near;
    let farthest = packet8::reduce_max(active, t_max);
    let mut live = active;
    let mut sp = 0;
    let mut r = bvh.root();
    let mut lanes = active;
    'walk: loop {
        if r.is_leaf() {
            let first = r.index as usize;
            let tri4s = (r.count as usize).div_ceil(4);
            usage.tri4s(tri4s as u32, lanes.into());
            for tri4 in &bvh.tri4s()[first..first + tri4s] {
                best.test_tri4(tri4, p, lanes);
                let hit = best.hit_lanes() & lanes;
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
            usage.node(lanes.into());
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
            if u16::from(live) & e.lanes != 0 {
                (r, lanes) = (e.r, e.lanes as u8 & live);
                continue 'walk;
            }
        }
    }
    active & !live
}
