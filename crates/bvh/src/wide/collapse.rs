//! The binary tree collapsed into wide nodes.

use super::node::WideNode;
use super::optimal::Plan;
use crate::BvhParams;
use crate::build::{Box3, PrimRef};
use crate::node::{ChildRef, Node};
use raybench_geom::Aabb;

/// What every collapse task reads: the binary tree, the number of triangles under each of its
/// interior nodes (a subtree's triangles are one range of the builder's records), whether
/// empty slots are filled, and the SAH-optimal plan of every node's children (none for the
/// greedy collapse).
pub(super) struct Binary<'a, const W: usize> {
    nodes: &'a [Node],
    sizes: Vec<u32>,
    fill_slots: bool,
    plan: Option<Plan<W>>,
    /// Subtrees of at least this many triangles collapse their children on rayon.
    grain: usize,
}

/// Leaves of more triangles than this (one `Tri4`) may be split to fill a node's empty slots.
const SPLIT_LEAVES_ABOVE: u32 = 4;

/// Subtrees of at least this many triangles collapse their children's subtrees on rayon in
/// large trees (measured: see docs/experiments.md, "collapse on rayon"); small trees take a
/// finer grain (see `grain.rs`), never under [`MIN_COLLAPSE_TASK`].
const PARALLEL_COLLAPSE: usize = 4096;

/// The fewest triangles a subtree collapsed on its own task has on small trees.
const MIN_COLLAPSE_TASK: usize = 256;

