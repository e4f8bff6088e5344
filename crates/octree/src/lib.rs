//! raybench-octree: an octree over triangles.
//!
//! A cube around the scene is split recursively into eight octants at its centre while a node
//! holds more than [`OctreeParams::max_obj`] triangles, down to at most
//! [`OctreeParams::max_depth`] levels — by default a limit derived from the scene, deep enough
//! for its smallest triangles ([`build::adaptive_depth_limit`]); each triangle goes into exactly
//! the octants its exact triangle–box test ([`raybench_geom::tribox`]) says it overlaps
//! ([`build`]; large nodes sort their triangles on both cores). Nodes are
//! flattened into one array (the present children of a node contiguous, in octant order; empty
//! octants are not stored) and one reference array. Rays visit the octants they pierce front to
//! back — at each node the ray's crossings of the three centre planes, sorted, give the
//! children in the order the ray enters them — and stop at the first leaf whose exit lies at
//! or beyond the closest hit, testing each triangle once thanks to a small mailbox
//! (`traverse`). Closest-point queries descend nearest octant first and skip every octant
//! farther than the nearest triangle found so far (`points.rs`).
//!
//! Against the uniform grid: the octree adapts its cell size to where the triangles are, so a
//! teapot in a stadium is subdivided down to its own scale while the empty stands stay coarse;
//! the price is a descent from the root for every leaf instead of a constant-time DDA step.
#![forbid(unsafe_code)]

pub mod build;
mod node;
mod points;
mod traverse;
mod validate;

pub use node::{MAX_DEPTH_LIMIT, Node};

use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, Walk};
use raybench_geom::{Aabb, MollerTriangle, Ray, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// The named knobs of an octree, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OctreeParams {
    /// MAX_OBJ: a node with at most this many triangles is a leaf.
    pub max_obj: u32,
    /// MAX_DEPTH: nodes at this depth are leaves whatever they hold (at most
    /// [`MAX_DEPTH_LIMIT`], which sizes the traversal stack). `None`: from the scene, one level
    /// past the cells as small as its smallest triangle ([`build::adaptive_depth_limit`]).
    pub max_depth: Option<u32>,
    /// Cost of visiting a node relative to one ray–triangle test, in the split rule: a node is
    /// split only when `traversal_cost + (references in its octants) / 4 < references`. A ray
    /// crossing a cube visits octants with 1/4 of its surface area each, so after a split it
    /// tests about a quarter of the octants' references (the surface-area heuristic for a
    /// fixed split). This is what stops triangles that every central octant shares —
    /// concentric, crossing, or two triangles along a shared edge when MAX_OBJ is 1 — from
    /// duplicating themselves down to MAX_DEPTH.
    pub traversal_cost: f32,
    /// The build refuses with [`BuildError::TooLarge`] when the references, nodes and triangle
    /// copies it holds would exceed this (checked at every split) instead of running out of
    /// memory.
    pub memory_limit_bytes: u64,
    /// Nodes with more triangles than this are split on two rayon tasks.
    pub parallel_threshold: u32,
}

impl OctreeParams {
    /// 8: the customary value, not tuned.
    pub const MAX_OBJ: u32 = 8;
    /// 8 GiB.
    pub const MEMORY_LIMIT: u64 = 8 << 30;

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        let d = OctreeParams::default();
        if (self.max_obj, self.max_depth, self.traversal_cost)
            == (d.max_obj, d.max_depth, d.traversal_cost)
        {
            "octree".into()
        } else {
            format!(
                "octree-obj{}-depth{}-ct{}",
                self.max_obj,
                self.max_depth.map_or("auto".into(), |d| d.to_string()),
                self.traversal_cost
            )
        }
    }
}

impl Default for OctreeParams {
    fn default() -> Self {
        OctreeParams {
            max_obj: OctreeParams::MAX_OBJ,
            max_depth: None,
            traversal_cost: raybench_accel::SAH_TRAVERSAL_COST as f32,
            memory_limit_bytes: OctreeParams::MEMORY_LIMIT,
            parallel_threshold: 4096,
        }
    }
}

/// A flattened octree: `nodes[0]` is the root, whose box is `root_box`; leaves index `refs`;
/// `triangles[prim]` is mesh triangle `prim` in Embree's precomputed layout.
#[derive(Debug)]
pub struct Octree {
    name: String,
    params: OctreeParams,
    /// The MAX_DEPTH the build used: the user's, or the one it derived from the scene.
    depth_limit: u32,
    root_box: Aabb,
    nodes: Vec<Node>,
    refs: Vec<u32>,
    triangles: Vec<MollerTriangle>,
    stats: BuildStats,
    /// The mesh, for the exact vertices closest-point queries need (the stored triangles are
    /// in Möller–Trumbore's edge form, which does not give the vertices back bit for bit).
    mesh: Arc<TriangleMesh>,
}

impl Octree {
    pub fn params(&self) -> &OctreeParams {
        &self.params
    }

    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The MAX_DEPTH the build used.
    pub fn depth_limit(&self) -> u32 {
        self.depth_limit
    }

    pub fn root_box(&self) -> Aabb {
        self.root_box
    }

    /// Checks the invariants (see `validate`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        validate::validate(self, mesh)
    }
}

impl Accel for Octree {
    type Params = OctreeParams;

    fn build(mesh: Arc<TriangleMesh>, params: &OctreeParams) -> Result<Octree, BuildError> {
        if params.max_depth.is_some_and(|d| d > MAX_DEPTH_LIMIT) {
            return Err(BuildError::Unsupported(format!(
                "max_depth <= {MAX_DEPTH_LIMIT} (got {params:?})"
            )));
        }
        build::build(&mesh, params)
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        self.stats.clone()
    }

    fn memory(&self) -> Memory {
        Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            indices: std::mem::size_of_val(self.refs.as_slice()) as u64,
            primitives: std::mem::size_of_val(self.triangles.as_slice()) as u64,
        }
    }
}

impl Walk for Octree {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.closest(p, max_radius, c)
    }
}
