//! The children of every wide node chosen for the least SAH cost, by dynamic programming over
//! the binary tree (the collapse of Ylitie, Karras and Laine 2017, "Efficient incoherent ray
//! traversal on GPUs through compressed wide BVHs", section 3, without its leaf merging).
//!
//! The greedy collapse (`collapse.rs`) fills each wide node by opening its largest child until the
//! node is full, whatever that leaves below: the subtrees it did not open become nodes of their
//! own, often of two or three children, each a whole node test for a few boxes (8-wide nodes
//! averaged 4.9–6 children on the suite's scenes, 6.7–8 with this plan). Here every binary interior
//! node `n` gets, for each `i` from 1 to `W`, the least cost of covering its triangles with at most
//! `i` children of one wide node: `n` alone (a leaf of the binary tree, or a wide node whose `W`
//! slots cover its two children), or `k` children covering its left child and `i - k` its right. A
//! wide node made from `n` takes the cheapest split of its `W` slots between its two children. The
//! prices are the binary builder's, so the two agree on what a tree costs: a node test is the
//! traversal cost times the node's box area, a leaf the intersection cost times its area times its
//! triangles rounded up to whole blocks.
//!
//! Making leaves of whole binary subtrees (the rest of Ylitie et al.'s collapse) never
//! changed a tree on the 17 scenes of the suite, and pricing the split of a leaf into two
//! slots inside the table built more slowly for the same speed (measured: see
//! docs/experiments.md, "SAH-optimal collapse"); the greedy collapse's leaf splits still
//! fill any slot the chosen children leave empty.
//!
//! One pass over the binary nodes, children before parents, with at most `W²/2` sums each;
//! subtrees of a grain of nodes or more ([`PARALLEL_PLAN`] on large trees, finer on small
//! ones: see `grain.rs`) are planned on rayon, and the plan does not depend on the thread
//! count.

use super::MAX_WIDTH;
use crate::BvhParams;
use crate::build::blocks;
use crate::node::{ChildRef, Node};
use raybench_geom::Aabb;

/// Subtrees of at least this many binary nodes plan their two children on rayon: 1,024
/// against 8,192, the bunny's and the 100k sphere's 2-thread builds 7 % faster (8,192 left the
/// bunny's plan on one thread; see docs/experiments.md, "the plan forked from 1,024 nodes").
const PARALLEL_PLAN: usize = 1024;

/// The fewest binary nodes a subtree planned on its own task has on small trees.
const MIN_PLAN_TASK: usize = 64;

/// Subtrees of at least this many of a tree's `nodes` plan their children on rayon.
fn plan_grain(nodes: usize) -> usize {
    crate::grain::grain(nodes, MIN_PLAN_TASK, PARALLEL_PLAN)
}

/// One binary interior node's entry: for `i` = 1 to `W`, how to cover it with at most `i`
/// children (`cover[i - 1]`: `(0, 0)` the node alone, or at most that many children from each
/// of its two); and how its own wide node splits its `W` slots between its children. The
/// costs behind these choices are needed only by the node's parent, so they travel up the
/// recursion instead of living here: an entry of 18 bytes at 8 wide instead of 88, written once
/// per binary node (measured: see docs/experiments.md, "the plan's costs returned, not stored").
#[derive(Clone, Copy)]
struct Entry<const W: usize> {
    cover: [(u8, u8); W],
    own: (u8, u8),
}

impl<const W: usize> Entry<W> {
    const EMPTY: Entry<W> = Entry {
        cover: [(0, 0); W],
        own: (0, 0),
    };
}

/// The entries of every binary interior node, in the binary tree's order.
pub(super) struct Plan<const W: usize> {
    entries: Vec<Entry<W>>,
}

impl<const W: usize> Plan<W> {
    /// The plan for `W`-wide nodes over the binary tree `nodes` (depth-first from the root at
    /// index 0: a node's left subtree right after it, then its right subtree).
    pub(super) fn new(nodes: &[Node], p: &BvhParams) -> Plan<W> {
        let mut entries = vec![Entry::EMPTY; nodes.len()];
        if !nodes.is_empty() {
            plan(nodes, 0, &mut entries, p, plan_grain(nodes.len()));
        }
        Plan { entries }
    }

