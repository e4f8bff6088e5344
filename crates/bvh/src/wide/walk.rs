//! The traversal loop, its stack and the child ordering.

use super::kernels::{NodeKernel, SseNodes};
use super::node::WideNode;
use super::{BvhWide, MAX_WIDTH};
use crate::node::{ChildRef, MAX_DEPTH};
use crate::simd::prefetch;
use raybench_accel::{CounterSink, Hit};
use raybench_geom::{Ray, Tri4, TriHit};

/// Stack entries a walk can need: a node pushes at most `MAX_WIDTH - 1`, one per level, and
/// the binary builder caps the depth at [`MAX_DEPTH`] (collapsing only shortens it).
pub(crate) const STACK: usize = (MAX_WIDTH - 1) * MAX_DEPTH + 1;

type Entry = (ChildRef, f32);

/// A traversal stack: subtrees still to visit with their entry distances.
pub(crate) type Stack = [Entry; STACK];

pub(crate) fn new_stack() -> Box<Stack> {
    Box::new([(ChildRef::default(), 0.0); STACK])
}

raybench_accel::per_thread_stack!(
    /// Runs `f` with this thread's traversal stack (a fresh one inside another walk).
    pub(crate) fn with_stack -> Stack = new_stack()
);

/// Any hit will do, so no sorting (as Embree's occlusion traversal): returns the child in the
/// lowest slot of `mask` and pushes the others to pop in slot order, calling `fetch` on each
/// (the returned child first) in the same pass over the mask, so a node pays for one loop's exit,
/// not two. Their entry distances are not kept: an any-hit walk ends at its first hit, so `t_max`
/// never shrinks and no pushed subtree is ever skipped (the pop does not look at them either).
#[inline(always)]
pub(super) fn first_in_slot_order<const W: usize>(
    child: &[ChildRef; W],
    mask: u32,
    stack: &mut Stack,
    sp: &mut usize,
    fetch: impl Fn(ChildRef),
) -> ChildRef {
    let first = child[mask.trailing_zeros() as usize];
    fetch(first);
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        let i = 31 - rest.leading_zeros() as usize;
        rest &= !(1 << i);
        fetch(child[i]);
        stack[*sp] = (child[i], 0.0);
        *sp += 1;
    }
    first
}

/// Starts fetching child `r` of a wide tree with `nodes` and `tri4s`: all of a node's lines,
/// or a leaf's first `Tri4` (three lines). The any-hit walks of the float and quantized trees
/// fetch with it.
#[inline(always)]
pub(super) fn prefetch_child<N>(nodes: &[N], tri4s: &[Tri4], r: ChildRef) {
    if r.is_leaf() {
        prefetch(tri4s.as_ptr().wrapping_add(r.index as usize));
    } else {
        prefetch(nodes.as_ptr().wrapping_add(r.index as usize));
    }
}

