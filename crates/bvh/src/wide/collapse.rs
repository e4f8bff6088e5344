//! The binary tree collapsed into wide nodes.

use super::node::WideNode;
use crate::build::{Box3, PrimRef};
use crate::node::{ChildRef, Node};
use raybench_geom::Aabb;

/// What every collapse task reads: the binary tree, the number of triangles under each of its
/// interior nodes (a subtree's triangles are one range of the builder's records), and whether
/// empty slots are filled.
pub(super) struct Binary<'a> {
    nodes: &'a [Node],
    sizes: Vec<u32>,
    fill_slots: bool,
}

/// Leaves of more triangles than this (one `Tri4`) may be split to fill a node's empty slots.
const SPLIT_LEAVES_ABOVE: u32 = 4;

/// Subtrees of at least this many triangles collapse their children's subtrees on rayon
/// (measured: see docs/experiments.md, "collapse on rayon").
const PARALLEL_COLLAPSE: usize = 4096;

impl Binary<'_> {
    pub(super) fn new(nodes: &[Node], fill_slots: bool) -> Binary<'_> {
        let mut sizes = vec![0u32; nodes.len()];
        // Children follow their parent in the depth-first array: fill in sizes bottom-up.
        for i in (0..nodes.len()).rev() {
            sizes[i] = nodes[i]
                .child
                .iter()
                .map(|c| {
                    if c.is_leaf() {
                        c.count
                    } else {
                        sizes[c.index as usize]
                    }
                })
                .sum();
        }
        Binary {
            nodes,
            sizes,
            fill_slots,
        }
    }

    fn size(&self, r: ChildRef) -> usize {
        if r.is_leaf() {
            r.count as usize
        } else {
            self.sizes[r.index as usize] as usize
        }
    }

    /// The children of the wide node made from binary node `r`, whose triangles are `refs`
    /// (the first of them record `start`): starting from its two children, the interior child
    /// with the largest area is opened (first on ties: deterministic) until there are `W` or
    /// only leaves remain; slots still empty are filled by splitting the largest leaves of more
    /// than one `Tri4`. Children stay in the order of their triangles.
    fn open<const W: usize>(
        &self,
        refs: &mut [PrimRef],
        start: u32,
        r: ChildRef,
    ) -> ([(ChildRef, Aabb); W], usize) {
        let n = &self.nodes[r.index as usize];
        // A fixed array, not a Vec: one wide node per call, no allocation.
        let mut kids = [(ChildRef::default(), Aabb::EMPTY); W];
        kids[0] = (n.child[0], n.child_bounds(0));
        kids[1] = (n.child[1], n.child_bounds(1));
        let mut len = 2;
        let largest = |kids: &[(ChildRef, Aabb)], openable: &dyn Fn(ChildRef) -> bool| {
            (0..kids.len())
                .filter(|&i| openable(kids[i].0))
                .max_by(|&a, &b| {
                    kids[a]
                        .1
                        .surface_area()
                        .total_cmp(&kids[b].1.surface_area())
                        .then(b.cmp(&a))
                })
        };
        while len < W {
            let two = if let Some(i) = largest(&kids[..len], &|c| !c.is_leaf()) {
                let m = &self.nodes[kids[i].0.index as usize];
                let halves = [
                    (m.child[0], m.child_bounds(0)),
                    (m.child[1], m.child_bounds(1)),
                ];
                (i, halves)
            } else if let Some(i) = largest(&kids[..len], &|c| {
                self.fill_slots && c.is_leaf() && c.count > SPLIT_LEAVES_ABOVE
            }) {
                let leaf = kids[i].0;
                let at = (leaf.index - start) as usize;
                let range = &mut refs[at..at + leaf.count as usize];
                (i, split_leaf(range, leaf.index))
            } else {
                break;
            };
            let (i, [a, b]) = two;
            kids.copy_within(i + 1..len, i + 2);
            kids[i] = a;
            kids[i + 1] = b;
            len += 1;
        }
        (kids, len)
    }
}

