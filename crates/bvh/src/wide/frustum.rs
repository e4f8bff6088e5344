//! A packet's rays bounded per axis, to rule out the children of a wide node that none of them
//! can enter in one pass (interval arithmetic over the packet, as in Wald, Boulos and Shirley
//! 2007), before the packet walk tests the rest ray by ray: eight slots a pass for an 8-wide
//! node, all sixteen of a 16-wide node in one 16-lane pass (the same operations lane for lane,
//! so the same slots as two 8-lane passes). The eight-lane packets of AVX2 ([`Frustum8`]) bound
//! their rays the same way and take the 8-lane passes.
//!
//! Exactness: the bound never rules out a child that a ray's own slab test enters, so the
//! packet walk tests, pushes and visits exactly what it would without it. Per axis, a ray's
//! entry distance through a plane is `(plane - origin) * inverse`, rounded twice. Both roundings
//! are monotone, and within one octant walk every ray's inverse has the same sign on an axis, so
//! the smallest value any ray can get is reached with the origin at one end of the packet's
//! origin range (which end depends on the sign) and the inverse at one of its ends; computed
//! with the same operations in the same order, it rounds to a value no larger than any ray's.
//! Likewise for the largest exit distance. A product that is NaN (`0 * inf`, a ray in a box's
//! face plane, which the slab test ignores on that axis) makes that axis unbounded.

use super::node::WideNode;
use raybench_geom::packet::Packet;
use raybench_geom::packet8::{self, Packet8};
use std::arch::x86_64::*;

/// Bounds over a set of lanes of a packet whose directions lie in one octant.
pub(super) struct Frustum {
    /// Per axis, the origin coordinate giving the smallest entry distance through a near
    /// plane (the largest origin where the direction is positive, the smallest where it is
    /// negative) and the one giving the largest exit distance through a far plane.
    near_origin: [__m512; 3],
    far_origin: [__m512; 3],
    /// Per axis, the smallest and largest inverse direction.
    inv_lo: [__m512; 3],
    inv_hi: [__m512; 3],
    /// The smallest `t_min`.
    t_min: __m512,
    /// Per axis, which stored side (min or max) holds the near planes (the walk's, too).
    pub(super) near: [usize; 3],
}

impl Frustum {
    /// The bounds of the `lanes` of `p` (not empty), whose directions lie in `octant` (bit `a`
    /// set when axis `a` points down).
    #[target_feature(enable = "avx512f")]
    pub(super) fn new(p: &Packet, lanes: u16, octant: u8) -> Frustum {
        let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
        let splat = |x: f32| _mm512_set1_ps(x);
        let lo = |v: __m512| _mm512_mask_reduce_min_ps(lanes, v);
        let hi = |v: __m512| _mm512_mask_reduce_max_ps(lanes, v);
        let down = |a: usize| near[a] == 1;
        Frustum {
            near_origin: [0, 1, 2].map(|a| {
                splat(if down(a) {
                    lo(p.origin[a])
                } else {
                    hi(p.origin[a])
                })
            }),
            far_origin: [0, 1, 2].map(|a| {
                splat(if down(a) {
                    hi(p.origin[a])
                } else {
                    lo(p.origin[a])
                })
            }),
            inv_lo: p.inv.map(|v| splat(lo(v))),
            inv_hi: p.inv.map(|v| splat(hi(v))),
            t_min: splat(lo(p.t_min)),
            near,
        }
    }

    /// The slots of `n` that some lane may enter with its far end at most `t_max`: bit `i`
    /// clear only when no lane's slab test can enter child `i`. Sixteen slots in one pass, eight
    /// a pass for an 8-wide node; a 4-wide node has every slot set.
    #[target_feature(enable = "avx512f")]
    pub(super) fn maybe_entered<const W: usize>(&self, n: &WideNode<W>, t_max: f32) -> u32 {
        if W == 16 {
            return self.sixteen(n, t_max);
        }
        self.by_octets(n, t_max)
    }

    /// [`Frustum::maybe_entered`] eight slots a pass.
    #[target_feature(enable = "avx512f")]
    fn by_octets<const W: usize>(&self, n: &WideNode<W>, t_max: f32) -> u32 {
        if !W.is_multiple_of(8) {
            return (1 << W) - 1;
        }
        let mut mask = 0;
        for o in 0..W / 8 {
            mask |= self.octet(n, o, t_max) << (8 * o);
        }
        mask
    }

