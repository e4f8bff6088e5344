//! `ToyBvh`: a deliberately plain structure written outside raybench against the public
//! `raybench_accel::Accel` trait, to show what benchmarking your own structure takes.
//!
//! Algorithm: a binary BVH whose nodes split their triangles at the median centroid on the
//! axis where the centroids spread most (the classic object-median build, as pbrt's
//! `SplitMethod::EqualCounts`), stopping at `max_leaf_size` triangles or where every centroid
//! coincides; flattened depth first so a node's left child follows it. Traversal is a loop over
//! a fixed stack, children in stored order, with the two-sided Möller–Trumbore of raybench-geom
//! on copies of the triangles; closest point walks the same tree, pruning boxes farther than
//! the best answer. Trade-off: the build is O(N log N) and needs no cost model, but a median
//! split ignores where the empty space is, so rays visit many more nodes than in an SAH tree
//! (compare `bvh-median` with `bvh-binned` in raybench's own list). Caveat: a toy, single
//! threaded, unordered, scalar; it is here to be measured against, not to win.

use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, Nearest, PointHit};
use raybench_geom::{Aabb, MollerTriangle, Ray, TriangleMesh, Vec3, box_distance_squared};
use serde::Serialize;
use std::sync::Arc;

/// The one knob, written into every report.
#[derive(Clone, Debug, Serialize)]
pub struct ToyParams {
    /// A node with at most this many triangles becomes a leaf (at least 1).
    pub max_leaf_size: usize,
}

impl Default for ToyParams {
    fn default() -> ToyParams {
        ToyParams { max_leaf_size: 4 }
    }
}

/// Enough for any tree: median splits halve the triangles, so depth stays below 33 for any
/// mesh raybench accepts (fewer than 2^32 triangles); [`ToyBvh::validate`] checks it.
const STACK: usize = 64;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: index of the first triangle in `prims`/`tris`. Inner: index of the right child
    /// (the left child is the next node).
    first_or_right: u32,
    /// Triangles in a leaf; 0 marks an inner node.
    count: u32,
}

#[derive(Debug)]
pub struct ToyBvh {
    nodes: Vec<Node>,
    /// Mesh index of each leaf triangle, leaf by leaf.
    prims: Vec<u32>,
    /// The same triangles in Möller–Trumbore's layout.
    tris: Vec<MollerTriangle>,
    mesh: Arc<TriangleMesh>,
    depth: u32,
}

impl ToyBvh {
    /// Appends the subtree over `prims` (mesh indices) and returns its depth.
    fn build_node(&mut self, mesh: &TriangleMesh, prims: &mut [u32], max_leaf: usize) -> u32 {
        let bounds = prims.iter().fold(Aabb::EMPTY, |b, &p| {
            b.union(&mesh.triangle(p as usize).bounds())
        });
        let centroid = |p: u32| mesh.triangle(p as usize).centroid();
        let spread = Aabb::from_points(prims.iter().map(|&p| centroid(p)));
        let axis = spread.largest_axis();
        let at = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            first_or_right: self.prims.len() as u32,
            count: prims.len() as u32,
        });
        if prims.len() <= max_leaf || spread.min[axis] == spread.max[axis] {
            self.prims.extend_from_slice(prims);
            return 1;
        }
        // Ties on the centroid are broken by mesh index, so the tree depends on the mesh only.
        let mid = prims.len() / 2;
        prims.select_nth_unstable_by(mid, |&a, &b| {
            (centroid(a)[axis].total_cmp(&centroid(b)[axis])).then(a.cmp(&b))
        });
        let (left, right) = prims.split_at_mut(mid);
        let left_depth = self.build_node(mesh, left, max_leaf);
        self.nodes[at].first_or_right = self.nodes.len() as u32;
        self.nodes[at].count = 0;
        let right_depth = self.build_node(mesh, right, max_leaf);
        1 + left_depth.max(right_depth)
    }

    /// The tree's invariants: every triangle in exactly one leaf, every box holding its
    /// children's boxes and its leaf triangles, depth within the traversal stack.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let mut seen = vec![false; mesh.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            if n.count == 0 {
                let (l, r) = (i + 1, n.first_or_right as usize);
                for child in [l, r] {
                    let c = self
                        .nodes
                        .get(child)
                        .ok_or(format!("node {i}: no child {child}"))?;
                    if !n.bounds.contains_box(&c.bounds) {
                        return Err(format!("node {i}: child {child}'s box sticks out"));
                    }
                }
                continue;
            }
            let first = n.first_or_right as usize;
            for &p in &self.prims[first..first + n.count as usize] {
                if std::mem::replace(&mut seen[p as usize], true) {
                    return Err(format!("triangle {p} is in two leaves"));
                }
                if !n.bounds.contains_box(&mesh.triangle(p as usize).bounds()) {
                    return Err(format!("leaf {i}: triangle {p} sticks out of its box"));
                }
            }
        }
        if let Some(p) = seen.iter().position(|s| !s) {
            return Err(format!("triangle {p} is in no leaf"));
        }
        if self.depth as usize >= STACK {
            return Err(format!("depth {} exceeds the stack of {STACK}", self.depth));
        }
        Ok(())
    }
}

