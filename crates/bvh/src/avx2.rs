//! The 8-wide node test in one pass of 8-lane AVX2 arithmetic per axis, chosen at run time.
//!
//! The SSE kernel ([`crate::wide::SseNodes`]) needs two 4-lane passes per axis for an 8-wide
//! node; AVX2 does the same arithmetic in one, lane for lane: `max`/`min` keep the accumulator
//! when a lane is NaN (`0 * inf` for a ray in a box's face plane, bug class B1), the compare is
//! ordered (false on NaN). [`Avx2Nodes`] can only be made by [`Avx2Nodes::detect`], after the
//! CPU has reported AVX2, which is what makes calling the `#[target_feature]` code sound.
//! AVX-512 adds nothing for 8 lanes of f32 that AVX2 lacks here (the mask compare into `k`
//! registers saves one `movemask`), so it is not a separate kernel.

use crate::wide::{BvhWide, NodeKernel, Stack, WideNode};
use raybench_accel::{CounterSink, Hit, NoCount};
use raybench_geom::Ray;
use std::arch::x86_64::*;

/// Proof that this CPU runs AVX2: the only way to reach the AVX2 code.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2Nodes(());

impl Avx2Nodes {
    pub(crate) fn detect() -> Option<Avx2Nodes> {
        std::arch::is_x86_feature_detected!("avx2").then_some(Avx2Nodes(()))
    }
}

/// The ray for the AVX2 test: origin and inverse direction splatted to 8 lanes, and per axis
/// which stored side (min or max) holds the near planes.
pub(crate) struct Avx2Ray {
    origin: [__m256; 3],
    inv: [__m256; 3],
    near: [bool; 3],
}

#[target_feature(enable = "avx2")]
fn splat_ray(ray: &Ray) -> Avx2Ray {
    let inv = ray.inv_dir().to_array();
    let origin = ray.origin().to_array();
    Avx2Ray {
        origin: origin.map(|x| _mm256_set1_ps(x)),
        inv: inv.map(|x| _mm256_set1_ps(x)),
        // -0 counts as negative: its inverse is -inf (bug class B3).
        near: inv.map(|x| x.is_sign_negative()),
    }
}

/// The eight lanes `8 * o ..` of a plane row, for one AVX load.
#[inline(always)]
fn oct<const W: usize>(row: &[f32; W], o: usize) -> &[f32; 8] {
    &row.as_chunks::<8>().0[o]
}

/// One pass per axis and eight children (a width that is not a multiple of 8 never gets
/// this kernel: see [`BvhWide`]'s build).
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

impl<const W: usize> NodeKernel<W> for Avx2Nodes {
    type Ray = Avx2Ray;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> Avx2Ray {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { splat_ray(ray) }
    }

    #[inline(always)]
    fn test(self, ray: &Avx2Ray, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { test_octs(ray, n, t_min, t_max) }
    }
}

/// [`BvhWide::walk_ray`] compiled for AVX2, so [`test_octs`] inlines into the loop.
#[target_feature(enable = "avx2")]
fn walk_ray_avx2<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    bvh.walk_ray::<ANY_HIT, C, Avx2Nodes>(k, ray, stack, c)
}

#[inline(always)]
pub(crate) fn walk_ray<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
    unsafe { walk_ray_avx2::<W, ANY_HIT, C>(bvh, k, ray, stack, c) }
}

/// Closest hits of a batch of rays in one AVX2 function: the loop lives inside the
/// `#[target_feature]` code, so a ray pays no call, prologue or kernel dispatch of its own.
#[target_feature(enable = "avx2")]
fn intersect_all_avx2<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    stack: &mut Stack,
) {
    for (o, ray) in out.iter_mut().zip(rays) {
        *o = bvh.walk_ray::<false, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount);
    }
}

/// Any-hit answers of a batch of rays, as [`intersect_all_avx2`].
#[target_feature(enable = "avx2")]
fn occluded_all_avx2<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [bool],
    stack: &mut Stack,
) {
    for (o, ray) in out.iter_mut().zip(rays) {
        *o = bvh
            .walk_ray::<true, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount)
            .is_some();
    }
}

pub(crate) fn intersect_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    stack: &mut Stack,
) {
    // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
    unsafe { intersect_all_avx2(bvh, k, rays, out, stack) }
}

pub(crate) fn occluded_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [bool],
    stack: &mut Stack,
) {
    // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
    unsafe { occluded_all_avx2(bvh, k, rays, out, stack) }
}
