//! The binary tree in the form reinsertion edits: one record per node (interior or leaf) with
//! its box, its parent and the height of its subtree, converted from a [`Flat`] and back.
//!
//! A leaf keeps the range of the old `refs` it was built with: moves never open a leaf, so the
//! range stays valid until [`Tree::into_flat`] copies every leaf's records into their new
//! depth-first place. Nothing here assumes a mesh index appears once in `refs`.

use crate::build::{Box3, Flat, PrimRef};
use crate::node::{ChildRef, Node};
use raybench_geom::{Aabb, Vec3};

/// No node (the root's parent).
pub(super) const NONE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Interior([u32; 2]),
    /// `count` records from `first` in the original `refs`.
    Leaf {
        first: u32,
        count: u32,
    },
}

pub(super) struct Tree {
    pub bounds: Vec<Box3>,
    pub kind: Vec<Kind>,
    pub parent: Vec<u32>,
    /// Levels below the node: 0 for a leaf.
    pub height: Vec<u32>,
    pub root: u32,
}

fn to_box(b: &Aabb) -> Box3 {
    Box3 {
        lo: b.min.into(),
        hi: b.max.into(),
    }
}

fn to_aabb(b: &Box3) -> Aabb {
    Aabb::new(Vec3::from(b.lo), Vec3::from(b.hi))
}

impl Tree {
    /// The tree of `flat`, whose root must be an interior node. Node 0 is the root; boxes are
    /// the ones the builder stored.
    pub(super) fn from_flat(flat: &Flat) -> Tree {
        let total = 2 * flat.nodes.len() + 1;
        let mut t = Tree {
            bounds: Vec::with_capacity(total),
            kind: Vec::with_capacity(total),
            parent: Vec::with_capacity(total),
            height: Vec::with_capacity(total),
            root: 0,
        };
        t.push(to_box(&flat.root_bounds), flat.root, NONE);
        // (record of the interior node, its index in `flat.nodes`)
        let mut stack = vec![(0u32, flat.root.index)];
        while let Some((at, flat_index)) = stack.pop() {
            let node = &flat.nodes[flat_index as usize];
            let mut kids = [0u32; 2];
            for (i, kid) in kids.iter_mut().enumerate() {
                let c = node.child[i];
                *kid = t.push(to_box(&node.child_bounds(i)), c, at);
                if !c.is_leaf() {
                    stack.push((*kid, c.index));
                }
            }
            t.kind[at as usize] = Kind::Interior(kids);
        }
        t.fix_heights();
        t
    }

    fn push(&mut self, b: Box3, c: ChildRef, parent: u32) -> u32 {
        let id = self.bounds.len() as u32;
        self.bounds.push(b);
        // An interior node's children are filled in when it is popped.
        self.kind.push(if c.is_leaf() {
            Kind::Leaf {
                first: c.index,
                count: c.count,
            }
        } else {
            Kind::Interior([NONE; 2])
        });
        self.parent.push(parent);
        self.height.push(0);
        id
    }

    /// Heights bottom-up: every child has a larger id than its parent after `from_flat`.
    fn fix_heights(&mut self) {
        for n in (0..self.kind.len()).rev() {
            if let Kind::Interior([a, b]) = self.kind[n] {
                self.height[n] = 1 + self.height[a as usize].max(self.height[b as usize]);
            }
        }
    }

    pub(super) fn len(&self) -> usize {
        self.kind.len()
    }

    #[inline(always)]
    pub(super) fn area(&self, n: u32) -> f64 {
        self.bounds[n as usize].half_area()
    }

    /// The other child of `n`'s parent (`n` is not the root).
    #[inline(always)]
    pub(super) fn sibling(&self, n: u32) -> u32 {
        match self.kind[self.parent[n as usize] as usize] {
            Kind::Interior([a, b]) => {
                if a == n {
                    b
                } else {
                    a
                }
            }
            Kind::Leaf { .. } => unreachable!("a parent is interior"),
        }
    }

    fn replace_child(&mut self, parent: u32, old: u32, new: u32) {
        if parent == NONE {
            self.root = new;
        } else if let Kind::Interior(kids) = &mut self.kind[parent as usize] {
            let slot = usize::from(kids[1] == old);
            debug_assert_eq!(kids[slot], old);
            kids[slot] = new;
        }
        self.parent[new as usize] = parent;
    }