impl raybench_accel::Walk for ToyBvh {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut r = *ray;
        let mut stack = [0u32; STACK];
        let mut len = usize::from(!self.nodes.is_empty());
        while len > 0 {
            len -= 1;
            let at = stack[len];
            let n = &self.nodes[at as usize];
            if n.bounds.intersect(&r).is_none() {
                continue;
            }
            if n.count == 0 {
                c.node();
                stack[len] = n.first_or_right;
                stack[len + 1] = at + 1;
                len += 2;
                continue;
            }
            c.leaf();
            let first = n.first_or_right as usize;
            for i in first..first + n.count as usize {
                c.prim_tests(1);
                let Some(h) = self.tris[i].intersect(&r) else {
                    continue;
                };
                let prim = self.prims[i];
                // Equal t: the lower mesh index wins, as in brute force.
                if best.is_some_and(|b| h.t > b.t || (h.t == b.t && prim > b.prim)) {
                    continue;
                }
                best = Some(Hit::from_tri_hit(prim, h));
                if ANY_HIT {
                    return best;
                }
                r = r.with_t_max(h.t);
            }
        }
        best
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        let mut nearest = Nearest::within(p, max_radius)?;
        let mut stack = [0u32; STACK];
        let mut len = usize::from(!self.nodes.is_empty());
        while len > 0 {
            len -= 1;
            let at = stack[len];
            let n = &self.nodes[at as usize];
            if box_distance_squared(p, &n.bounds) > nearest.bound_d2() {
                continue;
            }
            if n.count == 0 {
                c.node();
                stack[len] = n.first_or_right;
                stack[len + 1] = at + 1;
                len += 2;
                continue;
            }
            c.leaf();
            let first = n.first_or_right as usize;
            for &prim in &self.prims[first..first + n.count as usize] {
                c.prim_tests(1);
                nearest.test_triangle(p, prim, &self.mesh.triangle(prim as usize));
            }
        }
        nearest.into_hit()
    }
}

impl Accel for ToyBvh {
    type Params = ToyParams;

    fn build(mesh: Arc<TriangleMesh>, params: &ToyParams) -> Result<ToyBvh, BuildError> {
        if params.max_leaf_size == 0 {
            return Err(BuildError::Unsupported(
                "max_leaf_size must be at least 1".into(),
            ));
        }
        let mut bvh = ToyBvh {
            nodes: Vec::new(),
            prims: Vec::with_capacity(mesh.len()),
            tris: Vec::new(),
            mesh: mesh.clone(),
            depth: 0,
        };
        if !mesh.is_empty() {
            let mut prims: Vec<u32> = (0..mesh.len() as u32).collect();
            bvh.depth = bvh.build_node(&mesh, &mut prims, params.max_leaf_size);
        }
        bvh.tris = bvh
            .prims
            .iter()
            .map(|&p| MollerTriangle::new(&mesh.triangle(p as usize)))
            .collect();
        Ok(bvh)
    }

    fn name(&self) -> &str {
        "toy-bvh"
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        let leaves = self.nodes.iter().filter(|n| n.count > 0).count() as u64;
        BuildStats {
            nodes: self.nodes.len() as u64,
            leaves,
            max_depth: self.depth,
            refs: self.prims.len() as u64,
            sah_cost: None,
            extra: Default::default(),
        }
    }

    fn memory(&self) -> Memory {
        Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            indices: std::mem::size_of_val(self.prims.as_slice()) as u64,
            primitives: std::mem::size_of_val(self.tris.as_slice()) as u64,
        }
    }
}
