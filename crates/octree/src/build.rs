//! Octree construction: recursive subdivision into octants with exact insertion.
//!
//! The classic space-subdivision octree (Glassner, "Space subdivision for fast ray tracing",
//! IEEE CG&A 4(10), 1984), with triangles placed by the separating-axis triangle–box test of
//! Akenine-Möller (2001) instead of by bounding box. The root is the cube around the scene's
//! bounds (so cells stay cubic); a node is split at its centre into eight octants while it
//! holds more than MAX_OBJ triangles and is shallower than MAX_DEPTH. A triangle goes into an
//! octant when it overlaps the octant enlarged by [`raybench_geom::tribox::conservative_box`]'s
//! margin (2^-20 of the octant's coordinate magnitude, so fine near the origin where a small
//! teapot sits) — untested when its bounding box lies inside the enlarged octant, skipped when
//! its bounding box misses it.
//!
//! Termination and blow-up guards (docs/validation.md, B15, G7, G8, G10 and G13): a node is also a
//! leaf when its centre cannot be represented strictly between its faces in f32 (cells a few ulps
//! wide); when splitting makes no progress — two octants or more would each receive all the node's
//! triangles (identical triangles, a point, triangles meeting along an edge: the tiered stands of a
//! stadium are full of those, and without this rule every such edge is followed down to MAX_DEPTH,
//! its cells doubling at each level; one octant receiving everything, a teapot in one corner of the
//! node, is progress); when no triangle is as small as an octant on two axes at least (each then
//! crosses several octants, and splitting only follows their shared edges and corners down — at
//! every corner of a stadium's steps where more than MAX_OBJ triangles meet); or when a
//! surface-area cost model says the split does not pay ([`OctreeParams::traversal_cost`]:
//! concentric or crossing triangles, where each central octant gets most of them level after
//! level). The references and nodes in flight are counted at every split and the build stops with
//! [`BuildError::TooLarge`] past [`OctreeParams::memory_limit_bytes`].
//!
//! Built as a boxed tree (large nodes split on rayon tasks), then flattened: the present
//! children of a node contiguous, leaves' references in depth-first order.

use crate::node::{Node, child_box, mid};
use crate::{Octree, OctreeParams};
use raybench_accel::{BuildError, BuildStats};
use raybench_geom::tribox::{TriBox, conservative_box};
use raybench_geom::{Aabb, DVec3, MollerTriangle, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

enum BuildNode {
    Leaf(Vec<u32>),
    Interior {
        mid: Vec3,
        children: Vec<(u8, BuildNode)>,
    },
}

struct Ctx<'a> {
    mesh: &'a TriangleMesh,
    bounds: Vec<Aabb>,
    params: &'a OctreeParams,
    /// References held in lists right now (all leaves' at the end).
    live_refs: AtomicU64,
    nodes: AtomicU64,
    /// Bytes that do not grow: triangle copies and per-triangle bounds.
    fixed_bytes: u64,
}

impl Ctx<'_> {
    fn bytes(&self) -> u64 {
        self.fixed_bytes
            + self.live_refs.load(Ordering::Relaxed) * 4
            + self.nodes.load(Ordering::Relaxed) * std::mem::size_of::<Node>() as u64
    }
}

/// The root box: the cube around `b` (its largest extent on every axis, same centre), grown to
/// contain `b` whatever the rounding.
pub fn root_box(b: &Aabb) -> Aabb {
    if b.is_empty() {
        return Aabb::EMPTY;
    }
    let c = b.center();
    let half = b.extent().max_element() * 0.5;
    Aabb::new((c - half).min(b.min), (c + half).max(b.max))
}

/// The box insertion tests a node's triangles against.
#[inline]
pub fn enlarged(lo: Vec3, hi: Vec3) -> (DVec3, DVec3) {
    conservative_box(lo.as_dvec3(), hi.as_dvec3())
}

