//! The AVX2 kernels of the wide BVHs, chosen at run time: the 8-wide node test in one pass of
//! 8-lane arithmetic per axis, and leaves tested two `Tri4`s a pass (`leaf.rs`).
//!
//! The SSE kernel ([`super::kernels::SseNodes`]) needs two 4-lane passes per axis for an 8-wide
//! node; AVX2 does the same arithmetic in one, lane for lane: `max`/`min` keep the accumulator when
//! a lane is NaN (`0 * inf` for a ray in a box's face plane, docs/validation.md, B1), the compare
//! is ordered (false on NaN). [`Avx2Nodes`] can only be made by [`Avx2Nodes::detect`], after the
//! CPU has reported AVX2, which is what makes calling the `#[target_feature]` code sound. AVX-512
//! adds no arithmetic an 8-lane f32 test needs; a 16-wide node takes one 16-lane pass per axis
//! where the CPU has AVX-512F ([`test_sixteen`], the same operations lane for lane, so the same
//! answers as two 8-lane passes). What AVX-512 adds to every width is registers: 32 vector
//! registers instead of 16. The walk keeps ten splatted values of the ray live
//! (origin, direction, inverse direction, `t_min`); with AVX2's sixteen, the compiler spills them
//! and reloads six at every node. The batch loops are therefore compiled twice (`batch_loops`),
//! once with AVX-512F and VL enabled; the same arithmetic runs in both, so the answers and counters
//! are the same (measured: see docs/experiments.md, "batch loops compiled a second time with
//! AVX-512F and VL").

mod leaf;
mod order;

use super::BvhWide;
use super::kernels::{NodeKernel, slab_quads};
use super::node::WideNode;
use super::walk::{Stack, nearest_first};
use crate::node::ChildRef;
use crate::simd::F4;
use leaf::leaf_pairs;
use order::{nearest_first_sorted, nearest_first_sorted16};
use raybench_accel::{CounterSink, Hit, NoCount};
use raybench_geom::{Ray, Tri4, TriHit};
use std::arch::x86_64::*;

/// Proof that this CPU runs AVX2 and POPCNT (the only way to reach the AVX2 code), and whether
/// the batch loops may also use AVX-512VL's 32 vector registers. POPCNT, which every CPU with
/// AVX2 has, counts a node's entered children in one instruction: without it the compiler
/// writes a dozen-instruction bit count into the 16-wide walks at every node.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2Nodes {
    wide_registers: bool,
}

impl Avx2Nodes {
    /// AVX2 (with POPCNT) when the CPU has it; with `avx512` also AVX-512F and VL when it has
    /// them.
    pub(crate) fn detect(avx512: bool) -> Option<Avx2Nodes> {
        let avx2 = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt");
        avx2.then(|| Avx2Nodes {
            wide_registers: avx512
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl"),
        })
    }

    /// Whether the batch loops run with AVX-512VL's registers.
    pub(crate) fn wide_registers(self) -> bool {
        self.wide_registers
    }
}

/// The ray for the AVX2 tests: origin, direction, inverse direction and `t_min` splatted to 8
/// lanes, and per axis which stored side (min or max) holds the near planes.
pub(crate) struct Avx2Ray {
    pub(in crate::wide) origin: [__m256; 3],
    pub(in crate::wide) inv: [__m256; 3],
    pub(in crate::wide) near: [bool; 3],
    dir: [__m256; 3],
    t_min: __m256,
}

#[target_feature(enable = "avx2")]
fn splat_ray(ray: &Ray) -> Avx2Ray {
    let inv = ray.inv_dir().to_array();
    let origin = ray.origin().to_array();
    Avx2Ray {
        origin: origin.map(|x| _mm256_set1_ps(x)),
        inv: inv.map(|x| _mm256_set1_ps(x)),
        // -0 counts as negative: its inverse is -inf (docs/validation.md, B3).
        near: inv.map(|x| x.is_sign_negative()),
        dir: ray.dir().to_array().map(|x| _mm256_set1_ps(x)),
        t_min: _mm256_set1_ps(ray.t_min()),
    }
}

