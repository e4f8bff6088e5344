//! Closest-point queries on both BVHs: branch-and-bound nearest-neighbour search.
//!
//! The classic best-first-by-child depth-first search (Roussopoulos, Kelley and Vincent,
//! "Nearest neighbor queries", SIGMOD 1995, on R-trees; the same walk Embree's `rtcPointQuery`
//! makes): at each interior node the squared distances from the point to all children's boxes
//! are computed at once (SIMD, one pass per axis), children farther than the best squared
//! distance found so far (initially the squared radius) are dropped, the rest are visited
//! nearest first and the others pushed with their distance, and a popped subtree is skipped if
//! the best distance has meanwhile fallen below its box distance. Leaves compute the exact
//! point–triangle distance of each triangle ([`Nearest::test_triangle`]).
//!
//! Trade-off: a depth-first walk with nearest-child ordering needs only a fixed stack (no heap,
//! no allocation per query) and finds a close triangle early for points near the surface; a
//! global priority queue would visit a few nodes fewer for points far from everything, at the
//! price of a heap. Leaves read each triangle's exact vertices from the mesh (the ray layout's
//! edges `v0 - v1`, `v2 - v0` are rounded), so answers are brute force's bit for bit.

use crate::Bvh;
use crate::node::{ChildRef, MAX_DEPTH, Node};
use crate::simd::F4;
use crate::wide::{WideNode, quad, with_stack};
use raybench_accel::{CounterSink, Nearest, PointHit};
use raybench_geom::Tri4;
use raybench_geom::{Aabb, TriangleMesh, Vec3, box_distance_squared};

/// The query point splatted per axis, made once per query.
struct SplatPoint([F4; 3]);

impl SplatPoint {
    fn new(p: Vec3) -> SplatPoint {
        SplatPoint(p.to_array().map(F4::splat))
    }

    /// Squared distances to four boxes given per axis as `(min lanes, max lanes)`: per axis the
    /// gap `max(min - p, p - max, 0)`, squared and summed over x, y, z in that order. An empty
    /// box (`min = +inf`, `max = -inf`) is infinitely far.
    #[inline(always)]
    fn box_distances(&self, lo: [F4; 3], hi: [F4; 3]) -> F4 {
        let zero = F4::splat(0.0);
        let mut acc = zero;
        for axis in 0..3 {
            let below = lo[axis].sub(self.0[axis]);
            let above = self.0[axis].sub(hi[axis]);
            let gap = below.max_keep(above).max_keep(zero);
            acc = acc.add(gap.mul(gap));
        }
        acc
    }
}

// ---- binary BVH -------------------------------------------------------------------------

/// Squared distances from the point to both children of a binary node (lanes 0 and 1). The
/// node stores per axis `[min0, min1, max0, max1]`; swapping halves lines the maxima up.
#[inline(always)]
fn binary_child_distances(p: &SplatPoint, n: &Node) -> [f32; 2] {
    let lo = n.planes.map(|a| F4::load(&a));
    let hi = lo.map(F4::swap_halves);
    let d = p.box_distances(lo, hi).to_array();
    [d[0], d[1]]
}

/// The most recently pushed subtree whose squared distance is within `bound` (both walks push
/// the nearer subtrees last); the farther ones popped on the way are dropped for good, since
/// the bound only shrinks.
#[inline(always)]
pub(crate) fn pop_within(
    stack: &[(ChildRef, f32)],
    sp: &mut usize,
    bound: f32,
) -> Option<ChildRef> {
    while *sp > 0 {
        *sp -= 1;
        let (r, d2) = stack[*sp];
        if d2 <= bound {
            return Some(r);
        }
    }
    None
}