    /// The children of the wide node made from binary interior node `r`, in the order of
    /// their triangles: binary interior nodes (each a wide node in turn) and leaves.
    pub(super) fn children(&self, nodes: &[Node], r: ChildRef) -> ([(ChildRef, Aabb); W], usize) {
        let mut kids = [(ChildRef::default(), Aabb::EMPTY); W];
        let mut len = 0;
        let (a, b) = self.entries[r.index as usize].own;
        let node = &nodes[r.index as usize];
        for (c, budget) in [(0, a), (1, b)] {
            let child = (node.child[c], node.child_bounds(c));
            self.cover(nodes, child, budget, &mut kids, &mut len);
        }
        (kids, len)
    }

    fn cover(
        &self,
        nodes: &[Node],
        (r, bounds): (ChildRef, Aabb),
        budget: u8,
        kids: &mut [(ChildRef, Aabb); W],
        len: &mut usize,
    ) {
        let (a, b) = if r.is_leaf() {
            (0, 0)
        } else {
            self.entries[r.index as usize].cover[budget as usize - 1]
        };
        if a == 0 {
            kids[*len] = (r, bounds);
            *len += 1;
            return;
        }
        let node = &nodes[r.index as usize];
        for (c, budget) in [(0, a), (1, b)] {
            self.cover(
                nodes,
                (node.child[c], node.child_bounds(c)),
                budget,
                kids,
                len,
            );
        }
    }
}

/// The least cost of the wide tree made from binary interior node `r` (its own node test
/// included), in the builder's prices, not divided by the root's area: the plan of `r`'s
/// subtree alone.
#[cfg(test)]
pub(super) fn cost_as_node<const W: usize>(nodes: &[Node], r: ChildRef, p: &BvhParams) -> f64 {
    let at = r.index as usize;
    plan::<W>(
        nodes,
        at,
        &mut vec![Entry::EMPTY; nodes.len() - at],
        p,
        usize::MAX,
    )[0]
}

/// Fills the entries of the subtree of binary interior node `at` and returns `at`'s costs: for
/// `i` = 1 to `W`, the least cost of covering it with at most `i` children. `entries` starts
/// with that subtree's range of the binary tree, so `entries[0]` is `at`'s entry.
fn plan<const W: usize>(
    nodes: &[Node],
    at: usize,
    entries: &mut [Entry<W>],
    p: &BvhParams,
    grain: usize,
) -> [f64; W] {
    let node = &nodes[at];
    // A child's subtree starts at its index; the left one right after `at`.
    let right = node.child[1];
    let right_offset = if right.is_leaf() {
        entries.len()
    } else {
        right.index as usize - at
    };
    let side = |c: usize, part: &mut [Entry<W>]| -> [f64; W] {
        let r = node.child[c];
        if r.is_leaf() {
            [leaf_cost(node.child_bounds(c).surface_area(), r.count, p); W]
        } else {
            plan(nodes, r.index as usize, part, p, grain)
        }
    };
    let (l, r) = {
        let (left_part, right_part) = entries[1..].split_at_mut(right_offset - 1);
        if left_part.len().min(right_part.len()) >= grain {
            rayon::join(|| side(0, left_part), || side(1, right_part))
        } else {
            (side(0, left_part), side(1, right_part))
        }
    };
    // The cheapest split of `j` slots between the two children, j = 2 ..= width: `k` slots on
    // the left, the first `k` of equal costs. Looping over `k` outside and `j` inside gives
    // the same minima as the other way round (each `j` still meets `k` in increasing order)
    // with an inner loop of independent lanes.
    let mut cost = [0.0; MAX_WIDTH + 1];
    let mut left_slots = [1u8; MAX_WIDTH + 1];
    for j in 2..=W {
        cost[j] = l[0] + r[j - 2];
    }
    for k in 2..W {
        for j in k + 1..=W {
            let c = l[k - 1] + r[j - k - 1];
            let better = c < cost[j];
            cost[j] = if better { c } else { cost[j] };
            left_slots[j] = if better { k as u8 } else { left_slots[j] };
        }
    }
    let split = |j: usize| (left_slots[j], j as u8 - left_slots[j]);
    let area = node
        .child_bounds(0)
        .union(&node.child_bounds(1))
        .surface_area();
    let e = &mut entries[0];
    e.own = split(W);
    let mut costs = [0.0; W];
    let mut best = (area * p.traversal_cost as f64 + cost[W], (0, 0));
    for i in 1..=W {
        if i >= 2 && cost[i] < best.0 {
            best = (cost[i], split(i));
        }
        costs[i - 1] = best.0;
        e.cover[i - 1] = best.1;
    }
    costs
}