    /// [`Frustum::maybe_entered`] for the slots `8 * o ..`: [`Frustum8::octet`] on the low
    /// halves (the bounds are the same in every lane).
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn octet<const W: usize>(&self, n: &WideNode<W>, o: usize, t_max: f32) -> u32 {
        let low = |v: __m512| _mm512_castps512_ps256(v);
        let eight = Frustum8 {
            near_origin: self.near_origin.map(low),
            far_origin: self.far_origin.map(low),
            inv_lo: self.inv_lo.map(low),
            inv_hi: self.inv_hi.map(low),
            t_min: low(self.t_min),
            near: self.near,
        };
        eight.octet(n, o, t_max)
    }

    /// [`Frustum::maybe_entered`] for a 16-wide node, in one 16-lane pass: [`Frustum::octet`]'s
    /// operations lane for lane (`min`, `max` and the ordered compare behave alike at both
    /// widths, NaN included).
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sixteen<const W: usize>(&self, n: &WideNode<W>, t_max: f32) -> u32 {
        assert!(W == 16, "a 16-lane bound of a {W}-wide node");
        let bound = |x: __m512, y: __m512, nearest: bool| {
            let nan = _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(x, y);
            let (b, fill) = if nearest {
                (_mm512_min_ps(x, y), f32::NEG_INFINITY)
            } else {
                (_mm512_max_ps(x, y), f32::INFINITY)
            };
            _mm512_mask_blend_ps(nan, b, _mm512_set1_ps(fill))
        };
        let mut t0 = self.t_min;
        let mut t1 = _mm512_set1_ps(t_max);
        for a in 0..3 {
            let load = |side: usize| {
                let row: &[f32; W] = &n.planes[a][side];
                // SAFETY: W is 16 (asserted above), so the row is 16 initialised f32s; `loadu`
                // has no alignment requirement.
                unsafe { _mm512_loadu_ps(row.as_ptr()) }
            };
            let (inv_lo, inv_hi) = (self.inv_lo[a], self.inv_hi[a]);
            let d = _mm512_sub_ps(load(self.near[a]), self.near_origin[a]);
            let entry = bound(_mm512_mul_ps(d, inv_lo), _mm512_mul_ps(d, inv_hi), true);
            t0 = _mm512_max_ps(entry, t0);
            let d = _mm512_sub_ps(load(1 - self.near[a]), self.far_origin[a]);
            let exit = bound(_mm512_mul_ps(d, inv_lo), _mm512_mul_ps(d, inv_hi), false);
            t1 = _mm512_min_ps(exit, t1);
        }
        u32::from(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(t0, t1))
    }
}

/// [`Frustum`] over a set of lanes of an eight-lane packet ([`Packet8`], AVX2), each bound
/// broadcast to eight lanes: one pass per eight slots.
pub(super) struct Frustum8 {
    near_origin: [__m256; 3],
    far_origin: [__m256; 3],
    inv_lo: [__m256; 3],
    inv_hi: [__m256; 3],
    t_min: __m256,
    pub(super) near: [usize; 3],
}

impl Frustum8 {
    /// The bounds of the `lanes` of `p` (not empty), whose directions lie in `octant`.
    #[target_feature(enable = "avx2")]
    pub(super) fn new(p: &Packet8, lanes: u8, octant: u8) -> Frustum8 {
        let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
        let splat = |x: f32| _mm256_set1_ps(x);
        let lo = |v: __m256| packet8::reduce_min(lanes, v);
        let hi = |v: __m256| packet8::reduce_max(lanes, v);
        let down = |a: usize| near[a] == 1;
        Frustum8 {
            near_origin: [0, 1, 2].map(|a| {
                splat(if down(a) {
                    lo(p.origin[a])
                } else {
                    hi(p.origin[a])
                })
            }),
            far_origin: [0, 1, 2].map(|a| {
                splat(if down(a) {
                    hi(p.origin[a])
                } else {
                    lo(p.origin[a])
                })
            }),
            inv_lo: p.inv.map(|v| splat(lo(v))),
            inv_hi: p.inv.map(|v| splat(hi(v))),
            t_min: splat(lo(p.t_min)),
            near,
        }
    }

    /// The slots of `n` that some lane may enter with its far end at most `t_max`, as
    /// [`Frustum::maybe_entered`], eight slots a pass; a 4-wide node has every slot set.
    #[target_feature(enable = "avx2")]
    pub(super) fn maybe_entered<const W: usize>(&self, n: &WideNode<W>, t_max: f32) -> u32 {
        if !W.is_multiple_of(8) {
            return (1 << W) - 1;
        }
        let mut mask = 0;
        for o in 0..W / 8 {
            mask |= self.octet(n, o, t_max) << (8 * o);
        }
        mask
    }