/// The closest-point walk of the binary [`Bvh`], counting into `c` (a no-op for `NoCount`).
pub(crate) fn closest_point_binary<C: CounterSink>(
    bvh: &Bvh,
    p: Vec3,
    max_radius: f32,
    c: &mut C,
) -> Option<PointHit> {
    let mut nearest = Nearest::within(p, max_radius)?;
    if bvh.triangles.is_empty() || box_distance_squared(p, &bvh.root_bounds) > nearest.bound_d2() {
        return None;
    }
    let splat = SplatPoint::new(p);
    // One pushed sibling per level at most, and the builder caps the depth at MAX_DEPTH.
    let mut stack = [(ChildRef::default(), 0f32); MAX_DEPTH];
    let mut sp = 0;
    let mut next = Some(bvh.root);
    loop {
        while let Some(r) = next.take() {
            if r.is_leaf() {
                c.leaf();
                binary_leaf(bvh, r, p, &mut nearest, c);
                break;
            }
            c.node();
            let d = binary_child_distances(&splat, &bvh.nodes[r.index as usize]);
            let child = bvh.nodes[r.index as usize].child;
            let (near, far) = if d[1] < d[0] { (1, 0) } else { (0, 1) };
            let bound = nearest.bound_d2();
            if d[near] <= bound {
                next = Some(child[near]);
                if d[far] <= bound {
                    stack[sp] = (child[far], d[far]);
                    sp += 1;
                }
            }
        }
        next = pop_within(&stack, &mut sp, nearest.bound_d2());
        if next.is_none() {
            return nearest.into_hit();
        }
    }
}

#[inline(always)]
fn binary_leaf<C: CounterSink>(bvh: &Bvh, r: ChildRef, p: Vec3, nearest: &mut Nearest, c: &mut C) {
    let range = r.index as usize..(r.index + r.count) as usize;
    for &prim in &bvh.prim_ids[range] {
        c.prim_tests(1);
        nearest.test_triangle(p, prim, &bvh.mesh.triangle(prim as usize));
    }
}

// ---- wide BVHs (4 and 8 children) -------------------------------------------------------

/// What the wide walk reads of a [`crate::wide::BvhWide`] (its fields are private to `wide`).
pub(crate) struct WideView<'a, const W: usize> {
    pub root: ChildRef,
    pub root_bounds: &'a Aabb,
    pub nodes: &'a [WideNode<W>],
    pub tri4s: &'a [Tri4],
    pub mesh: &'a TriangleMesh,
}

/// Squared distances from the point to all children of a wide node, four at a time (unused
/// slots hold empty boxes: infinitely far).
#[inline(always)]
fn wide_child_distances<const W: usize>(p: &SplatPoint, n: &WideNode<W>) -> [f32; W] {
    let mut d = [0.0; W];
    for q in 0..W / 4 {
        let lo = n.planes.map(|a| F4::load(quad(&a[0], q)));
        let hi = n.planes.map(|a| F4::load(quad(&a[1], q)));
        d[4 * q..4 * q + 4].copy_from_slice(&p.box_distances(lo, hi).to_array());
    }
    d
}

/// The children within `bound` (`child[i]` at squared distance `d[i]`), sorted nearest first
/// into `out` (insertion sort on at most sixteen entries, in registers). Returns how many there
/// are. Shared by the float and quantized wide trees.
#[inline(always)]
pub(crate) fn children_within(
    child: &[ChildRef],
    d: &[f32],
    bound: f32,
    out: &mut [(ChildRef, f32)],
) -> usize {
    let mut len = 0;
    for (&c, &di) in child.iter().zip(d) {
        if di > bound {
            continue; // also every unused slot of a float node: its distance is +inf
        }
        let mut at = len;
        while at > 0 && out[at - 1].1 > di {
            out[at] = out[at - 1];
            at -= 1;
        }
        out[at] = (c, di);
        len += 1;
    }
    len
}

/// Descends into the nearest of `kids` (sorted nearest first, at least one) and pushes the
/// rest, farthest first, so the nearest pushed one is popped first.
#[inline(always)]
pub(crate) fn descend(
    kids: &[(ChildRef, f32)],
    stack: &mut [(ChildRef, f32)],
    sp: &mut usize,
) -> ChildRef {
    for &entry in kids[1..].iter().rev() {
        stack[*sp] = entry;
        *sp += 1;
    }
    kids[0].0
}