    /// Moves `x` (not the root) next to `c`: `x`'s parent leaves its place to `x`'s sibling and
    /// becomes the parent of `c` and `x` where `c` was. The caller has checked that `c` is
    /// outside `x`'s subtree, not an ancestor of `x`, and not `x`'s sibling.
    pub(super) fn move_next_to(&mut self, x: u32, c: u32) {
        let p = self.parent[x as usize];
        let sibling = self.sibling(x);
        let grand = self.parent[p as usize];
        self.replace_child(grand, p, sibling);
        let at = self.parent[c as usize];
        self.replace_child(at, c, p);
        self.kind[p as usize] = Kind::Interior([c, x]);
        self.parent[c as usize] = p;
        self.parent[x as usize] = p;
        if grand != NONE {
            self.refit_up(grand);
        }
        self.refit_up(p);
    }

    /// Recomputes boxes and heights from `n` to the root.
    fn refit_up(&mut self, mut n: u32) {
        while n != NONE {
            if let Kind::Interior([a, b]) = self.kind[n as usize] {
                let (a, b) = (a as usize, b as usize);
                self.bounds[n as usize] = self.bounds[a].union(&self.bounds[b]);
                self.height[n as usize] = 1 + self.height[a].max(self.height[b]);
            }
            n = self.parent[n as usize];
        }
    }

    /// The builder's SAH cost: every interior node costs `traversal`, every leaf `leaf_cost`
    /// of its triangle count, each weighted by its area relative to the root's (0 for a root
    /// without area).
    pub(super) fn sah(&self, traversal: f64, leaf_cost: impl Fn(u32) -> f64) -> f64 {
        let root_area = self.area(self.root);
        if root_area <= 0.0 {
            return 0.0;
        }
        let mut sum = 0.0;
        let mut stack = vec![self.root];
        while let Some(n) = stack.pop() {
            let cost = match self.kind[n as usize] {
                Kind::Interior(kids) => {
                    stack.extend(kids);
                    traversal
                }
                Kind::Leaf { count, .. } => leaf_cost(count),
            };
            sum += cost * self.area(n);
        }
        sum / root_area
    }

    /// The tree in the builder's flat form: nodes depth-first (a node's first child follows
    /// it), leaves' records copied from `refs` in the order the walk meets them.
    pub(super) fn into_flat(self, refs: &[PrimRef]) -> Flat {
        let interior = self
            .kind
            .iter()
            .filter(|k| matches!(k, Kind::Interior(_)))
            .count();
        let mut nodes: Vec<Node> = Vec::with_capacity(interior);
        let mut out: Vec<PrimRef> = Vec::with_capacity(refs.len());
        // (record, index of the parent in `nodes`, slot); the root has no parent slot.
        let mut stack = vec![(self.root, u32::MAX, 0usize)];
        let mut root = ChildRef::default();
        while let Some((n, parent, slot)) = stack.pop() {
            let r = match self.kind[n as usize] {
                Kind::Leaf { first, count } => {
                    let at = out.len() as u32;
                    out.extend_from_slice(&refs[first as usize..(first + count) as usize]);
                    ChildRef { index: at, count }
                }
                Kind::Interior([a, b]) => {
                    let at = nodes.len() as u32;
                    let (ba, bb) = (
                        to_aabb(&self.bounds[a as usize]),
                        to_aabb(&self.bounds[b as usize]),
                    );
                    nodes.push(Node::new([&ba, &bb], [ChildRef::default(); 2]));
                    // The second child is popped after the whole first subtree.
                    stack.push((b, at, 1));
                    stack.push((a, at, 0));
                    ChildRef {
                        index: at,
                        count: 0,
                    }
                }
            };
            if parent == u32::MAX {
                root = r;
            } else {
                nodes[parent as usize].child[slot] = r;
            }
        }
        Flat {
            nodes,
            refs: out,
            root,
            root_bounds: to_aabb(&self.bounds[self.root as usize]),
            // The caller carries over what the builder reported.
            spatial: None,
        }
    }
}
