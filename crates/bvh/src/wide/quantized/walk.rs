//! The quantized tree's traversal loop: the float tree's ordered walk with each node decoded
//! before its test.

use super::BvhQuantized;
use super::kernels::QuantKernel;
use super::node::{Plane, QWIDTH};
use crate::node::ChildRef;
use crate::wide::kernels::SseNodes;
use crate::wide::walk::{Stack, first_in_slot_order, nearest_first, prefetch_child, with_stack};
use raybench_accel::{CounterSink, Hit};
use raybench_geom::{Ray, TriHit};

impl<P: Plane> BvhQuantized<P> {
    /// The one traversal loop — closest or any hit, counted or not — for a given kernel, with
    /// the float walk's child ordering, so its answers are the float tree's: a quantized box
    /// only ever holds its float box, so the walk may enter more children, and it still
    /// visits every subtree the float walk visits before its closest hit is final.
    #[inline(always)]
    pub(super) fn walk_with<const ANY_HIT: bool, C: CounterSink, K: QuantKernel<P>>(
        &self,
        kernel: K,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        if self.tri4s.is_empty() {
            return None;
        }
        let t_min = ray.t_min();
        let mut best_t = ray.t_max();
        let wide = kernel.ray(ray);
        let mut best: Option<(usize, TriHit)> = None;
        let mut sp = 0;
        let mut r = self.root;
        // The root's children are tested on their float boxes: rounded out, they would let in
        // every ray that starts on the scene's outer box and leaves it (shadow rays from a
        // roof toward the sky), and send it down to the leaf it starts on.
        if !r.is_leaf() {
            c.node();
            let n = &self.root_node;
            let (mask, entry) = kernel.test(&wide, n, t_min, best_t);
            if mask == 0 {
                return None;
            }
            r = self.enter::<ANY_HIT>(&n.child, mask, &entry, stack, &mut sp);
        }
        'walk: loop {
            if r.is_leaf() {
                c.leaf();
                c.prim_tests(r.count as u64);
                let first = r.index as usize;
                let leaf = &self.tri4s[first..first + (r.count as usize).div_ceil(4)];
                if kernel.leaf::<ANY_HIT>(&wide, leaf, first, &mut best_t, &mut best) {
                    break 'walk;
                }
            } else {
                c.node();
                let n = &self.nodes[r.index as usize];
                let (mask, entry) = kernel.test_quantized(&wide, n, t_min, best_t);
                if mask != 0 {
                    r = self.enter::<ANY_HIT>(&n.child, mask, &entry, stack, &mut sp);
                    continue 'walk;
                }
            }
            // Pop the nearest pushed subtree that may still hold a closer hit.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let (next, t_entry) = stack[sp];
                if ANY_HIT || t_entry <= best_t {
                    r = next;
                    continue 'walk;
                }
            }
        }
        best.map(|(lane, h)| Hit::from_tri_hit(self.tri4s[lane / 4].ids[lane % 4], h))
    }

    /// Descends into the children in `mask` of a node tested: starts fetching them, pushes all
    /// but the one to visit next (the nearest for closest hits, the first slot for any hit)
    /// and returns that one.
    #[inline(always)]
    fn enter<const ANY_HIT: bool>(
        &self,
        child: &[ChildRef; QWIDTH],
        mask: u32,
        entry: &[f32; QWIDTH],
        stack: &mut Stack,
        sp: &mut usize,
    ) -> ChildRef {
        if ANY_HIT {
            first_in_slot_order(child, mask, stack, sp, |r| self.prefetch(r))
        } else {
            self.prefetch_children(child, mask);
            nearest_first(child, mask, entry, stack, sp)
        }
    }

    /// Starts fetching every child in `mask` (see [`prefetch_child`]: a node's two or three
    /// lines).
    #[inline(always)]
    fn prefetch_children(&self, child: &[ChildRef; QWIDTH], mut mask: u32) {
        while mask != 0 {
            self.prefetch(child[mask.trailing_zeros() as usize]);
            mask &= mask - 1;
        }
    }

    #[inline(always)]
    fn prefetch(&self, r: ChildRef) {
        prefetch_child(&self.nodes, &self.tri4s, r);
    }

    /// [`BvhQuantized::walk_with`] with the kernel chosen at build time.
    #[inline(always)]
    pub(super) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
            return unsafe {
                super::kernels::walk_ray_avx2::<P, ANY_HIT, C>(self, k, ray, stack, c)
            };
        }
        self.walk_with::<ANY_HIT, C, SseNodes>(SseNodes, ray, stack, c)
    }

    pub(super) fn trace_single<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        with_stack(|stack| self.trace::<ANY_HIT, C>(ray, stack, c))
    }
}