pub(crate) fn build(mesh: &Arc<TriangleMesh>, params: &OctreeParams) -> Result<Octree, BuildError> {
    let n = mesh.len();
    let triangles: Vec<MollerTriangle> = (0..n)
        .into_par_iter()
        .map(|i| MollerTriangle::new(&mesh.triangle(i)))
        .collect();
    let root = root_box(&mesh.bounds());
    let fixed_bytes =
        n as u64 * (std::mem::size_of::<MollerTriangle>() + std::mem::size_of::<Aabb>()) as u64;
    let ctx = Ctx {
        mesh,
        bounds: (0..n)
            .into_par_iter()
            .map(|i| mesh.triangle(i).bounds())
            .collect(),
        params,
        live_refs: AtomicU64::new(n as u64),
        nodes: AtomicU64::new(1),
        fixed_bytes,
    };
    if ctx.bytes() > params.memory_limit_bytes {
        return Err(too_large(ctx.bytes(), params));
    }
    let mut nodes = Vec::new();
    let mut refs = Vec::new();
    if n > 0 {
        // Every triangle lies in the root (non-finite ones never reach a mesh).
        let all: Vec<u32> = (0..n as u32)
            .filter(|&p| {
                let b = &ctx.bounds[p as usize];
                b.min.cmple(b.max).all()
            })
            .collect();
        let tree = build_node(&ctx, root.min, root.max, all, 0)?;
        let count = ctx.nodes.load(Ordering::Relaxed) as usize;
        nodes.reserve_exact(count);
        nodes.push(Node::default());
        refs.reserve_exact(ctx.live_refs.load(Ordering::Relaxed) as usize);
        flatten(&tree, 0, &mut nodes, &mut refs);
    }
    let stats = stats(&nodes, refs.len(), n, params);
    Ok(Octree {
        name: params.name(),
        params: params.clone(),
        root_box: root,
        nodes,
        refs,
        triangles,
        stats,
        mesh: mesh.clone(),
    })
}

fn too_large(needed_bytes: u64, params: &OctreeParams) -> BuildError {
    BuildError::TooLarge {
        needed_bytes,
        limit_bytes: params.memory_limit_bytes,
    }
}

