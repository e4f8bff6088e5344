//! A packet's test of a wide node, two ways round. Child by child ([`lanes_entering`]): one
//! pass per child the packet bounds leave, each testing the child's box against all sixteen
//! lanes, which pays where most lanes reach the node. Lane by lane ([`children_by_lane`]): one
//! pass per lane, each testing all the node's children against that lane's ray, as the
//! single-ray walk tests a node, which pays where a few lanes reach a node that leaves many
//! children to test: deep in a tree, where a packet's rays have parted.
//!
//! Exactness: both compute a lane's entry and exit distances through a child's box from the
//! same operands, with the same operations in the same order (`(plane - origin) * inverse`,
//! `max` and `min` keeping the accumulator on a NaN, an ordered `<=`), which are also the
//! single-ray walk's, so each lane enters exactly the same children either way. A child's entry
//! distance is the least among the lanes that enter it either way; the walk only compares it,
//! so which of `-0` and `+0` a tie returns does not matter.

use super::node::WideNode;
use raybench_geom::packet::Packet;
use std::arch::x86_64::*;

/// The lanes among `lanes` of `p` that enter child `slot` of `n` with their far ends at `t_far`
/// (a lane each), and every lane's entry distance into it.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn lanes_entering<const W: usize>(
    p: &Packet,
    n: &WideNode<W>,
    near: [usize; 3],
    lanes: u16,
    slot: usize,
    t_far: __m512,
) -> (u16, __m512) {
    let mut t0 = p.t_min;
    let mut t1 = t_far;
    for (a, &near) in near.iter().enumerate() {
        let lo = _mm512_set1_ps(n.planes[a][near][slot]);
        let hi = _mm512_set1_ps(n.planes[a][1 - near][slot]);
        t0 = _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(lo, p.origin[a]), p.inv[a]), t0);
        t1 = _mm512_min_ps(_mm512_mul_ps(_mm512_sub_ps(hi, p.origin[a]), p.inv[a]), t1);
    }
    (_mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(lanes, t0, t1), t0)
}

