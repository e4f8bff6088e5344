//! The quantized node test, and the AVX2 batch loops.
//!
//! The arithmetic is the float node test's on decoded planes, lane for lane: every decoded
//! plane lies outside its float plane, and subtracting the origin and multiplying by the same
//! inverse direction are monotonic, so a ray that enters a float box enters its quantized box.
//! With AVX2 each plane row is decoded in registers — one widening load (8 bytes to 8 lanes),
//! one integer-to-float conversion, a multiply by the power-of-two step (exact) and an add —
//! right before the slab test; the portable kernel decodes the whole node to floats and runs
//! the float SSE test.

use super::BvhQuantized;
use super::node::{Plane, QNode, QWIDTH};
use crate::wide::kernels::{NodeKernel, SseNodes};

/// A node kernel that can also test quantized nodes.
pub(crate) trait QuantKernel<P: Plane>: NodeKernel<QWIDTH> {
    /// The float kernel's slab test on the node's decoded planes (bit for bit
    /// [`QNode::decode_scalar`]'s): entry distances, and the mask of the used slots entered
    /// within `[t_min, t_max]`.
    fn test_quantized(
        self,
        ray: &Self::Ray,
        n: &QNode<P>,
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; QWIDTH]);
}

/// The portable kernel decodes the node to floats and runs the float node test on them.
impl<P: Plane> QuantKernel<P> for SseNodes {
    #[inline(always)]
    fn test_quantized(
        self,
        ray: &Self::Ray,
        n: &QNode<P>,
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; QWIDTH]) {
        let (mask, entry) = self.test(ray, &n.decode_scalar(), t_min, t_max);
        (mask & n.used_mask(), entry)
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{BvhQuantized, Plane, QNode, QWIDTH, QuantKernel};
    use crate::wide::avx2::{Avx2Nodes, Avx2Ray};
    use crate::wide::walk::Stack;
    use raybench_accel::{Hit, NoCount};
    use raybench_geom::Ray;
    use std::arch::x86_64::*;

    /// One plane row in registers: 8 planes of 8 or 16 bits widened to 8 lanes, `origin + q
    /// * step`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn plane<P: Plane>(row: &[P; QWIDTH], origin: __m256, step: __m256) -> __m256 {
        let wide = if std::mem::size_of::<P>() == 1 {
            // SAFETY: `row` is 8 readable bytes; `loadl_epi64` reads exactly 8, unaligned.
            unsafe { _mm256_cvtepu8_epi32(_mm_loadl_epi64(row.as_ptr().cast())) }
        } else {
            // SAFETY: `row` is 8 `u16`s (`Plane` is sealed: `u8` or `u16`), 16 readable
            // bytes; `loadu_si128` reads exactly 16, unaligned.
            unsafe { _mm256_cvtepu16_epi32(_mm_loadu_si128(row.as_ptr().cast())) }
        };
        let q = _mm256_cvtepi32_ps(wide);
        _mm256_add_ps(origin, _mm256_mul_ps(q, step))
    }

    /// The float AVX2 node test (`test_octs`) on planes decoded in registers: per axis the
    /// near and far rows (chosen by the ray's direction signs) decoded, then the same
    /// subtract, multiply, `max`/`min` and ordered compare, lane for lane.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn test_avx2<P: Plane>(
        r: &Avx2Ray,
        n: &QNode<P>,
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; QWIDTH]) {
        let mut t0 = _mm256_set1_ps(t_min);
        let mut t1 = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let origin = _mm256_set1_ps(n.origin[a]);
            let step = _mm256_set1_ps(super::super::node::step(n.exp[a]));
            let near = plane(&n.q[a][r.near[a] as usize], origin, step);
            let far = plane(&n.q[a][!r.near[a] as usize], origin, step);
            t0 = _mm256_max_ps(
                _mm256_mul_ps(_mm256_sub_ps(near, r.origin[a]), r.inv[a]),
                t0,
            );
            t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(far, r.origin[a]), r.inv[a]), t1);
        }
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32;
        let mut entry = [0.0f32; QWIDTH];
        // SAFETY: `entry` is 8 writable f32s; `storeu` has no alignment requirement.
        unsafe { _mm256_storeu_ps(entry.as_mut_ptr(), t0) };
        (mask & n.used_mask(), entry)
    }

    impl<P: Plane> QuantKernel<P> for Avx2Nodes {
        #[inline(always)]
        fn test_quantized(
            self,
            ray: &Avx2Ray,
            n: &QNode<P>,
            t_min: f32,
            t_max: f32,
        ) -> (u32, [f32; QWIDTH]) {
            // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
            unsafe { test_avx2(ray, n, t_min, t_max) }
        }
    }

    /// The walk compiled for AVX2, so the decode and the node test inline into the loop.
    #[target_feature(enable = "avx2")]
    pub(in crate::wide::quantized) fn walk_ray_avx2<
        P: Plane,
        const ANY_HIT: bool,
        C: raybench_accel::CounterSink,
    >(
        bvh: &BvhQuantized<P>,
        k: Avx2Nodes,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        bvh.walk_with::<ANY_HIT, C, Avx2Nodes>(k, ray, stack, c)
    }

    /// The batch loops, once with AVX2 and once with AVX-512F and VL for their 32 registers
    /// (the same arithmetic, so the same answers), as the float tree's.
    macro_rules! batch_loops {
        ($features:literal, $closest:ident, $any:ident) => {
            #[target_feature(enable = $features)]
            fn $closest<P: Plane>(
                bvh: &BvhQuantized<P>,
                k: Avx2Nodes,
                rays: &[Ray],
                out: &mut [Option<Hit>],
                stack: &mut Stack,
            ) {
                for (o, ray) in out.iter_mut().zip(rays) {
                    *o = bvh.walk_with::<false, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount);
                }
            }

            #[target_feature(enable = $features)]
            fn $any<P: Plane>(
                bvh: &BvhQuantized<P>,
                k: Avx2Nodes,
                rays: &[Ray],
                out: &mut [bool],
                stack: &mut Stack,
            ) {
                for (o, ray) in out.iter_mut().zip(rays) {
                    *o = bvh
                        .walk_with::<true, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount)
                        .is_some();
                }
            }
        };
    }

    batch_loops!("avx2", intersect_all_avx2, occluded_all_avx2);
    batch_loops!(
        "avx2,avx512f,avx512vl",
        intersect_all_avx512,
        occluded_all_avx512
    );

    pub(in crate::wide::quantized) fn intersect_all<P: Plane>(
        bvh: &BvhQuantized<P>,
        k: Avx2Nodes,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stack: &mut Stack,
    ) {
        if k.wide_registers() {
            // SAFETY: `k` says AVX-512F and VL only when `detect` saw them on this CPU.
            unsafe { intersect_all_avx512(bvh, k, rays, out, stack) }
        } else {
            // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
            unsafe { intersect_all_avx2(bvh, k, rays, out, stack) }
        }
    }

    pub(in crate::wide::quantized) fn occluded_all<P: Plane>(
        bvh: &BvhQuantized<P>,
        k: Avx2Nodes,
        rays: &[Ray],
        out: &mut [bool],
        stack: &mut Stack,
    ) {
        if k.wide_registers() {
            // SAFETY: `k` says AVX-512F and VL only when `detect` saw them on this CPU.
            unsafe { occluded_all_avx512(bvh, k, rays, out, stack) }
        } else {
            // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
            unsafe { occluded_all_avx2(bvh, k, rays, out, stack) }
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// The AVX2 quantized node test answers as the portable one (decode, then the SSE
        /// float test), mask and entry distances bit for bit, on the extreme sample nodes and
        /// rays in every direction octant, axis-parallel ones included.
        #[test]
        fn avx2_test_matches_the_portable_test() {
            matches_portable::<u8>();
            matches_portable::<u16>();
        }

        fn matches_portable<P: Plane>() {
            use crate::wide::kernels::{NodeKernel, SseNodes};
            use raybench_geom::Vec3;
            let Some(k) = Avx2Nodes::detect(false) else {
                return;
            };
            let mut rng = 0x9e3779b97f4a7c15u64;
            let mut next = move || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
            };
            let mut checked = 0;
            for n in super::super::super::node::tests::sample_nodes::<P>() {
                for i in 0..2000 {
                    // Aimed at a point of one child from around it, or along an axis (±0 in
                    // the other components) every sixth ray.
                    let b = n.child_bounds(i % n.children());
                    let at = |t: f32| b.min + (b.max - b.min) * (t * 0.5 + 0.5);
                    let target = at(next());
                    let reach = (b.max - b.min).max_element().max(1.0) * 4.0;
                    let o = target + Vec3::new(next(), next(), next()) * reach;
                    let mut dir = target - o;
                    if i % 6 == 0 {
                        let keep = i % 3;
                        let zero = if i % 12 == 0 { 0.0 } else { -0.0 };
                        dir = Vec3::from_array(std::array::from_fn(|a| {
                            if a == keep { dir[a] } else { zero }
                        }));
                    }
                    if dir == Vec3::ZERO || !dir.is_finite() || !o.is_finite() {
                        continue;
                    }
                    let ray = Ray::infinite(o, dir);
                    let (sse, avx) = (SseNodes, k);
                    let sr = NodeKernel::<QWIDTH>::ray(sse, &ray);
                    let ar = NodeKernel::<QWIDTH>::ray(avx, &ray);
                    let (ms, es) = QuantKernel::<P>::test_quantized(sse, &sr, &n, 0.0, 1e30);
                    let (ma, ea) = QuantKernel::<P>::test_quantized(avx, &ar, &n, 0.0, 1e30);
                    assert_eq!(ms, ma, "{ray:?}");
                    for lane in 0..QWIDTH {
                        if ms & (1 << lane) != 0 {
                            assert_eq!(es[lane].to_bits(), ea[lane].to_bits(), "{ray:?}");
                        }
                    }
                    checked += ms.count_ones();
                }
            }
            assert!(checked > 1000, "the rays must enter children: {checked}");
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx2::{intersect_all, occluded_all, walk_ray_avx2};
