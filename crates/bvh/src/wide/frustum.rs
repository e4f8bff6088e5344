//! A packet's rays bounded per axis, to rule out the children of a wide node that none of them
//! can enter in one 8-lane pass (interval arithmetic over the packet, as in Wald, Boulos and
//! Shirley 2007), before the packet walk tests the rest ray by ray.
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
use std::arch::x86_64::*;

/// Bounds over a set of lanes of a packet whose directions lie in one octant.
pub(super) struct Frustum {
    /// Per axis, the origin coordinate giving the smallest entry distance through a near
    /// plane (the largest origin where the direction is positive, the smallest where it is
    /// negative) and the one giving the largest exit distance through a far plane.
    near_origin: [__m256; 3],
    far_origin: [__m256; 3],
    /// Per axis, the smallest and largest inverse direction.
    inv_lo: [__m256; 3],
    inv_hi: [__m256; 3],
    /// The smallest `t_min`.
    t_min: __m256,
    /// Per axis, which stored side (min or max) holds the near planes (the walk's, too).
    pub(super) near: [usize; 3],
}

impl Frustum {
    /// The bounds of the `lanes` of `p` (not empty), whose directions lie in `octant` (bit `a`
    /// set when axis `a` points down).
    #[target_feature(enable = "avx512f")]
    pub(super) fn new(p: &Packet, lanes: u16, octant: u8) -> Frustum {
        let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
        let splat = |x: f32| _mm256_set1_ps(x);
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
    /// clear only when no lane's slab test can enter child `i`. Eight slots a pass; a 4-wide
    /// node has every slot set.
    #[target_feature(enable = "avx512f")]
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

    /// [`Frustum::maybe_entered`] for the slots `8 * o ..`.
    #[target_feature(enable = "avx512f")]
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