/// Of the children `child` in `mask` (entry distances `entry`), returns the nearest and pushes
/// the others so that they pop nearest first (equal distances: lower slot first). One, two and
/// three children — most nodes — take a short path; more are inserted into the stack in place.
#[inline(always)]
pub(super) fn nearest_first<const W: usize>(
    child: &[ChildRef; W],
    mut mask: u32,
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    let a = mask.trailing_zeros() as usize;
    mask &= mask - 1;
    if mask == 0 {
        return child[a];
    }
    let b = mask.trailing_zeros() as usize;
    mask &= mask - 1;
    if mask == 0 {
        let (near, far) = if entry[b] < entry[a] { (b, a) } else { (a, b) };
        stack[*sp] = (child[far], entry[far]);
        *sp += 1;
        return child[near];
    }
    if mask & (mask - 1) == 0 {
        // Three: a branch-free network of three compare-exchanges on keys that hold the
        // distance's bits above the slot (non-negative floats order as integers; -0 is made +0),
        // so equal distances go lower slot first, as in the insertion below (measured: see
        // docs/experiments.md, "three entered children ordered by three branch-free
        // compare-exchanges").
        let key = |i: usize| u64::from((entry[i] + 0.0).to_bits()) << 32 | i as u64;
        let c = mask.trailing_zeros() as usize;
        let (ka, kb, kc) = (key(a), key(b), key(c));
        let (x, y) = (ka.min(kb), ka.max(kb));
        let (y, z) = (y.min(kc), y.max(kc));
        let (x, y) = (x.min(y), x.max(y));
        for k in [z, y] {
            let i = k as u32 as usize;
            stack[*sp] = (child[i], entry[i]);
            *sp += 1;
        }
        return child[x as u32 as usize];
    }
    // Four or more: keep stack[base..] in decreasing distance, the nearest on top; a later
    // (higher) slot goes below earlier slots at the same distance. (Written out here rather than
    // shared with the tests' copy: as a call, even inlined, the walk compiled 7 % slower.)
    let base = *sp;
    let mut insert = |i: usize| {
        let e = (child[i], entry[i]);
        let mut j = *sp;
        while j > base && stack[j - 1].1 <= e.1 {
            stack[j] = stack[j - 1];
            j -= 1;
        }
        stack[j] = e;
        *sp += 1;
    };
    insert(a);
    insert(b);
    while mask != 0 {
        insert(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
    *sp -= 1;
    stack[*sp].0
}

impl<const W: usize> BvhWide<W> {
    /// The one traversal loop — closest or any hit, counted or not — for a given node
    /// kernel. `stack` is scratch space, so batch callers reuse one allocation for all their
    /// rays. There is no separate test of the root box: the root node's test covers it.
    #[inline(always)]
    pub(crate) fn walk_with<const ANY_HIT: bool, C: CounterSink, K: NodeKernel<W>>(
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
                let (mask, entry) = kernel.test(&wide, n, t_min, best_t);
                if mask != 0 {
                    r = if ANY_HIT {
                        first_in_slot_order(&n.child, mask, stack, &mut sp, |c| {
                            prefetch_child(&self.nodes, &self.tri4s, c)
                        })
                    } else {
                        self.prefetch_children(n, mask);
                        kernel.order(&n.child, mask, &entry, stack, &mut sp)
                    };
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

    /// Starts fetching every child in `mask`, for the closest-hit walk: each child's address is
    /// chosen without a branch (node or leaf), and a leaf gets as many lines as a node (at 16
    /// wide eight, so both `Tri4`s of a two-`Tri4` leaf), which made 16-wide random rays 7 %
    /// faster and no walk slower (measured: see docs/experiments.md, "closest-hit walks
    /// prefetching by an address select"). The any-hit walk keeps [`prefetch_child`], for
    /// which the same change was 2 % slower.
    #[inline(always)]
    fn prefetch_children(&self, n: &WideNode<W>, mut mask: u32) {
        let lines = size_of::<WideNode<W>>().max(size_of::<Tri4>()) / 64;
        while mask != 0 {
            let r = n.child[mask.trailing_zeros() as usize];
            mask &= mask - 1;
            let leaf = self
                .tri4s
                .as_ptr()
                .wrapping_add(r.index as usize)
                .cast::<[u8; 64]>();
            let node = self
                .nodes
                .as_ptr()
                .wrapping_add(r.index as usize)
                .cast::<[u8; 64]>();
            let at = std::hint::select_unpredictable(r.is_leaf(), leaf, node);
            for k in 0..lines {
                prefetch(at.wrapping_add(k));
            }
        }
    }

    /// [`BvhWide::walk_with`] with the kernel chosen at build time.
    #[inline(always)]
    pub(super) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            return super::avx2::walk_ray::<W, ANY_HIT, C>(self, k, ray, stack, c);
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

/// The insertion alone, for every child in `mask`: the order [`nearest_first`] must give, for
/// the tests of its short paths and of the AVX2 network.
#[cfg(test)]
pub(super) fn inserted<const W: usize>(
    child: &[ChildRef; W],
    mut mask: u32,
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    let base = *sp;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let e = (child[i], entry[i]);
        let mut j = *sp;
        while j > base && stack[j - 1].1 <= e.1 {
            stack[j] = stack[j - 1];
            j -= 1;
        }
        stack[j] = e;
        *sp += 1;
    }
    *sp -= 1;
    stack[*sp].0
}

/// Checks `order` against [`inserted`] on the masks of `W` children in `masks`, with distances
/// drawn from a few values (many exactly equal, -0 and +0 among them, the others far more than 16
/// ulps apart): the same child first, and the same children with the same distances pushed in
/// the same order. Returns the cases checked.
#[cfg(test)]
pub(super) fn check_against_insertion<const W: usize>(
    masks: impl Iterator<Item = u32>,
    order: impl Fn(&[ChildRef; W], u32, &[f32; W], &mut Stack, &mut usize) -> ChildRef,
) -> usize {
    let values = [0.0f32, 0.5, -0.0, 1.0, 1.0e3, 3.25];
    let child: [ChildRef; W] = std::array::from_fn(|i| ChildRef {
        index: 100 + i as u32,
        count: 0,
    });
    let mut checked = 0;
    let (mut a, mut b) = (new_stack(), new_stack());
    for mask in masks {
        for seed in 0..25usize {
            let entry: [f32; W] =
                std::array::from_fn(|i| values[(i * 7 + seed * 3 + i * seed) % values.len()]);
            let (mut sa, mut sb) = (0, 0);
            let first_a = inserted(&child, mask, &entry, &mut a, &mut sa);
            let first_b = order(&child, mask, &entry, &mut b, &mut sb);
            assert_eq!(first_a, first_b, "mask {mask:016b}, distances {entry:?}");
            assert_eq!(sa, sb, "mask {mask:016b}, distances {entry:?}");
            assert_eq!(a[..sa], b[..sb], "mask {mask:016b}, distances {entry:?}");
            checked += 1;
        }
    }
    checked
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk started inside another on the same thread gets a stack of its own, and the outer
    /// walk's entries are untouched.
    #[test]
    fn a_nested_walk_gets_its_own_stack() {
        let marker = (ChildRef { index: 7, count: 3 }, 2.5);
        let (outer, inner) = with_stack(|outer| {
            outer[0] = marker;
            let inner = with_stack(|inner| {
                inner[0] = (ChildRef::default(), -1.0);
                inner.as_ptr()
            });
            (outer[0], inner != outer.as_ptr())
        });
        assert_eq!(outer, marker);
        assert!(inner, "the nested walk had the outer walk's stack");
        // The thread's stack is free again afterwards.
        assert_eq!(with_stack(|s| s[0]), marker);
    }

    /// The short paths of [`nearest_first`] (one to three children) order as the insertion.
    #[test]
    fn the_short_paths_order_as_the_insertion() {
        let masks = (1u32..256).filter(|m| (1..=3).contains(&m.count_ones()));
        let checked = check_against_insertion::<8>(masks, nearest_first);
        assert_eq!(checked, (8 + 28 + 56) * 25);
    }

    /// The any-hit walk fetches every entered child exactly once, and no other, the child it
    /// walks next first: every mask of 8 children and every 5th of 16.
    #[test]
    fn every_entered_child_is_fetched_once() {
        fn check<const W: usize>(masks: impl Iterator<Item = u32>) {
            let child: [ChildRef; W] = std::array::from_fn(|i| ChildRef {
                index: i as u32,
                count: 0,
            });
            let mut stack = new_stack();
            for mask in masks {
                let fetched = std::cell::Cell::new(0u32);
                let fetch = |c: ChildRef| {
                    let bit = 1 << c.index;
                    assert_eq!(
                        fetched.get() & bit,
                        0,
                        "mask {mask:b}: slot {} twice",
                        c.index
                    );
                    if fetched.get() == 0 {
                        assert_eq!(bit, mask & mask.wrapping_neg(), "mask {mask:b}: first");
                    }
                    fetched.set(fetched.get() | bit);
                };
                let mut sp = 0;
                let first = first_in_slot_order(&child, mask, &mut stack, &mut sp, fetch);
                assert_eq!(fetched.get(), mask, "mask {mask:b}");
                assert_eq!(first.index, mask.trailing_zeros());
                // The rest pop in slot order.
                let popped: Vec<u32> = stack[..sp].iter().rev().map(|e| e.0.index).collect();
                let rest: Vec<u32> = (0..W as u32)
                    .filter(|&i| mask >> i & 1 == 1)
                    .skip(1)
                    .collect();
                assert_eq!(popped, rest, "mask {mask:b}");
            }
        }
        check::<8>(1u32..256);
        check::<16>((1u32..1 << 16).step_by(5));
    }
}