/// The eight lanes `8 * o ..` of a plane row, for one AVX load.
#[inline(always)]
fn oct<const W: usize>(row: &[f32; W], o: usize) -> &[f32; 8] {
    &row.as_chunks::<8>().0[o]
}

/// One pass per axis and eight children.
#[target_feature(enable = "avx2")]
#[inline]
fn test_octs<const W: usize>(
    r: &Avx2Ray,
    n: &WideNode<W>,
    t_min: f32,
    t_max: f32,
) -> (u32, [f32; W]) {
    let mut mask = 0;
    let mut entry = [0.0f32; W];
    for o in 0..W / 8 {
        let mut t0 = _mm256_set1_ps(t_min);
        let mut t1 = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let near = oct(&n.planes[a][r.near[a] as usize], o);
            let far = oct(&n.planes[a][!r.near[a] as usize], o);
            // SAFETY: each is a reference to 8 contiguous initialised f32s, and `loadu` has
            // no alignment requirement.
            let (near, far) = unsafe {
                (
                    _mm256_loadu_ps(near.as_ptr()),
                    _mm256_loadu_ps(far.as_ptr()),
                )
            };
            t0 = _mm256_max_ps(
                _mm256_mul_ps(_mm256_sub_ps(near, r.origin[a]), r.inv[a]),
                t0,
            );
            t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(far, r.origin[a]), r.inv[a]), t1);
        }
        mask |= (_mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32) << (8 * o);
        let out: &mut [f32; 8] = &mut entry.as_chunks_mut::<8>().0[o];
        // SAFETY: `out` is 8 writable f32s; `storeu` has no alignment requirement.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), t0) };
    }
    (mask, entry)
}

/// The sixteen children of a 16-wide node in one 16-lane pass per axis (AVX-512F): the
/// arithmetic of [`test_octs`], lane for lane. The ray's 8-lane splats are widened here: the
/// widening does not depend on the node, so inlined into a batch loop it can leave the walk.
#[target_feature(enable = "avx2,avx512f")]
#[inline]
fn test_sixteen<const W: usize>(
    r: &Avx2Ray,
    n: &WideNode<W>,
    t_min: f32,
    t_max: f32,
) -> (u32, [f32; W]) {
    assert!(W == 16, "a 16-lane test of a {W}-wide node");
    let mut t0 = _mm512_set1_ps(t_min);
    let mut t1 = _mm512_set1_ps(t_max);
    for a in 0..3 {
        let near = &n.planes[a][r.near[a] as usize];
        let far = &n.planes[a][!r.near[a] as usize];
        let origin = _mm512_broadcastss_ps(_mm256_castps256_ps128(r.origin[a]));
        let inv = _mm512_broadcastss_ps(_mm256_castps256_ps128(r.inv[a]));
        // SAFETY: W is 16 (asserted above), so each row is 16 contiguous initialised f32s;
        // `loadu` has no alignment requirement.
        let (near, far) = unsafe {
            (
                _mm512_loadu_ps(near.as_ptr()),
                _mm512_loadu_ps(far.as_ptr()),
            )
        };
        t0 = _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(near, origin), inv), t0);
        t1 = _mm512_min_ps(_mm512_mul_ps(_mm512_sub_ps(far, origin), inv), t1);
    }
    let mask = u32::from(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(t0, t1));
    let mut entry = [0.0f32; W];
    // SAFETY: `entry` is 16 writable f32s (W is 16); `storeu` has no alignment requirement.
    unsafe { _mm512_storeu_ps(entry.as_mut_ptr(), t0) };
    (mask, entry)
}

impl<const W: usize> NodeKernel<W> for Avx2Nodes {
    type Ray = Avx2Ray;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> Avx2Ray {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { splat_ray(ray) }
    }