fn leaf_cost(area: f64, n: u32, p: &BvhParams) -> f64 {
    area * p.intersection_cost as f64 * blocks(p, n as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{Flat, build};
    use crate::wide::{BvhWide, Collapse, WideParams};
    use raybench_accel::Accel;

    /// The exhaustive enumeration below is exponential in the width: 8-wide plans.
    const WIDTH: usize = 8;

    fn binary(spec: &str, p: &BvhParams) -> Flat {
        let mesh = raybench_testkit::generated(spec, 3);
        build(&mesh, p).expect("builds")
    }

    /// The cheapest way of covering `r` with exactly `k` children, for every `k` up to
    /// `budget` (`f64::INFINITY` where there is none): `r` itself, or a cover of each of its
    /// children. By recursion over the tree, without the table or its ranges.
    fn covers(nodes: &[Node], r: ChildRef, bounds: Aabb, budget: usize, p: &BvhParams) -> Vec<f64> {
        let mut best = vec![f64::INFINITY; budget + 1];
        best[1] = cheapest_as_child(nodes, r, bounds, p);
        if !r.is_leaf() && budget >= 2 {
            let n = &nodes[r.index as usize];
            let a = covers(nodes, n.child[0], n.child_bounds(0), budget - 1, p);
            let b = covers(nodes, n.child[1], n.child_bounds(1), budget - 1, p);
            for (ka, ca) in a.iter().enumerate().skip(1) {
                for (kb, cb) in b.iter().enumerate().skip(1).take(budget - ka) {
                    best[ka + kb] = best[ka + kb].min(ca + cb);
                }
            }
        }
        best
    }

    /// The least cost of `r` as one child: its leaf, or its cheapest wide node.
    fn cheapest_as_child(nodes: &[Node], r: ChildRef, bounds: Aabb, p: &BvhParams) -> f64 {
        if r.is_leaf() {
            return leaf_cost(bounds.surface_area(), r.count, p);
        }
        cheapest_node(nodes, r, p)
    }

    fn cheapest_node(nodes: &[Node], r: ChildRef, p: &BvhParams) -> f64 {
        let n = &nodes[r.index as usize];
        let area = n.child_bounds(0).union(&n.child_bounds(1)).surface_area();
        let a = covers(nodes, n.child[0], n.child_bounds(0), WIDTH - 1, p);
        let b = covers(nodes, n.child[1], n.child_bounds(1), WIDTH - 1, p);
        let mut best = f64::INFINITY;
        for (ka, ca) in a.iter().enumerate().skip(1) {
            for cb in b.iter().skip(1).take(WIDTH - ka) {
                best = best.min(ca + cb);
            }
        }
        area * p.traversal_cost as f64 + best
    }

    /// The cost of a built wide tree in the builder's prices, summed in f64.
    fn wide_cost<const W: usize>(t: &BvhWide<W>, p: &BvhParams) -> f64 {
        let mut sum = 0.0;
        let root = &t.nodes()[t.root().index as usize];
        let whole = (0..root.children()).fold(Aabb::EMPTY, |b, i| b.union(&root.child_bounds(i)));
        sum += whole.surface_area() * p.traversal_cost as f64;
        let mut stack = vec![t.root()];
        while let Some(r) = stack.pop() {
            let n = &t.nodes()[r.index as usize];
            for i in 0..n.children() {
                let (c, area) = (n.child[i], n.child_bounds(i).surface_area());
                if c.is_leaf() {
                    sum += leaf_cost(area, c.count, p);
                } else {
                    sum += area * p.traversal_cost as f64;
                    stack.push(c);
                }
            }
        }
        sum
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-4 * a.abs().max(b.abs())
    }

    /// On small trees (single-triangle leaves, so deep), the table's cost of every interior
    /// node is the least over every cover an exhaustive enumeration finds.
    #[test]
    fn the_plan_is_the_cheapest_of_every_cover() {
        let p = BvhParams {
            max_leaf_size: 1,
            ..WideParams::default().binary
        };
        for spec in [
            "soup:triangles=40",
            "teapot:triangles=48",
            "grass:density=1",
        ] {
            let flat = binary(spec, &p);
            assert!(flat.nodes.len() > 20, "{spec}: {} nodes", flat.nodes.len());
            for i in 0..flat.nodes.len().min(60) {
                let r = ChildRef {
                    index: i as u32,
                    count: 0,
                };
                let (planned, exhaustive) = (
                    cost_as_node::<WIDTH>(&flat.nodes, r, &p),
                    cheapest_node(&flat.nodes, r, &p),
                );
                assert!(
                    close(planned, exhaustive),
                    "{spec} node {i}: {planned} against {exhaustive}"
                );
            }
        }
    }

    /// Without leaf splits, the wide tree built from the plan costs what the plan says, and
    /// no more than the greedy collapse's tree of the same binary tree.
    #[test]
    fn the_built_tree_costs_what_the_plan_says() {
        fn check<const W: usize>(spec: &str) {
            let mesh = raybench_testkit::generated(spec, 3);
            let with = |collapse| WideParams {
                collapse,
                fill_slots: false,
                ..WideParams::for_width(W as u32)
            };
            let optimal =
                BvhWide::<W>::build_wide(mesh.clone(), &with(Collapse::Optimal)).expect("builds");
            let greedy =
                BvhWide::<W>::build_wide(mesh.clone(), &with(Collapse::Greedy)).expect("builds");
            optimal.validate(&mesh).expect("the tree validates");
            let p = &optimal.params().binary;
            let flat = build(&mesh, p).expect("builds");
            let planned = cost_as_node::<W>(&flat.nodes, flat.root, p);
            let (built, greedy) = (wide_cost(&optimal, p), wide_cost(&greedy, p));
            assert!(
                close(planned, built),
                "{spec}, {W} wide: planned {planned}, built {built}"
            );
            assert!(
                built <= greedy * (1.0 + 1e-6),
                "{spec}, {W} wide: {built} against greedy {greedy}"
            );
            assert_eq!(optimal.stats_with_splits().refs, mesh.len() as u64);
        }
        for spec in [
            "teapot:triangles=20000",
            "soup:triangles=5000",
            "grass:density=20",
            "hair",
        ] {
            check::<8>(spec);
            check::<4>(spec);
        }
    }

    /// Large subtrees are planned on rayon; the plan is the one a single thread makes.
    #[test]
    fn the_plan_is_the_same_on_one_and_two_threads() {
        let p = WideParams::default().binary;
        let flat = binary("sphere:triangles=200000", &p);
        let right = flat.nodes[0].child[1];
        assert!(flat.nodes[0].child.iter().all(|c| !c.is_leaf()));
        // The root's two subtrees, as `plan` splits the entries.
        let sides = (
            right.index as usize - 1,
            flat.nodes.len() - right.index as usize,
        );
        assert!(
            sides.0.min(sides.1) >= plan_grain(flat.nodes.len()),
            "big enough to fork: {sides:?}"
        );
        let plan = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| Plan::<WIDTH>::new(&flat.nodes, &p))
        };
        let (one, two) = (plan(1), plan(2));
        assert_eq!(one.entries.len(), two.entries.len());
        for (a, b) in one.entries.iter().zip(&two.entries) {
            assert_eq!((a.cover, a.own), (b.cover, b.own));
        }
    }

    /// Boxes near Embree's coordinate limit (1.844e18) have areas near f32's largest, so the
    /// plan sums its costs in f64: summed in f32 they overflowed, no split was cheaper than
    /// infinity, and the collapse indexed a cover of zero slots.
    #[test]
    fn boxes_near_the_coordinate_limit_are_planned() {
        use raybench_geom::{Triangle, TriangleMesh, Vec3};
        let big = 1.8e18f32;
        let tris: Vec<Triangle> = (0..400)
            .map(|i| {
                let t = i as f32 / 400.0;
                Triangle::new(
                    Vec3::new(-big, -big * t, -big),
                    Vec3::new(big, big * (1.0 - t), -big * t),
                    Vec3::new(big * t, big, big),
                )
            })
            .collect();
        let (mesh, removed) = TriangleMesh::from_triangles(&tris).expect("a mesh");
        assert_eq!(removed, Default::default());
        let mesh = std::sync::Arc::new(mesh);
        let t = BvhWide::<8>::build(mesh.clone(), &WideParams::default()).expect("builds");
        t.validate(&mesh).expect("the tree validates");
        assert!(t.nodes().len() > 1, "{} nodes", t.nodes().len());
    }
}
