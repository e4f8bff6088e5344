//! The node kernels: one wide-node slab test per kernel, and the leaf test it pairs with.

use super::node::{WideNode, quad};
use super::walk::{Stack, nearest_first};
use crate::node::ChildRef;
use crate::simd::F4;
use raybench_geom::{Ray, Tri4, TriHit};

/// One wide-node slab test: entry distances of all `W` children and the mask of those entered
/// within `[t_min, t_max]`. Implementations compute the scalar slab test's arithmetic lane for
/// lane, so every kernel answers alike; a NaN (`0 * inf`, a ray in a box's face plane) is
/// ignored because the `max`/`min` keep the accumulator (docs/validation.md, B1).
pub(crate) trait NodeKernel<const W: usize>: Copy {
    type Ray;
    fn ray(self, ray: &Ray) -> Self::Ray;
    fn test(self, ray: &Self::Ray, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]);
    /// The `Tri4`s of one leaf (the first is `Tri4` `first` of the tree) against the ray below
    /// `*best_t`, exactly as [`intersect_tri4s`] does it; true when an any-hit query may stop.
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &Self::Ray,
        tri4s: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool;

    /// Of the children in `mask`, returns the nearest and pushes the others to pop nearest
    /// first ([`nearest_first`]).
    #[inline(always)]
    fn order(
        self,
        child: &[ChildRef; W],
        mask: u32,
        entry: &[f32; W],
        stack: &mut Stack,
        sp: &mut usize,
    ) -> ChildRef {
        nearest_first(child, mask, entry, stack, sp)
    }
}

/// The baseline kernel: one 4-lane pass per axis and four children (SSE on x86-64, portable
/// elsewhere).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SseNodes;

/// The ray as [`SseNodes`] needs it: the ray itself (for the leaves' [`Tri4`] tests), its
/// origin and inverse direction splatted, and per axis which stored side (min or max) holds
/// the near planes.
pub(crate) struct WideRay {
    ray: Ray,
    origin: [F4; 3],
    inv: [F4; 3],
    near: [bool; 3],
}

impl<const W: usize> NodeKernel<W> for SseNodes {
    type Ray = WideRay;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> WideRay {
        let inv = ray.inv_dir().to_array();
        WideRay {
            inv: inv.map(F4::splat),
            // -0 counts as negative: its inverse is -inf (docs/validation.md, B3).
            near: inv.map(|x| x.is_sign_negative()),
            origin: ray.origin().to_array().map(F4::splat),
            ray: *ray,
        }
    }

    #[inline(always)]
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &WideRay,
        tri4s: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool {
        intersect_tri4s::<ANY_HIT>(tri4s, first, &ray.ray, best_t, best)
    }

    #[inline(always)]
    fn test(self, r: &WideRay, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        slab_quads(&r.origin, &r.inv, r.near, n, t_min, t_max)
    }
}

/// The slab test of a node's children four lanes a pass, for a ray splatted as `origin` and
/// `inv` whose near planes lie on the sides `near` (the SSE kernel, and the AVX2 kernel's
/// 4-wide nodes).
#[inline(always)]
pub(crate) fn slab_quads<const W: usize>(
    origin: &[F4; 3],
    inv: &[F4; 3],
    near: [bool; 3],
    n: &WideNode<W>,
    t_min: f32,
    t_max: f32,
) -> (u32, [f32; W]) {
    let mut mask = 0;
    let mut entry = [0.0; W];
    for q in 0..W / 4 {
        let mut t0 = F4::splat(t_min);
        let mut t1 = F4::splat(t_max);
        for a in 0..3 {
            let near_planes = F4::load(quad(&n.planes[a][near[a] as usize], q));
            let far_planes = F4::load(quad(&n.planes[a][!near[a] as usize], q));
            t0 = near_planes.sub(origin[a]).mul(inv[a]).max_keep(t0);
            t1 = far_planes.sub(origin[a]).mul(inv[a]).min_keep(t1);
        }
        mask |= t0.le_mask(t1) << (4 * q);
        entry[4 * q..4 * q + 4].copy_from_slice(&t0.to_array());
    }
    (mask, entry)
}

/// Tests a leaf's `Tri4`s (the first is `Tri4` `first` of the tree) one after the other below
/// `*best_t`, keeping the closest hit (as a lane index `4 * tri4 + lane`); true when an
/// any-hit query may stop. A later `Tri4`'s lane replaces the best hit so far when its
/// window test `t <= best_t` passes, so on an exact tie the later `Tri4` wins.
#[inline(always)]
pub(crate) fn intersect_tri4s<const ANY_HIT: bool>(
    tri4s: &[Tri4],
    first: usize,
    ray: &Ray,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
) -> bool {
    for (k, tri4) in tri4s.iter().enumerate() {
        if let Some((lane, h)) = tri4.intersect(ray, *best_t) {
            *best_t = h.t;
            *best = Some((4 * (first + k) + lane, h));
            if ANY_HIT {
                return true;
            }
        }
    }
    false
}
