//! Closest-point queries on the quantized tree: the float tree's branch-and-bound walk
//! (`crate::point`) over the decoded boxes, in scalar code. A decoded box holds its float box,
//! so its distance is never larger and no subtree that may hold the nearest triangle is
//! dropped; the leaves compute exact distances from the mesh's vertices, so the answer is
//! brute force's.

use super::BvhQuantized;
use super::node::{Plane, QWIDTH};
use crate::node::ChildRef;
use crate::point::{children_within, descend, pop_within};
use crate::wide::with_stack;
use raybench_accel::{CounterSink, Nearest, PointHit};
use raybench_geom::{Vec3, box_distance_squared};

impl<P: Plane> BvhQuantized<P> {
    pub(super) fn closest_point_walk<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<PointHit> {
        let mut nearest = Nearest::within(p, max_radius)?;
        if self.tri4s.is_empty() || box_distance_squared(p, &self.root_bounds) > nearest.bound_d2()
        {
            return None;
        }
        // The ray walk's per-thread stack (as deep as any walk needs), not one cleared per query.
        with_stack(|stack| {
            let mut sp = 0;
            let mut next = Some(self.root);
            loop {
                while let Some(r) = next.take() {
                    if r.is_leaf() {
                        c.leaf();
                        let first = 4 * r.index as usize;
                        for slot in first..first + r.count as usize {
                            c.prim_tests(1);
                            let prim = self.tri4s[slot / 4].ids[slot % 4];
                            nearest.test_triangle(p, prim, &self.mesh.triangle(prim as usize));
                        }
                        break;
                    }
                    c.node();
                    let n = &self.nodes[r.index as usize];
                    let k = n.children();
                    let mut d = [0f32; QWIDTH];
                    for (i, di) in d[..k].iter_mut().enumerate() {
                        *di = box_distance_squared(p, &n.child_bounds(i));
                    }
                    let mut kids = [(ChildRef::default(), 0f32); QWIDTH];
                    let len =
                        children_within(&n.child[..k], &d[..k], nearest.bound_d2(), &mut kids);
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
}