    #[inline(always)]
    fn test(self, ray: &Avx2Ray, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU, and says
        // `wide_registers` only when it also saw AVX-512F (and VL).
        unsafe {
            if W == 16 && self.wide_registers {
                test_sixteen(ray, n, t_min, t_max)
            } else if W.is_multiple_of(8) {
                test_octs(ray, n, t_min, t_max)
            } else {
                // 4 wide: the SSE kernel's arithmetic on the low halves of the splatted ray.
                let low = |v: &[__m256; 3]| v.map(|x| F4::from_m128(_mm256_castps256_ps128(x)));
                slab_quads(&low(&ray.origin), &low(&ray.inv), ray.near, n, t_min, t_max)
            }
        }
    }

    #[inline(always)]
    fn order(
        self,
        child: &[ChildRef; W],
        mask: u32,
        entry: &[f32; W],
        stack: &mut Stack,
        sp: &mut usize,
    ) -> ChildRef {
        // Up to three children, the short paths of `nearest_first` are cheaper than the
        // network's chain of stages (measured: see docs/experiments.md, "a sorting network for
        // nodes entering four or more children").
        if mask.count_ones() < 4 {
            return nearest_first(child, mask, entry, stack, sp);
        }
        if W == 16 && self.wide_registers {
            // SAFETY: `wide_registers` only after `detect` saw AVX-512F (and AVX2) on this CPU.
            return unsafe { nearest_first_sorted16(child, mask, entry, stack, sp) };
        }
        if W != 8 {
            return nearest_first(child, mask, entry, stack, sp);
        }
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { nearest_first_sorted(child, mask, entry, stack, sp) }
    }

    #[inline(always)]
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &Avx2Ray,
        tri4s: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { leaf_pairs::<ANY_HIT>(ray, tri4s, first, best_t, best) }
    }
}

/// [`BvhWide::walk_with`] compiled for AVX2, so [`test_octs`] inlines into the loop.
#[target_feature(enable = "avx2,popcnt")]
fn walk_ray_avx2<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    bvh.walk_with::<ANY_HIT, C, Avx2Nodes>(k, ray, stack, c)
}

#[inline(always)]
pub(crate) fn walk_ray<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    // SAFETY: `k` exists only after `detect` saw AVX2 and POPCNT on this CPU.
    unsafe { walk_ray_avx2::<W, ANY_HIT, C>(bvh, k, ray, stack, c) }
}

/// The batch loops, once per instruction set: the loop lives inside the `#[target_feature]`
/// code, so a ray pays no call, prologue or kernel dispatch of its own. The AVX-512 copies run
/// the same AVX2 arithmetic lane for lane (so the same answers); what they gain is sixteen more
/// vector registers, so the splatted ray (origin, direction, inverse direction, `t_min`: ten
/// registers) no longer spills to the stack and is reloaded at every node.
macro_rules! batch_loops {
    ($features:literal, $closest:ident, $any:ident) => {
        #[target_feature(enable = $features)]
        fn $closest<const W: usize>(
            bvh: &BvhWide<W>,
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
        fn $any<const W: usize>(
            bvh: &BvhWide<W>,
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

batch_loops!("avx2,popcnt", intersect_all_avx2, occluded_all_avx2);
batch_loops!(
    "avx2,avx512f,avx512vl,popcnt",
    intersect_all_avx512,
    occluded_all_avx512
);

pub(crate) fn intersect_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    stack: &mut Stack,
) {
    if k.wide_registers {
        // SAFETY: `k` says AVX-512F and VL only when `detect` saw them (and AVX2 and POPCNT) on
        // this CPU.
        unsafe { intersect_all_avx512(bvh, k, rays, out, stack) }
    } else {
        // SAFETY: `k` exists only after `detect` saw AVX2 and POPCNT on this CPU.
        unsafe { intersect_all_avx2(bvh, k, rays, out, stack) }
    }
}

pub(crate) fn occluded_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [bool],
    stack: &mut Stack,
) {
    if k.wide_registers {
        // SAFETY: `k` says AVX-512F and VL only when `detect` saw them (and AVX2 and POPCNT) on
        // this CPU.
        unsafe { occluded_all_avx512(bvh, k, rays, out, stack) }
    } else {
        // SAFETY: `k` exists only after `detect` saw AVX2 and POPCNT on this CPU.
        unsafe { occluded_all_avx2(bvh, k, rays, out, stack) }
    }
}
