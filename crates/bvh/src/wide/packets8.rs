//! The packet walk of `packets.rs` on CPUs with AVX2 but not AVX-512F: each block of sixteen
//! coherent rays walked as two packets of eight, one ray per AVX2 lane, for closest or any
//! hit. The same walk in every other respect: the packet bounds first (`frustum.rs`'s
//! [`Frustum8`]), then each remaining child's box against the lanes that reach the node, the
//! stack kept in entry order, a subtree skipped when it starts beyond every active ray's best,
//! one walk per octant present, the same [`Switch`](super::packet_switch) handing packets to
//! the single-ray walk where their rays share little. Eight lanes halve what one visit does
//! for the rays, so a packet pays where its rays share nodes and leaves a little less than on
//! AVX-512. Where few lanes reach a node, it is tested lane by lane, and where one or two
//! reach a leaf, its (triangle, ray) pairs are tested in one pass, as on AVX-512.
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
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 and POPCNT on this CPU.
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
    each_packet::<LANES, W, _>(
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

/// Lanes at most this many that reach a node test its children lane by lane
/// ([`children_by_lane`]) where the packet bounds leave more children than that.
const FEW_LANES: u32 = 4;

/// Calls `push` with every child of `n` among `maybe` (the children the packet bounds leave)
/// that some of the `lanes` of `p` enter with their far ends at `t_far`, in slot order, as an
/// entry carrying the lanes that enter it and, with `DISTANCE`, the least of their entry
/// distances (else 0: the any-hit walk never compares them). The node is tested lane by lane
/// where few lanes reach it and the bounds leave more children than lanes (an 8- or 16-wide
/// node), else child by child up to the first unused slot; either way each lane enters the same
/// children.
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
    let few = lanes.count_ones();
    if W.is_multiple_of(8) && few <= FEW_LANES && few < maybe.count_ones() {
        for o in 0..W / 8 {
            let slots = (maybe >> (8 * o)) as u8;
            if slots == 0 {
                continue;
            }
            let (mut entered, lanes_of, entry_of) =
                children_by_lane(p, n, o, near, lanes, slots, t_far);
            while entered != 0 {
                let slot = entered.trailing_zeros() as usize;
                entered &= entered - 1;
                push(Entry {
                    r: n.child[8 * o + slot],
                    t_entry: if DISTANCE { entry_of[slot] } else { 0.0 },
                    lanes: lanes_of[slot] as u16,
                });
            }
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
                    packet8::reduce_min(entered, t0)
                } else {
                    0.0
                },
                lanes: entered.into(),
            });
        }
    }
}