impl<const W: usize> Binary<'_, W> {
    /// `optimal`: the builder's prices to plan the children with (see `optimal.rs`), or
    /// `None` for the greedy collapse.
    pub(super) fn new<'a>(
        nodes: &'a [Node],
        fill_slots: bool,
        optimal: Option<&BvhParams>,
    ) -> Binary<'a, W> {
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
        let plan = optimal.map(|p| Plan::new(nodes, p));
        let triangles = sizes.first().map_or(0, |&n| n as usize);
        Binary {
            nodes,
            sizes,
            fill_slots,
            plan,
            grain: crate::grain::grain(triangles, MIN_COLLAPSE_TASK, PARALLEL_COLLAPSE),
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
    /// (the first of them record `start`): the plan's, when there is one; otherwise, starting
    /// from its two children, the interior child with the largest area is opened (first on
    /// ties: deterministic) until there are `W` or only leaves remain. Slots still empty are
    /// filled by splitting the largest leaves of more than one `Tri4`. Children stay in the
    /// order of their triangles.
    fn open(
        &self,
        refs: &mut [PrimRef],
        start: u32,
        r: ChildRef,
    ) -> ([(ChildRef, Aabb); W], usize) {
        let n = &self.nodes[r.index as usize];
        // A fixed array, not a Vec: one wide node per call, no allocation.
        let (mut kids, mut len) = match &self.plan {
            Some(plan) => plan.children(self.nodes, r),
            None => {
                let mut kids = [(ChildRef::default(), Aabb::EMPTY); W];
                kids[0] = (n.child[0], n.child_bounds(0));
                kids[1] = (n.child[1], n.child_bounds(1));
                (kids, 2)
            }
        };
        // The plan's children are final; only the greedy collapse opens more of them.
        let planned = self.plan.is_some();
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
            let two = if let Some(i) = largest(&kids[..len], &|c| !planned && !c.is_leaf()) {
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

/// Collapses the whole binary tree (root `r`, triangles `refs` from record 0) into wide
/// nodes, depth-first; returns them with the reference to the root. Subtrees of a grain of
/// triangles or more ([`PARALLEL_COLLAPSE`] in large trees) collapse their children on rayon
/// into separate pieces ([`Piece`]); once every piece is done, each is copied exactly once
/// into its place in the final array, in parallel too. The nodes and their order are the
/// ones one thread makes.
pub(super) fn collapse_tree<const W: usize>(
    b: &Binary<W>,
    refs: &mut [PrimRef],
    r: ChildRef,
) -> (Vec<WideNode<W>>, ChildRef) {
    use rayon::prelude::*;
    let piece = piece::<W>(b, refs, 0, r);
    let mut nodes: Vec<WideNode<W>> = (0..piece.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| WideNode::empty())
        .collect();
    let root = place(piece, &mut nodes, 0);
    (nodes, root)
}

/// A collapsed subtree as the parallel collapse returns it.
enum Piece<const W: usize> {
    /// Collapsed by one task: nodes depth-first from local index 0 whose interior child
    /// references are local too, or a leaf (`nodes` empty).
    Local {
        nodes: Vec<WideNode<W>>,
        root: ChildRef,
    },
    /// A node whose children were collapsed on rayon (slot order), with its boxes set and
    /// its child references left to [`place`]; `len` counts the nodes of the whole piece.
    Fork {
        node: WideNode<W>,
        children: Vec<Piece<W>>,
        len: usize,
    },
}

impl<const W: usize> Piece<W> {
    fn len(&self) -> usize {
        match self {
            Piece::Local { nodes, .. } => nodes.len(),
            Piece::Fork { len, .. } => *len,
        }
    }
}

/// Collapses the binary subtree `r`, whose triangles are `refs` (the first of them record
/// `start`), into a [`Piece`]: on this thread below the grain's triangles, else with its
/// children's subtrees on rayon.
fn piece<const W: usize>(b: &Binary<W>, refs: &mut [PrimRef], start: u32, r: ChildRef) -> Piece<W> {
    use rayon::prelude::*;
    if r.is_leaf() || refs.len() < b.grain {
        let mut nodes = Vec::new();
        let root = collapse(b, refs, start, r, &mut nodes);
        return Piece::Local { nodes, root };
    }
    let (kids, len) = b.open(refs, start, r);
    let mut node = WideNode::empty();
    let mut jobs = Vec::with_capacity(len);
    for (slot, (child, bounds, mine, first)) in
        child_ranges(b, &kids[..len], refs, start).enumerate()
    {
        node.set_child(slot, &bounds, ChildRef::default());
        jobs.push((child, mine, first));
    }
    let children: Vec<Piece<W>> = jobs
        .into_par_iter()
        .map(|(child, mine, first)| piece(b, mine, first, child))
        .collect();
    let len = 1 + children.iter().map(Piece::len).sum::<usize>();
    Piece::Fork {
        node,
        children,
        len,
    }
}

/// Writes `piece` into `out` (exactly its length), whose first node has index `base` in the
/// final array; returns the reference to the piece's root.
fn place<const W: usize>(piece: Piece<W>, out: &mut [WideNode<W>], base: u32) -> ChildRef {
    use rayon::prelude::*;
    match piece {
        Piece::Local { root, .. } if root.is_leaf() => root,
        Piece::Local { nodes, root } => {
            for (o, mut node) in out.iter_mut().zip(nodes) {
                let used = node.children();
                for c in node.child[..used].iter_mut().filter(|c| !c.is_leaf()) {
                    c.index += base;
                }
                *o = node;
            }
            ChildRef {
                index: base + root.index,
                count: 0,
            }
        }
        Piece::Fork { node, children, .. } => {
            let (head, mut rest) = out.split_first_mut().expect("a fork has its own node");
            *head = node;
            let mut jobs = Vec::with_capacity(children.len());
            let mut at = base + 1;
            for child in children {
                let len = child.len();
                let (mine, tail) = std::mem::take(&mut rest).split_at_mut(len);
                jobs.push((child, mine, at));
                at += len as u32;
                rest = tail;
            }
            let refs: Vec<ChildRef> = jobs
                .into_par_iter()
                .map(|(child, mine, at)| place(child, mine, at))
                .collect();
            head.child[..refs.len()].copy_from_slice(&refs);
            ChildRef {
                index: base,
                count: 0,
            }
        }
    }
}

/// Collapses the binary subtree `r`, whose triangles are `refs` (the first of them record
/// `start`), into wide nodes appended to `out` depth-first, on the calling thread. Leaves
/// stay triangle ranges (`{ index: first record, count }`) until [`number_tri4s`].
///
/// [`number_tri4s`]: super::pack::number_tri4s
fn collapse<const W: usize>(
    b: &Binary<W>,
    refs: &mut [PrimRef],
    start: u32,
    r: ChildRef,
    out: &mut Vec<WideNode<W>>,
) -> ChildRef {
    if r.is_leaf() {
        return r;
    }
    let (kids, len) = b.open(refs, start, r);
    let at = out.len();
    out.push(WideNode::empty());
    for (slot, (child, bounds, mine, first)) in
        child_ranges(b, &kids[..len], refs, start).enumerate()
    {
        let r = collapse(b, mine, first, child, out);
        out[at].set_child(slot, &bounds, r);
    }
    ChildRef {
        index: at as u32,
        count: 0,
    }
}

/// The children of a wide node (`kids`, in slot order) with their triangles: consecutive
/// ranges of `refs`, whose first record is `start`; each with the index of its first record.
fn child_ranges<'a, const W: usize>(
    b: &'a Binary<W>,
    kids: &'a [(ChildRef, Aabb)],
    refs: &'a mut [PrimRef],
    start: u32,
) -> impl Iterator<Item = (ChildRef, Aabb, &'a mut [PrimRef], u32)> + 'a {
    let (mut rest, mut first) = (refs, start);
    kids.iter().map(move |&(child, bounds)| {
        let size = b.size(child);
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size);
        debug_assert!(!child.is_leaf() || child.index == first);
        rest = tail;
        let at = first;
        first += size as u32;
        (child, bounds, mine, at)
    })
}
