//! Decoding a quantized node for the float kernels, and the AVX2 batch loops.
//!
//! A node is decoded to the float node's planes ([`WideNode`]) and handed to the float
//! node kernel, so the slab arithmetic is the float tree's, lane for lane: only the planes
//! differ, and every decoded plane lies outside its float plane, so a ray that enters a float
//! box enters its quantized box (subtraction and multiplication by the same inverse are
//! monotonic). With AVX2 the decode is one widening load (8 bytes to 8 lanes), one integer to
//! float conversion, a multiply by the power-of-two step (exact) and an add per plane; inlined
//! into the walk, the decoded planes stay in registers.

use super::BvhQuantized;
use super::node::{QNode, QWIDTH};
use crate::wide::WideNode;
use crate::wide::kernels::{NodeKernel, SseNodes};

/// A node kernel that can also test quantized nodes, by decoding them first.
pub(crate) trait QuantKernel: NodeKernel<QWIDTH> {
    /// The node's planes as floats, bit for bit [`QNode::decode_scalar`] in the used slots
    /// (unused slots are masked off by the walk, whatever they decode to).
    fn decode(self, n: &QNode) -> WideNode<QWIDTH>;
}

impl QuantKernel for SseNodes {
    #[inline(always)]
    fn decode(self, n: &QNode) -> WideNode<QWIDTH> {
        n.decode_scalar()
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{BvhQuantized, QNode, QWIDTH, QuantKernel, WideNode};
    use crate::wide::avx2::Avx2Nodes;
    use crate::wide::walk::Stack;
    use raybench_accel::{Hit, NoCount};
    use raybench_geom::Ray;
    use std::arch::x86_64::*;

    /// One plane row: 8 bytes widened to 8 lanes, `origin + q * step`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn decode_row(row: &[u8; QWIDTH], origin: __m256, step: __m256) -> [f32; QWIDTH] {
        let mut out = [0.0f32; QWIDTH];
        // SAFETY: `row` is 8 readable bytes (`loadl_epi64` reads exactly 8, unaligned) and
        // `out` 8 writable f32s (`storeu` has no alignment requirement).
        unsafe {
            let bytes = _mm_loadl_epi64(row.as_ptr().cast());
            let q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
            let plane = _mm256_add_ps(origin, _mm256_mul_ps(q, step));
            _mm256_storeu_ps(out.as_mut_ptr(), plane);
        }
        out
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    fn decode_avx2(n: &QNode) -> WideNode<QWIDTH> {
        let mut planes = [[[0.0f32; QWIDTH]; 2]; 3];
        for (axis, p) in planes.iter_mut().enumerate() {
            let origin = _mm256_set1_ps(n.origin[axis]);
            let step = _mm256_set1_ps(super::super::node::step(n.exp[axis]));
            p[0] = decode_row(&n.q[axis][0], origin, step);
            p[1] = decode_row(&n.q[axis][1], origin, step);
        }
        WideNode {
            planes,
            child: n.child,
        }
    }

    impl QuantKernel for Avx2Nodes {
        #[inline(always)]
        fn decode(self, n: &QNode) -> WideNode<QWIDTH> {
            // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
            unsafe { decode_avx2(n) }
        }
    }

    /// The walk compiled for AVX2, so the decode and the node test inline into the loop.
    #[target_feature(enable = "avx2")]
    pub(in crate::wide::quantized) fn walk_ray_avx2<
        const ANY_HIT: bool,
        C: raybench_accel::CounterSink,
    >(
        bvh: &BvhQuantized,
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
            fn $closest(
                bvh: &BvhQuantized,
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
            fn $any(
                bvh: &BvhQuantized,
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

    pub(in crate::wide::quantized) fn intersect_all(
        bvh: &BvhQuantized,
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

    pub(in crate::wide::quantized) fn occluded_all(
        bvh: &BvhQuantized,
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

        /// The AVX2 decode is the scalar decode bit for bit in every used slot.
        #[test]
        fn avx2_decode_matches_scalar() {
            let Some(k) = Avx2Nodes::detect(false) else {
                return;
            };
            for n in super::super::super::node::tests::sample_nodes() {
                let (a, b) = (k.decode(&n), n.decode_scalar());
                for i in 0..n.children() {
                    assert_eq!(
                        a.child_bounds(i).min.to_array().map(f32::to_bits),
                        b.child_bounds(i).min.to_array().map(f32::to_bits)
                    );
                    assert_eq!(
                        a.child_bounds(i).max.to_array().map(f32::to_bits),
                        b.child_bounds(i).max.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx2::{intersect_all, occluded_all, walk_ray_avx2};