/// The children of `n` among `slots` that the `lanes` of `p` enter with their far ends at
/// `t_far` (a lane each): as a slot mask, and per slot the lanes that enter it and the least of
/// their entry distances (meaningful only for the slots in the mask). Slots not in use are
/// never in the mask.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn children_by_lane<const W: usize>(
    p: &Packet,
    n: &WideNode<W>,
    near: [usize; 3],
    lanes: u16,
    slots: u32,
    t_far: __m512,
) -> (u32, [u32; 16], [f32; 16]) {
    let used = if W >= 16 { u16::MAX } else { (1u16 << W) - 1 };
    let row = |r: &[f32; W]| {
        // SAFETY: `used` covers the first `W` lanes only, and `r` holds `W` initialised f32s;
        // the masked load reads no other lane and needs no alignment.
        unsafe { _mm512_maskz_loadu_ps(used, r.as_ptr()) }
    };
    let lo = [0, 1, 2].map(|a| row(&n.planes[a][near[a]]));
    let hi = [0, 1, 2].map(|a| row(&n.planes[a][1 - near[a]]));
    // The slots in use (an unused one holds an empty box, minimum above maximum), so that no
    // slot the child-by-child walk stops before is ever reported, whatever a ray's direction.
    let (min, max) = if near[0] == 0 {
        (lo[0], hi[0])
    } else {
        (hi[0], lo[0])
    };
    let slots = slots as u16 & _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(used, min, max);
    let mut entry = _mm512_set1_ps(f32::INFINITY);
    let mut by_slot = _mm512_setzero_si512();
    let mut union = 0u16;
    let mut rest = lanes;
    while rest != 0 {
        let lane = rest.trailing_zeros();
        rest &= rest - 1;
        let at = _mm512_set1_epi32(lane as i32);
        let pick = |v: __m512| _mm512_permutexvar_ps(at, v);
        let mut t0 = pick(p.t_min);
        let mut t1 = pick(t_far);
        for a in 0..3 {
            let (origin, inv) = (pick(p.origin[a]), pick(p.inv[a]));
            t0 = _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(lo[a], origin), inv), t0);
            t1 = _mm512_min_ps(_mm512_mul_ps(_mm512_sub_ps(hi[a], origin), inv), t1);
        }
        let entered = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(slots, t0, t1);
        entry = _mm512_mask_min_ps(entry, entered, entry, t0);
        by_slot = _mm512_mask_or_epi32(by_slot, entered, by_slot, _mm512_set1_epi32(1 << lane));
        union |= entered;
    }
    let mut lanes_of = [0u32; 16];
    let mut entry_of = [0.0f32; 16];
    // SAFETY: both are 16 writable 4-byte values; the unaligned stores need no alignment.
    unsafe {
        _mm512_storeu_si512(lanes_of.as_mut_ptr().cast(), by_slot);
        _mm512_storeu_ps(entry_of.as_mut_ptr(), entry);
    }
    (u32::from(union), lanes_of, entry_of)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::ChildRef;
    use raybench_geom::packet::{Avx512Packets, RayPackets, load, octant_groups};
    use raybench_geom::{Ray, SplitMix64, Vec3};

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
        let used = 1 + rng.next_u64() as usize % W;
        for slot in 0..used {
            let a = Vec3::new(coord(rng), coord(rng), coord(rng));
            let mut b = Vec3::new(coord(rng), coord(rng), coord(rng));
            if rng.next_u64().is_multiple_of(5) {
                b[slot % 3] = a[slot % 3]; // a flat box
            }
            let r = ChildRef {
                index: slot as u32,
                count: 1,
            };
            n.set_child(slot, &raybench_geom::Aabb::new(a.min(b), a.max(b)), r);
        }
        n
    }

    /// Lane by lane answers as child by child, on every lane subset of a few sizes: the same
    /// children entered by the same lanes, and the same least entry distance, on random nodes
    /// of 8 and 16 children (some unused, some flat) and packets whose rays have zero
    /// direction components and origins in the boxes' planes.
    #[test]
    fn lanes_enter_the_children_they_enter_one_child_at_a_time() {
        let Some(_) = Avx512Packets::detect() else {
            eprintln!("no AVX-512F on this CPU: the packet walk does not run here");
            return;
        };
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
            let n = node::<W>(rng);
            let mut entered_pairs = 0;
            // SAFETY: `detect` saw AVX-512F above.
            unsafe {
                let (p, best) = load(&packets.range(0, 16).expect("one block")[0]);
                octant_groups(&p, 16, |group, octant| {
                    let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
                    for subset in [group, group & 0x5555, group & 0x0F0F, group & 0x0003] {
                        let lanes = subset & group;
                        if lanes == 0 {
                            continue;
                        }
                        let slots = rng.next_u64() as u32 | 0xF;
                        let (union, lanes_of, entry_of) =
                            children_by_lane(&p, &n, near, lanes, slots, best.t);
                        assert_eq!(union >> n.children(), 0, "a slot not in use");
                        for slot in 0..W {
                            let (want, t) = if slots >> slot & 1 == 1 {
                                let (e, t0) = lanes_entering(&p, &n, near, lanes, slot, best.t);
                                (e, _mm512_mask_reduce_min_ps(e, t0))
                            } else {
                                (0, 0.0)
                            };
                            assert_eq!(union >> slot & 1 == 1, want != 0, "slot {slot}");
                            if want != 0 {
                                assert_eq!(lanes_of[slot] as u16, want, "slot {slot}");
                                assert_eq!(entry_of[slot], t, "slot {slot}");
                                entered_pairs += want.count_ones() as usize;
                            }
                        }
                    }
                });
            }
            entered_pairs
        }
        let mut rng = SplitMix64::new(0xfe1a);
        let entered: usize = (0..3_000)
            .map(|_| check::<8>(&mut rng) + check::<16>(&mut rng))
            .sum();
        assert!(entered > 20_000, "only {entered} (lane, child) entries");
    }
}