    /// [`Frustum8::maybe_entered`] for the slots `8 * o ..`.
    #[target_feature(enable = "avx")]
    #[inline]
    fn octet<const W: usize>(&self, n: &WideNode<W>, o: usize, t_max: f32) -> u32 {
        // A NaN bound (`0 * inf`) is replaced by `fill`: no bound on that axis.
        let bound = |x: __m256, y: __m256, nearest: bool| {
            let nan = _mm256_cmp_ps::<_CMP_UNORD_Q>(x, y);
            let (b, fill) = if nearest {
                (_mm256_min_ps(x, y), f32::NEG_INFINITY)
            } else {
                (_mm256_max_ps(x, y), f32::INFINITY)
            };
            _mm256_blendv_ps(b, _mm256_set1_ps(fill), nan)
        };
        let mut t0 = self.t_min;
        let mut t1 = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let load = |side: usize| {
                let row: &[f32; 8] = &n.planes[a][side].as_chunks::<8>().0[o];
                // SAFETY: a reference to 8 initialised f32s; `loadu` has no alignment
                // requirement.
                unsafe { _mm256_loadu_ps(row.as_ptr()) }
            };
            let (inv_lo, inv_hi) = (self.inv_lo[a], self.inv_hi[a]);
            let d = _mm256_sub_ps(load(self.near[a]), self.near_origin[a]);
            let entry = bound(_mm256_mul_ps(d, inv_lo), _mm256_mul_ps(d, inv_hi), true);
            t0 = _mm256_max_ps(entry, t0);
            let d = _mm256_sub_ps(load(1 - self.near[a]), self.far_origin[a]);
            let exit = bound(_mm256_mul_ps(d, inv_lo), _mm256_mul_ps(d, inv_hi), false);
            t1 = _mm256_min_ps(exit, t1);
        }
        // An empty slot (+inf minimum, -inf maximum) may pass where an inverse is zero; the
        // walk stops at the first empty slot.
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::ChildRef;
    use raybench_geom::packet::{Avx512Packets, RayPackets, load, octant_groups};
    use raybench_geom::{Aabb, Ray, SplitMix64, Vec3};

    /// A coordinate from a short list (so planes often equal an origin's coordinate, and a ray
    /// along an axis then meets `0 * inf`) or, half the time, any value in `[-2, 2)`.
    fn coordinate(rng: &mut SplitMix64) -> f32 {
        const GRID: [f32; 5] = [-1.0, -0.5, 0.0, 0.5, 1.0];
        if rng.next_u64() & 1 == 0 {
            GRID[(rng.next_u64() % 5) as usize]
        } else {
            rng.range(-2.0, 2.0)
        }
    }

    /// A direction component: often zero (either sign), else any value in `[-1, 1)`.
    fn component(rng: &mut SplitMix64) -> f32 {
        match rng.next_u64() % 4 {
            0 => 0.0,
            1 => -0.0,
            _ => rng.range(-1.0, 1.0),
        }
    }

    /// The one 16-lane pass rules out exactly the slots two 8-lane passes rule out, on
    /// packets with zero direction components, origins on the boxes' planes, nodes with empty
    /// slots and several far ends.
    #[test]
    fn sixteen_lanes_rule_out_what_two_octets_do() {
        if Avx512Packets::detect().is_none() {
            eprintln!("no AVX-512F on this CPU: the 16-lane packet bounds never run here");
            return;
        }
        let mut rng = SplitMix64::new(17);
        let (mut cases, mut ruled_out, mut kept) = (0, 0u32, 0u32);
        for _ in 0..400 {
            let rays: Vec<Ray> = (0..16)
                .map(|_| {
                    let o = Vec3::new(
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                    );
                    let mut d = Vec3::new(
                        component(&mut rng),
                        component(&mut rng),
                        component(&mut rng),
                    );
                    if d.abs().max_element() == 0.0 {
                        d.x = 1.0;
                    }
                    Ray::new(o, d, rng.range(0.0, 0.1), f32::INFINITY)
                })
                .collect();
            let mut node = WideNode::<16>::empty();
            for slot in 0..1 + (rng.next_u64() % 16) as usize {
                let corner = |rng: &mut SplitMix64| {
                    Vec3::new(coordinate(rng), coordinate(rng), coordinate(rng))
                };
                let (a, b) = (corner(&mut rng), corner(&mut rng));
                let child = ChildRef {
                    index: slot as u32,
                    count: 1,
                };
                node.set_child(slot, &Aabb::new(a.min(b), a.max(b)), child);
            }
            let packets = RayPackets::new(&rays);
            let block = &packets.range(0, 16).expect("one whole block")[0];
            // SAFETY: AVX-512F was detected above.
            unsafe {
                let (p, _) = load(block);
                octant_groups(&p, 16, |lanes, octant| {
                    let f = Frustum::new(&p, lanes, octant);
                    for t_max in [f32::INFINITY, 1.5, 0.25] {
                        let one = f.sixteen(&node, t_max);
                        assert_eq!(one, f.by_octets(&node, t_max), "lanes {lanes:016b}");
                        ruled_out += 16 - one.count_ones();
                        kept += one.count_ones();
                        cases += 1;
                    }
                });
            }
        }
        assert!(cases >= 1200, "{cases} cases");
        // Neither answer alone would make the comparison meaningful.
        assert!(
            ruled_out > 1000 && kept > 1000,
            "ruled out {ruled_out}, kept {kept}"
        );
    }

