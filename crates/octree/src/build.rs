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
//! Sorting a node's triangles into octants is most of the build, so it does as little as it can:
//! per axis the triangle's bounds against the split plane (widened by the largest margin) rule
//! out the halves it cannot touch, so a triangle inside one octant meets one box; a box that
//! contains the triangle's bounds, or one of its corners, takes it without the 13-axis test,
//! which runs only for triangles crossing a box with no corner in it. The outcome is exactly
//! the full test's against every octant. Nodes over [`OctreeParams::parallel_threshold`]
//! triangles sort them in chunks on rayon tasks (concatenated in order, so the tree does not
//! depend on the thread count) and build their children on tasks.
//!
//! MAX_DEPTH adapts to the scene unless the user sets it ([`adaptive_depth_limit`]): at least
//! [`DEPTH_FLOOR`], deeper when the smallest triangles need it, so a 1 cm teapot in a 1 km
//! stadium is cut down to its own scale instead of stopping with hundreds of triangles a leaf.
//!
//! Built as a boxed tree, then flattened: the present children of a node contiguous, leaves'
//! references in depth-first order.

use crate::node::{MAX_DEPTH_LIMIT, Node, child_box, mid};
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
    /// Nodes at this depth are leaves ([`adaptive_depth_limit`]).
    depth_limit: u32,
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
    let bounds: Vec<Aabb> = (0..n)
        .into_par_iter()
        .map(|i| mesh.triangle(i).bounds())
        .collect();
    let depth_limit = params
        .max_depth
        .unwrap_or_else(|| adaptive_depth_limit(&root, &bounds));
    let ctx = Ctx {
        mesh,
        bounds,
        params,
        live_refs: AtomicU64::new(n as u64),
        nodes: AtomicU64::new(1),
        fixed_bytes,
        depth_limit,
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
    let stats = stats(&nodes, &refs, &ctx.bounds, n, params, depth_limit);
    Ok(Octree {
        name: params.name(),
        params: params.clone(),
        depth_limit,
        root_box: root,
        nodes,
        refs,
        triangles,
        stats,
        mesh: mesh.clone(),
    })
}

/// The default MAX_DEPTH, from the scene's extent: [`DEPTH_FLOOR`], or deeper when the
/// scene's smallest triangle (its largest side; points ignored) is finer than cells at that
/// depth, down to one level past cells of its size, at most [`MAX_DEPTH_LIMIT`]: a tiny object
/// in a huge scene is subdivided down to its own scale. Never shallower than the floor: long
/// thin triangles (a fan of needles) separate well below their own length.
pub fn adaptive_depth_limit(root: &Aabb, bounds: &[Aabb]) -> u32 {
    let smallest = bounds
        .par_iter()
        .map(|b| b.extent().max_element())
        .filter(|&e| e > 0.0)
        .reduce(|| f32::INFINITY, f32::min);
    let extent = root.extent().max_element();
    if !(smallest.is_finite() && extent > 0.0) {
        return DEPTH_FLOOR;
    }
    let levels = (extent as f64 / smallest as f64).log2().ceil() + 1.0;
    (levels.min(MAX_DEPTH_LIMIT as f64) as u32).max(DEPTH_FLOOR)
}