/// The children `8 * o ..` of `n` among `slots` that the `lanes` of `p` enter with their far
/// ends at `t_far`, one pass a lane against the eight children (as the single-ray walk tests a
/// node): as a slot mask, and per slot the lanes that enter it and the least of their entry
/// distances (meaningful only for the slots in the mask). Slots not in use are never in the
/// mask. The same operands and operations as [`lanes_entering`], so the same lanes enter.
#[target_feature(enable = "avx2")]
#[inline]
fn children_by_lane<const W: usize>(
    p: &Packet8,
    n: &WideNode<W>,
    o: usize,
    near: [usize; 3],
    lanes: u8,
    slots: u8,
    t_far: __m256,
) -> (u8, [u32; 8], [f32; 8]) {
    let row = |r: &[f32; W]| {
        let octet: &[f32; 8] = &r.as_chunks::<8>().0[o];
        // SAFETY: a reference to 8 initialised f32s; `loadu` has no alignment requirement.
        unsafe { _mm256_loadu_ps(octet.as_ptr()) }
    };
    let lo = [0, 1, 2].map(|a| row(&n.planes[a][near[a]]));
    let hi = [0, 1, 2].map(|a| row(&n.planes[a][1 - near[a]]));
    // The slots in use (an unused one holds an empty box, minimum above maximum).
    let (min, max) = if near[0] == 0 {
        (lo[0], hi[0])
    } else {
        (hi[0], lo[0])
    };
    let slots = slots & bits(_mm256_cmp_ps::<_CMP_LE_OQ>(min, max));
    let mut entry = _mm256_set1_ps(f32::INFINITY);
    let mut by_slot = _mm256_setzero_si256();
    let mut union = 0u8;
    let mut rest = lanes;
    while rest != 0 {
        let lane = rest.trailing_zeros();
        rest &= rest - 1;
        let at = _mm256_set1_epi32(lane as i32);
        let pick = |v: __m256| _mm256_permutevar8x32_ps(v, at);
        let mut t0 = pick(p.t_min);
        let mut t1 = pick(t_far);
        for a in 0..3 {
            let (origin, inv) = (pick(p.origin[a]), pick(p.inv[a]));
            t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(lo[a], origin), inv), t0);
            t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(hi[a], origin), inv), t1);
        }
        let inside = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1);
        let entered = bits(inside) & slots;
        if entered == 0 {
            continue;
        }
        let m = packet8::lanes_mask(entered);
        entry = _mm256_blendv_ps(entry, _mm256_min_ps(entry, t0), m);
        let lane_bit = _mm256_and_si256(_mm256_castps_si256(m), _mm256_set1_epi32(1 << lane));
        by_slot = _mm256_or_si256(by_slot, lane_bit);
        union |= entered;
    }
    let mut lanes_of = [0u32; 8];
    let mut entry_of = [0.0f32; 8];
    // SAFETY: both are 8 writable 4-byte values; the unaligned stores need no alignment.
    unsafe {
        _mm256_storeu_si256(lanes_of.as_mut_ptr().cast(), by_slot);
        _mm256_storeu_ps(entry_of.as_mut_ptr(), entry);
    }
    (union, lanes_of, entry_of)
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
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 and POPCNT on this CPU.
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
    each_packet::<LANES, W, _>(
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

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::packet::RayPackets;
    use raybench_geom::{Aabb, SplitMix64, Vec3};

    /// A coordinate drawn from a few values that rays and boxes share (so origins lie in box
    /// planes) or a random one.
    fn coord(rng: &mut SplitMix64) -> f32 {
        match rng.next_u64() % 6 {
            0 => 0.0,
            1 => 1.0,
            2 => -0.5,
            _ => rng.signed() * 2.0,
        }
    }

    fn node<const W: usize>(rng: &mut SplitMix64) -> WideNode<W> {
        let mut n = WideNode::<W>::empty();
        for slot in 0..1 + rng.next_u64() as usize % W {
            let a = Vec3::new(coord(rng), coord(rng), coord(rng));
            let mut b = Vec3::new(coord(rng), coord(rng), coord(rng));
            if rng.next_u64().is_multiple_of(5) {
                b[slot % 3] = a[slot % 3]; // a flat box
            }
            let r = ChildRef {
                index: slot as u32,
                count: 1,
            };
            n.set_child(slot, &Aabb::new(a.min(b), a.max(b)), r);
        }
        n
    }

    /// Lane by lane answers as child by child on every lane subset of a few sizes: the same
    /// children entered by the same lanes, with the same least entry distance, on random
    /// 8- and 16-wide nodes (some slots unused, some boxes flat) and packets whose rays have
    /// zero direction components and origins in the boxes' planes.
    #[test]
    fn lanes_enter_the_children_they_enter_one_child_at_a_time() {
        if Avx2Packets::detect().is_none() {
            eprintln!("no AVX2 on this CPU: the eight-lane packet walk does not run here");
            return;
        }
        fn check<const W: usize>(rng: &mut SplitMix64) -> usize {
            let rays: Vec<Ray> = (0..16)
                .map(|_| {
                    let origin = Vec3::new(coord(rng), coord(rng), coord(rng));
                    let mut dir = rng.signed_vec();
                    for a in 0..3 {
                        match rng.next_u64() % 8 {
                            0 => dir[a] = 0.0,
                            1 => dir[a] = -0.0,
                            _ => {}
                        }
                    }
                    if dir == Vec3::ZERO {
                        dir.x = 1.0;
                    }
                    let t_max = [f32::INFINITY, 0.75, 3.0][rng.next_u64() as usize % 3];
                    Ray::new(origin, dir, rng.unit() * 0.1, t_max)
                })
                .collect();
            let packets = RayPackets::new(&rays);
            let block = &packets.range(0, 16).expect("one block")[0];
            let n = node::<W>(rng);
            let mut pairs = 0;
            for half in 0..2 {
                // SAFETY: `detect` saw AVX2 above.
                unsafe {
                    let (p, best) = packet8::load(block, half);
                    packet8::octant_groups(&p, LANES, |group, octant| {
                        let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
                        for subset in [group, group & 0x55, group & 0x0F, group & 0x03] {
                            if subset == 0 {
                                continue;
                            }
                            for o in 0..W / 8 {
                                let slots = rng.next_u64() as u8 | 0x3;
                                let (union, lanes_of, entry_of) =
                                    children_by_lane(&p, &n, o, near, subset, slots, best.t);
                                for slot in 0..8 {
                                    let at = 8 * o + slot;
                                    let used = at < n.children();
                                    let (want, t) = if used && slots >> slot & 1 == 1 {
                                        let (e, t0) =
                                            lanes_entering(&p, &n, near, subset, at, best.t);
                                        (
                                            e,
                                            if e != 0 {
                                                packet8::reduce_min(e, t0)
                                            } else {
                                                0.0
                                            },
                                        )
                                    } else {
                                        (0, 0.0)
                                    };
                                    assert_eq!(union >> slot & 1 == 1, want != 0, "slot {at}");
                                    if want != 0 {
                                        assert_eq!(lanes_of[slot] as u8, want, "slot {at}");
                                        assert_eq!(entry_of[slot], t, "slot {at}");
                                        pairs += want.count_ones() as usize;
                                    }
                                }
                            }
                        }
                    });
                }
            }
            pairs
        }
        let mut rng = SplitMix64::new(0xfe18);
        let pairs: usize = (0..2_000)
            .map(|_| check::<8>(&mut rng) + check::<16>(&mut rng))
            .sum();
        assert!(pairs > 20_000, "only {pairs} (lane, child) entries");
    }
}