fn build_node(
    ctx: &Ctx<'_>,
    lo: Vec3,
    hi: Vec3,
    prims: Vec<u32>,
    depth: u32,
) -> Result<BuildNode, BuildError> {
    let n = prims.len();
    if n <= ctx.params.max_obj as usize || depth >= ctx.params.max_depth {
        return Ok(BuildNode::Leaf(prims));
    }
    let m = mid(lo, hi);
    if (0..3).any(|a| !(lo[a] < m[a] && m[a] < hi[a])) {
        return Ok(BuildNode::Leaf(prims)); // too small to split in f32
    }
    let octant = (hi - lo) * 0.5;
    let fits = |p: u32| {
        let small = ctx.bounds[p as usize].extent().cmple(octant);
        small.x as u8 + small.y as u8 + small.z as u8 >= 2
    };
    if !prims.iter().any(|&p| fits(p)) {
        // Every triangle is larger than an octant on two axes at least: each passes through
        // several, and splitting can only follow their shared edges and corners downwards.
        return Ok(BuildNode::Leaf(prims));
    }
    let boxes: [(DVec3, DVec3); 8] = std::array::from_fn(|o| {
        let (clo, chi) = child_box(lo, hi, m, o as u32);
        enlarged(clo, chi)
    });
    let mut lists: [Vec<u32>; 8] = Default::default();
    for &p in &prims {
        let b = &ctx.bounds[p as usize];
        let (blo, bhi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let mut tb: Option<TriBox> = None;
        for (o, &(clo, chi)) in boxes.iter().enumerate() {
            if !(blo.cmple(chi).all() && bhi.cmpge(clo).all()) {
                continue;
            }
            let inside = blo.cmpge(clo).all() && bhi.cmple(chi).all();
            if inside
                || tb
                    .get_or_insert_with(|| TriBox::new(&ctx.mesh.triangle(p as usize)))
                    .plane_and_edges_overlap(clo, chi)
            {
                lists[o].push(p);
            }
        }
    }
    if lists.iter().filter(|l| l.len() == n).count() >= 2 {
        // No progress: two octants or more would each get every triangle — they all meet at
        // a point, along an edge or on a face the split plane cannot separate them from.
        return Ok(BuildNode::Leaf(prims));
    }
    let added: u64 = lists.iter().map(|l| l.len() as u64).sum();
    if ctx.params.traversal_cost as f64 + added as f64 / 4.0 >= n as f64 {
        return Ok(BuildNode::Leaf(prims)); // splitting would cost more than it saves
    }
    let present = lists.iter().filter(|l| !l.is_empty()).count() as u64;
    ctx.live_refs.fetch_add(added, Ordering::Relaxed);
    ctx.live_refs.fetch_sub(n as u64, Ordering::Relaxed);
    ctx.nodes.fetch_add(present, Ordering::Relaxed);
    drop(prims);
    if ctx.bytes() > ctx.params.memory_limit_bytes {
        return Err(too_large(ctx.bytes(), ctx.params));
    }
    let work: Vec<(u8, Vec<u32>)> = lists
        .into_iter()
        .enumerate()
        .filter(|(_, l)| !l.is_empty())
        .map(|(o, l)| (o as u8, l))
        .collect();
    let child = |(o, list): (u8, Vec<u32>)| {
        let (clo, chi) = child_box(lo, hi, m, o as u32);
        build_node(ctx, clo, chi, list, depth + 1).map(|c| (o, c))
    };
    let children = if n > ctx.params.parallel_threshold as usize {
        work.into_par_iter()
            .map(child)
            .collect::<Result<Vec<_>, _>>()?
    } else {
        work.into_iter().map(child).collect::<Result<Vec<_>, _>>()?
    };
    Ok(BuildNode::Interior { mid: m, children })
}

/// Writes `node` at `nodes[at]`, its children contiguously after everything written so far.
fn flatten(node: &BuildNode, at: usize, nodes: &mut Vec<Node>, refs: &mut Vec<u32>) {
    match node {
        BuildNode::Leaf(list) => {
            nodes[at] = Node::leaf(refs.len() as u32, list.len() as u32);
            refs.extend_from_slice(list);
        }
        BuildNode::Interior { mid, children } => {
            let first = nodes.len();
            nodes.resize(first + children.len(), Node::default());
            let mask = children.iter().fold(0u8, |m, (o, _)| m | 1 << o);
            nodes[at] = Node::interior(*mid, first as u32, mask);
            for (j, (_, c)) in children.iter().enumerate() {
                flatten(c, first + j, nodes, refs);
            }
        }
    }
}

fn stats(nodes: &[Node], refs: usize, n: usize, params: &OctreeParams) -> BuildStats {
    let mut leaves = 0u64;
    let mut max_depth = 0u32;
    let mut max_leaf = 0usize;
    let mut at_max_depth = 0u64;
    if !nodes.is_empty() {
        let mut todo = vec![(0usize, 0u32)];
        while let Some((i, d)) = todo.pop() {
            let node = &nodes[i];
            max_depth = max_depth.max(d);
            if node.is_leaf() {
                leaves += 1;
                max_leaf = max_leaf.max(node.refs().len());
                at_max_depth += (d == params.max_depth) as u64;
            } else {
                let first = node.first_child() as usize;
                for j in 0..node.mask().count_ones() as usize {
                    todo.push((first + j, d + 1));
                }
            }
        }
    }
    let mut extra = BTreeMap::new();
    extra.insert(
        "refs_per_triangle".into(),
        if n == 0 { 0.0 } else { refs as f64 / n as f64 },
    );
    extra.insert(
        "refs_per_leaf".into(),
        if leaves == 0 {
            0.0
        } else {
            refs as f64 / leaves as f64
        },
    );
    extra.insert("max_refs_per_leaf".into(), max_leaf as f64);
    extra.insert("leaves_at_max_depth".into(), at_max_depth as f64);
    extra.insert("max_obj".into(), params.max_obj as f64);
    extra.insert("max_depth_limit".into(), params.max_depth as f64);
    BuildStats {
        nodes: nodes.len() as u64,
        leaves,
        max_depth,
        refs: refs as u64,
        sah_cost: None,
        extra,
    }
}