/// Splits a leaf's triangles `refs` (the first of them record `first`) in two, forced (as
/// Embree's wide builder splits every child of more than one block until the node is full):
/// sorted by centroid on the axis where the centroids spread most, cut where `area × Tri4s`
/// summed over both halves is least (first on ties). One axis, not three: three sorts cost about a
/// third more build time for the same trace speed (measured: see docs/experiments.md, "the
/// leaf split along the best of three axes"). Ties in the sort go by mesh
/// index (deterministic).
fn split_leaf(refs: &mut [PrimRef], first: u32) -> [(ChildRef, Aabb); 2] {
    let spread = refs
        .iter()
        .fold(Box3::EMPTY, |b, p| b.grow(p.centroid2()))
        .extent();
    let axis = spread.max_position();
    refs.sort_unstable_by(|a, b| {
        a.centroid2_on(axis)
            .total_cmp(&b.centroid2_on(axis))
            .then(a.id().cmp(&b.id()))
    });
    let tri4s = |k: usize| k.div_ceil(4) as f64;
    let n = refs.len();
    // The boxes of the right-hand halves `refs[k..]`, on the stack for the usual leaf sizes.
    let (mut small, mut large) = ([Box3::EMPTY; 32], Vec::new());
    let right: &mut [Box3] = if n <= small.len() {
        &mut small[..n]
    } else {
        large.resize(n, Box3::EMPTY);
        &mut large
    };
    let mut acc = Box3::EMPTY;
    for k in (1..n).rev() {
        acc = acc.union(&refs[k].bounds());
        right[k] = acc;
    }
    let (mut best, mut cut, mut left) = (f64::INFINITY, 1, Box3::EMPTY);
    let mut acc = Box3::EMPTY;
    for k in 1..n {
        acc = acc.union(&refs[k - 1].bounds());
        let cost = acc.half_area() * tri4s(k) + right[k].half_area() * tri4s(n - k);
        if cost < best {
            (best, cut, left) = (cost, k, acc);
        }
    }
    let leaf = |index: usize, count: usize, b: Box3| {
        let r = ChildRef {
            index: first + index as u32,
            count: count as u32,
        };
        (r, b.to_aabb())
    };
    [leaf(0, cut, left), leaf(cut, n - cut, right[cut])]
}

/// Collapses the binary subtree `r`, whose triangles are `refs` (the first of them record
/// `start`), into wide nodes appended to `out` depth-first. Leaves stay triangle ranges
/// (`{ index: first record, count }`) until [`number_tri4s`]. A subtree of
/// [`PARALLEL_COLLAPSE`] triangles or more collapses its children on rayon, each into a
/// vector of its own, appended in slot order afterwards: the same nodes in the same order as
/// one thread makes them.
pub(super) fn collapse<const W: usize>(
    b: &Binary,
    refs: &mut [PrimRef],
    start: u32,
    r: ChildRef,
    out: &mut Vec<WideNode<W>>,
) -> ChildRef {
    if r.is_leaf() {
        return r;
    }
    let parallel = refs.len() >= PARALLEL_COLLAPSE;
    let (kids, len) = b.open::<W>(refs, start, r);
    let at = out.len();
    out.push(WideNode::empty());
    // The children's triangles are consecutive ranges of `refs`, in slot order.
    let mut jobs = Vec::with_capacity(len);
    let (mut rest, mut first) = (refs, start);
    for &(child, _) in &kids[..len] {
        let size = b.size(child);
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size);
        debug_assert!(!child.is_leaf() || child.index == first);
        jobs.push((child, mine, first));
        rest = tail;
        first += size as u32;
    }
    if parallel {
        use rayon::prelude::*;
        let parts: Vec<(ChildRef, Vec<WideNode<W>>)> = jobs
            .into_par_iter()
            .map(|(child, mine, first)| {
                let mut local = Vec::new();
                let r = collapse(b, mine, first, child, &mut local);
                (r, local)
            })
            .collect();
        for (slot, (r, local)) in parts.into_iter().enumerate() {
            let r = append_part(out, r, local);
            out[at].set_child(slot, &kids[slot].1, r);
        }
    } else {
        for (slot, (child, mine, first)) in jobs.into_iter().enumerate() {
            let r = collapse(b, mine, first, child, out);
            out[at].set_child(slot, &kids[slot].1, r);
        }
    }
    ChildRef {
        index: at as u32,
        count: 0,
    }
}

/// Appends a subtree collapsed into a vector of its own (interior references local to it) to
/// `out`, and returns the reference to its root there.
fn append_part<const W: usize>(
    out: &mut Vec<WideNode<W>>,
    r: ChildRef,
    local: Vec<WideNode<W>>,
) -> ChildRef {
    if r.is_leaf() {
        return r;
    }
    let base = out.len() as u32;
    out.extend(local.into_iter().map(|mut node| {
        let used = node.children();
        for c in node.child[..used].iter_mut().filter(|c| !c.is_leaf()) {
            c.index += base;
        }
        node
    }));
    ChildRef {
        index: base + r.index,
        count: 0,
    }
}