/// The closest-point walk of a wide BVH, counting into `c` (a no-op for `NoCount`).
pub(crate) fn closest_point_wide<const W: usize, C: CounterSink>(
    bvh: &WideView<'_, W>,
    p: Vec3,
    max_radius: f32,
    c: &mut C,
) -> Option<PointHit> {
    let mut nearest = Nearest::within(p, max_radius)?;
    if bvh.tri4s.is_empty() || box_distance_squared(p, bvh.root_bounds) > nearest.bound_d2() {
        return None;
    }
    let splat = SplatPoint::new(p);
    // The ray walk's per-thread stack (as deep as any walk needs), not one cleared per query.
    with_stack(|stack| {
        let mut sp = 0;
        let mut next = Some(bvh.root);
        let mut kids = [(ChildRef::default(), 0f32); W];
        loop {
            while let Some(r) = next.take() {
                if r.is_leaf() {
                    c.leaf();
                    wide_leaf(bvh, r, p, &mut nearest, c);
                    break;
                }
                c.node();
                let n = &bvh.nodes[r.index as usize];
                let d = wide_child_distances(&splat, n);
                let len = children_within(&n.child, &d, nearest.bound_d2(), &mut kids);
                if len == 0 {
                    break;
                }
                next = Some(descend(&kids[..len], stack.as_mut_slice(), &mut sp));
            }
            next = pop_within(stack.as_slice(), &mut sp, nearest.bound_d2());
            if next.is_none() {
                return nearest.into_hit();
            }
        }
    })
}

/// The `count` used lanes of the leaf's `Tri4`s, one exact distance each.
#[inline(always)]
fn wide_leaf<const W: usize, C: CounterSink>(
    bvh: &WideView<'_, W>,
    r: ChildRef,
    p: Vec3,
    nearest: &mut Nearest,
    c: &mut C,
) {
    let first = 4 * r.index as usize;
    for slot in first..first + r.count as usize {
        c.prim_tests(1);
        let prim = bvh.tri4s[slot / 4].ids[slot % 4];
        nearest.test_triangle(p, prim, &bvh.mesh.triangle(prim as usize));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simd_box_distances_match_geom() {
        let boxes = [
            Aabb::new(Vec3::ZERO, Vec3::ONE),
            Aabb::new(Vec3::new(-3.0, 2.0, 0.5), Vec3::new(-1.0, 4.0, 0.5)),
        ];
        let node = Node::new([&boxes[0], &boxes[1]], [ChildRef::default(); 2]);
        for p in [
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(2.0, -1.0, 3.0),
            Vec3::new(-2.0, 3.0, 0.5),
            Vec3::new(-10.0, 10.0, -10.0),
        ] {
            let d = binary_child_distances(&SplatPoint::new(p), &node);
            assert_eq!(d, boxes.map(|b| box_distance_squared(p, &b)), "p = {p}");
        }
    }

    #[test]
    fn children_are_sorted_and_pruned() {
        let mut n = WideNode::<8> {
            planes: [[[0.0; 8]; 2]; 3],
            child: [ChildRef::default(); 8],
        };
        for (i, c) in n.child.iter_mut().enumerate() {
            c.index = i as u32;
        }
        let d = [5.0, 1.0, f32::INFINITY, 3.0, 0.0, 9.0, 3.0, 2.0];
        let mut out = [(ChildRef::default(), 0f32); 8];
        let len = children_within(&n.child, &d, 5.0, &mut out);
        let order: Vec<u32> = out[..len].iter().map(|(c, _)| c.index).collect();
        assert_eq!(
            order,
            [4, 1, 7, 3, 6, 0],
            "ascending, stable, 9 and inf pruned"
        );
    }
}