/// 20: the textbook octree's MAX_DEPTH here (2^-20 of a 1 km root is 1 mm). Most scenes stop
/// on the split rules well above it.
pub const DEPTH_FLOOR: u32 = 20;

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
    if n <= ctx.params.max_obj as usize || depth >= ctx.depth_limit {
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
    let split = Split::new(lo, hi, m);
    let lists = if n > ctx.params.parallel_threshold as usize {
        // Chunks in order, concatenated in order: the same lists as the serial loop.
        let parts: Vec<[Vec<u32>; 8]> = prims
            .par_chunks(CLASSIFY_CHUNK)
            .map(|chunk| split.classify(ctx, chunk))
            .collect();
        let mut lists: [Vec<u32>; 8] = Default::default();
        for (o, list) in lists.iter_mut().enumerate() {
            list.reserve_exact(parts.iter().map(|p| p[o].len()).sum());
            for part in &parts {
                list.extend_from_slice(&part[o]);
            }
        }
        lists
    } else {
        split.classify(ctx, &prims)
    };
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

/// Triangles per rayon task when a large node sorts its triangles into octants.
const CLASSIFY_CHUNK: usize = 4096;

/// Leaves above this many references are counted apart when their triangles do not share a
/// point (a build stat).
const CROWDED: usize = 64;

/// True when the bounding boxes of `prims` have a point in common: no split can separate them
/// there, however deep.
fn share_a_point(bounds: &[Aabb], prims: &[u32]) -> bool {
    let mut lo = Vec3::splat(f32::NEG_INFINITY);
    let mut hi = Vec3::splat(f32::INFINITY);
    for &p in prims {
        let b = &bounds[p as usize];
        lo = lo.max(b.min);
        hi = hi.min(b.max);
    }
    lo.cmple(hi).all()
}

/// The octants in the upper half of axis `a`, as a mask over octant numbers.
const UPPER_ON: [u32; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];

/// One node's split into octants: the eight enlarged child boxes, and per axis the bounds a
/// triangle's box must reach to touch the lower or the upper half of any of them.
struct Split {
    boxes: [(DVec3, DVec3); 8],
    /// Largest coordinate a box touching the lower half may start at, per axis.
    lower_reach: DVec3,
    /// Smallest coordinate a box touching the upper half may end at, per axis.
    upper_reach: DVec3,
}

impl Split {
    fn new(lo: Vec3, hi: Vec3, m: Vec3) -> Split {
        let boxes: [(DVec3, DVec3); 8] = std::array::from_fn(|o| {
            let (clo, chi) = child_box(lo, hi, m, o as u32);
            enlarged(clo, chi)
        });
        // Octant 0 is lower on every axis and octant 7 upper; the margins differ per octant
        // (they follow its coordinates' magnitude), so take the widest reach of all eight.
        let mut lower_reach = DVec3::splat(f64::NEG_INFINITY);
        let mut upper_reach = DVec3::splat(f64::INFINITY);
        for (o, &(clo, chi)) in boxes.iter().enumerate() {
            for a in 0..3 {
                if o & (1 << a) == 0 {
                    lower_reach[a] = lower_reach[a].max(chi[a]);
                } else {
                    upper_reach[a] = upper_reach[a].min(clo[a]);
                }
            }
        }
        Split {
            boxes,
            lower_reach,
            upper_reach,
        }
    }

    /// The octants each of `prims` goes into, in the order of `prims`. Per axis the bounds
    /// rule out the halves a triangle cannot touch, so most triangles meet one or two boxes;
    /// those are tested exactly: untested when the triangle's box lies inside, the 13-axis
    /// test otherwise.
    fn classify(&self, ctx: &Ctx<'_>, prims: &[u32]) -> [Vec<u32>; 8] {
        let mut lists: [Vec<u32>; 8] = Default::default();
        for &p in prims {
            let b = &ctx.bounds[p as usize];
            let (blo, bhi) = (b.min.as_dvec3(), b.max.as_dvec3());
            // The octants whose halves the bounds reach on every axis (bit `o` for octant `o`).
            let mut candidates = 0xffu32;
            for a in 0..3 {
                if blo[a] > self.lower_reach[a] {
                    candidates &= UPPER_ON[a];
                }
                if bhi[a] < self.upper_reach[a] {
                    candidates &= !UPPER_ON[a];
                }
            }
            let mut tb: Option<TriBox> = None;
            while candidates != 0 {
                let o = candidates.trailing_zeros() as usize;
                candidates &= candidates - 1;
                let (clo, chi) = self.boxes[o];
                if !(blo.cmple(chi).all() && bhi.cmpge(clo).all()) {
                    continue;
                }
                let inside = blo.cmpge(clo).all() && bhi.cmple(chi).all();
                if inside || {
                    // A corner inside the box settles it; the 13-axis test only for
                    // triangles that cross the box without a corner in it.
                    let t = tb.get_or_insert_with(|| TriBox::new(&ctx.mesh.triangle(p as usize)));
                    t.vertices()
                        .iter()
                        .any(|v| v.cmpge(clo).all() && v.cmple(chi).all())
                        || t.plane_and_edges_overlap(clo, chi)
                } {
                    lists[o].push(p);
                }
            }
        }
        lists
    }
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

fn stats(
    nodes: &[Node],
    refs: &[u32],
    bounds: &[Aabb],
    n: usize,
    params: &OctreeParams,
    depth_limit: u32,
) -> BuildStats {
    let mut leaves = 0u64;
    let mut max_depth = 0u32;
    let mut max_leaf = 0usize;
    let mut at_max_depth = 0u64;
    let mut crowded_apart = 0u64;
    if !nodes.is_empty() {
        let mut todo = vec![(0usize, 0u32)];
        while let Some((i, d)) = todo.pop() {
            let node = &nodes[i];
            max_depth = max_depth.max(d);
            if node.is_leaf() {
                leaves += 1;
                max_leaf = max_leaf.max(node.refs().len());
                at_max_depth += (d == depth_limit) as u64;
                let list = &refs[node.refs()];
                crowded_apart += (list.len() > CROWDED && !share_a_point(bounds, list)) as u64;
            } else {
                let first = node.first_child() as usize;
                for j in 0..node.mask().count_ones() as usize {
                    todo.push((first + j, d + 1));
                }
            }
        }
    }
    let refs = refs.len();
    let mut extra = BTreeMap::new();
    // Leaves no split could thin out are expected; these could have been.
    extra.insert(
        "leaves_over_64_not_sharing_a_point".into(),
        crowded_apart as f64,
    );
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
    extra.insert("max_depth_limit".into(), depth_limit as f64);
    BuildStats {
        nodes: nodes.len() as u64,
        leaves,
        max_depth,
        refs: refs as u64,
        sah_cost: None,
        extra,
    }
}