    /// The eight-lane bounds (AVX2) never rule out a child that one of their rays' slab tests
    /// enters, with the walk's operations (`max` and `min` keeping the accumulator on a NaN),
    /// on rays with zero direction components and origins on the boxes' planes; and they rule
    /// out children, or they would prove nothing.
    #[test]
    fn eight_lane_bounds_keep_every_child_a_ray_enters() {
        use raybench_geom::packet8::{self, Avx2Packets};
        if Avx2Packets::detect().is_none() {
            eprintln!("no AVX2 on this CPU: the eight-lane packet bounds never run here");
            return;
        }
        let mut rng = SplitMix64::new(18);
        let (mut entered, mut ruled_out) = (0u32, 0u32);
        for _ in 0..300 {
            let rays: Vec<Ray> = (0..16)
                .map(|_| {
                    let o = Vec3::new(
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                    );
                    let mut d = Vec3::new(
                        component(&mut rng),
                        component(&mut rng),
                        component(&mut rng),
                    );
                    if d.abs().max_element() == 0.0 {
                        d.x = 1.0;
                    }
                    Ray::new(o, d, rng.range(0.0, 0.1), f32::INFINITY)
                })
                .collect();
            let mut node = WideNode::<16>::empty();
            let used = 1 + (rng.next_u64() % 16) as usize;
            for slot in 0..used {
                let corner = |rng: &mut SplitMix64| {
                    Vec3::new(coordinate(rng), coordinate(rng), coordinate(rng))
                };
                let (a, b) = (corner(&mut rng), corner(&mut rng));
                let child = ChildRef {
                    index: slot as u32,
                    count: 1,
                };
                node.set_child(slot, &Aabb::new(a.min(b), a.max(b)), child);
            }
            let packets = RayPackets::new(&rays);
            let block = &packets.range(0, 16).expect("one whole block")[0];
            for half in 0..2 {
                // SAFETY: AVX2 was detected above.
                unsafe {
                    let (p, _) = packet8::load(block, half);
                    packet8::octant_groups(&p, 8, |lanes, octant| {
                        let f = Frustum8::new(&p, lanes, octant);
                        for t_max in [f32::INFINITY, 1.5, 0.25] {
                            let maybe = f.maybe_entered(&node, t_max);
                            for lane in (0..8).filter(|l| lanes >> l & 1 == 1) {
                                let ray = &rays[8 * half + lane];
                                for slot in 0..used {
                                    if enters(ray, &node, slot, f.near, t_max) {
                                        assert_eq!(maybe >> slot & 1, 1, "slot {slot}");
                                        entered += 1;
                                    }
                                }
                            }
                            ruled_out += used as u32 - (maybe & ((1 << used) - 1)).count_ones();
                        }
                    });
                }
            }
        }
        assert!(
            entered > 1000 && ruled_out > 1000,
            "entered {entered}, ruled out {ruled_out}"
        );
    }

    /// The walk's slab test of one ray against child `slot` of `n`, far end `t_max`.
    fn enters(ray: &Ray, n: &WideNode<16>, slot: usize, near: [usize; 3], t_max: f32) -> bool {
        let (o, inv) = (ray.origin(), ray.inv_dir());
        let (mut t0, mut t1) = (ray.t_min(), t_max);
        for a in 0..3 {
            let entry = (n.planes[a][near[a]][slot] - o[a]) * inv[a];
            let exit = (n.planes[a][1 - near[a]][slot] - o[a]) * inv[a];
            t0 = if entry > t0 { entry } else { t0 };
            t1 = if exit < t1 { exit } else { t1 };
        }
        t0 <= t1
    }
}
