//! raybench-bvh: binary bounding volume hierarchies over triangles.
//!
//! Built over one array of primitive records partitioned in place (each node owns a range;
//! see [`build`]), sequential subtrees written straight into depth-first node vectors that are
//! joined once; the result is a depth-first array of 64-byte nodes (each holding both
//! children's boxes, laid out for one SIMD slab test per axis) with the triangles reordered into
//! leaf order, and traversed
//! from that flat form (`traverse`). Five registered variants share the code:
//!
//! | name | builder | traversal |
//! |---|---|---|
//! | `bvh-median` | object median on the longest centroid axis | ordered |
//! | `bvh-sweep` | full-sweep SAH | ordered |
//! | `bvh-binned` | binned SAH (Wald 2007) | ordered |
//! | `bvh-binned-unordered` | binned SAH | fixed child order |
//! | `bvh-binned-reinsert` | binned SAH, then reinsertion ([`build::reinsert`]) | ordered |

pub mod build;
mod cover;
mod grain;
mod node;
mod point;
mod simd;
mod traverse;
mod validate;
pub mod wide;

pub use build::SpatialSplits;
pub use build::reinsert::{ReinsertStats, Reinsertion};
pub use node::{ChildRef, MAX_DEPTH, Node};
pub use wide::{
    Bvh4, Bvh8, Bvh8Compressed, Bvh8Compressed16, Bvh16, BvhQuantized, BvhWide, Collapse,
    NodeFormat, NodeSimd, PacketFloors, WideParams,
};

use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, Walk};
use raybench_geom::{MollerTriangle, Ray, TriangleMesh};
use serde::Serialize;
use std::sync::Arc;

/// How the tree is split.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Builder {
    Median,
    Sweep,
    #[default]
    Binned,
}

/// The named knobs of a BVH, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BvhParams {
    pub builder: Builder,
    /// Bins per axis for the binned builder (at most; see `triangles_per_bin`). 32: a lower
    /// SAH cost than 8 or 16 for a few percent more build time (measured: see
    /// docs/experiments.md, "32 bins, against 8 and 16").
    pub bins: u32,
    /// A node gets one bin per this many triangles (at least 2, at most `bins`): 1 gives a small
    /// node a candidate between every two centroids.
    pub triangles_per_bin: u32,
    /// SAH cost of stepping through a node, for the builder's split decisions.
    pub traversal_cost: f32,
    /// SAH cost of one ray–triangle test, for the builder's split decisions.
    pub intersection_cost: f32,
    /// Triangles tested together in a leaf (1: one at a time; 4: the wide BVH's [`Tri4`]s).
    /// The SAH prices a leaf by the blocks it fills, so a leaf of 3 costs as much as one of 4.
    ///
    /// [`Tri4`]: raybench_geom::Tri4
    pub leaf_block: u32,
    /// A node with more triangles than this is always split (if its triangles can be told
    /// apart at all; see `build`).
    pub max_leaf_size: u32,
    /// Visit the nearer child first and skip subtrees beyond the closest hit.
    pub ordered: bool,
    /// Ranges larger than this are built on two rayon tasks. With several threads, a small
    /// mesh's ranges are split from fewer triangles than this, down to 256, so that every
    /// thread gets a share; the tree is the same either way.
    pub parallel_threshold: u32,
    /// The build refuses with [`BuildError::TooLarge`] when its estimate of the memory it
    /// needs (taken before allocating anything) exceeds this.
    pub memory_limit_bytes: u64,
    /// Optimize the built tree by reinsertion (see [`build::reinsert`]) before it is flattened
    /// for traversal or collapsed into wide nodes; `None`: the builder's tree as it is.
    pub reinsertion: Option<Reinsertion>,
    /// Spatial splits (a Split BVH, see `build/spatial`): `None` builds object splits only.
    pub spatial_splits: Option<SpatialSplits>,
    /// Children of at least this many triangles take their centroid bounds from their boxes
    /// (known from the bins: twice the box, clipped to the parent's centroid bounds) instead of
    /// a pass over their records. Such bounds hold every centroid but are looser where the
    /// triangles are large beside the node, which costs little in large nodes; `None`: a pass
    /// for every child.
    pub centroids_from_boxes: Option<u32>,
}

impl Default for BvhParams {
    fn default() -> Self {
        BvhParams::binned()
    }
}

impl BvhParams {
    /// 8 GiB, as the grid and octree use: a third of the project machine's memory.
    pub const MEMORY_LIMIT: u64 = 8 << 30;

    pub fn binned() -> BvhParams {
        BvhParams {
            builder: Builder::Binned,
            bins: 32,
            triangles_per_bin: 1,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            leaf_block: 1,
            max_leaf_size: 8,
            ordered: true,
            parallel_threshold: 4096,
            memory_limit_bytes: BvhParams::MEMORY_LIMIT,
            reinsertion: None,
            spatial_splits: None,
            centroids_from_boxes: None,
        }
    }
    pub fn median() -> BvhParams {
        BvhParams {
            builder: Builder::Median,
            max_leaf_size: 4,
            ..BvhParams::binned()
        }
    }
    pub fn sweep() -> BvhParams {
        BvhParams {
            builder: Builder::Sweep,
            ..BvhParams::binned()
        }
    }
    pub fn binned_unordered() -> BvhParams {
        BvhParams {
            ordered: false,
            ..BvhParams::binned()
        }
    }

    /// The binned builder with spatial splits at their defaults.
    pub fn sbvh() -> BvhParams {
        BvhParams {
            spatial_splits: Some(SpatialSplits::default()),
            ..BvhParams::binned()
        }
    }

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        let base = match self.builder {
            _ if self.spatial_splits.is_some() => "bvh-sbvh",
            Builder::Median => "bvh-median",
            Builder::Sweep => "bvh-sweep",
            Builder::Binned => "bvh-binned",
        };
        let optimized = if self.reinsertion.is_some() {
            "-reinsert"
        } else {
            ""
        };
        if self.ordered {
            format!("{base}{optimized}")
        } else {
            format!("{base}-unordered{optimized}")
        }
    }
}

/// A flattened BVH: nodes depth-first (a node's first child follows it), triangles in leaf
/// order in Embree's precomputed layout, and each one's index in the original mesh.
#[derive(Debug)]
pub struct Bvh {
    name: String,
    params: BvhParams,
    nodes: Vec<Node>,
    /// The whole tree: an interior node, or for tiny meshes a single leaf.
    root: ChildRef,
    root_bounds: raybench_geom::Aabb,
    triangles: Vec<MollerTriangle>,
    prim_ids: Vec<u32>,
    /// What spatial splits did (`None` without them).
    spatial: Option<build::SpatialReport>,
    /// The mesh as built, for closest-point queries (exact vertices, not the ray layout's
    /// rounded edges).
    mesh: Arc<TriangleMesh>,
    /// What the reinsertion optimizer did, when it ran.
    reinsertion: Option<ReinsertStats>,
}

impl Bvh {
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    pub fn params(&self) -> &BvhParams {
        &self.params
    }

    /// Checks the invariants (see `validate`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        validate::validate(self, mesh)
    }
}

impl Accel for Bvh {
    type Params = BvhParams;

    fn build(mesh: Arc<TriangleMesh>, params: &BvhParams) -> Result<Bvh, BuildError> {
        if params.bins < 2 || params.max_leaf_size < 1 {
            return Err(BuildError::Unsupported(format!(
                "bins >= 2 and max_leaf_size >= 1 (got {params:?})"
            )));
        }
        let (flat, reinsertion) = build::reinsert::optimize(build::build(&mesh, params)?, params);
        let prim_ids = flat.prim_ids();
        let triangles = prim_ids
            .iter()
            .map(|&i| MollerTriangle::new(&mesh.triangle(i as usize)))
            .collect();
        Ok(Bvh {
            name: params.name(),
            params: params.clone(),
            nodes: flat.nodes,
            root: flat.root,
            root_bounds: flat.root_bounds,
            triangles,
            prim_ids,
            spatial: flat.spatial,
            mesh,
            reinsertion,
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        if self.triangles.is_empty() {
            return BuildStats::default();
        }
        let mut stats = build::Shape::measure(&self.nodes, self.root, &self.root_bounds);
        if let Some(r) = &self.reinsertion {
            r.insert_into(&mut stats.extra);
        }
        build::spatial_stats(&mut stats, self.spatial, self.mesh.len());
        stats
    }

    fn memory(&self) -> Memory {
        Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            indices: std::mem::size_of_val(self.prim_ids.as_slice()) as u64,
            primitives: std::mem::size_of_val(self.triangles.as_slice()) as u64,
        }
    }
}

impl Walk for Bvh {
    /// Any hit needs no order: the first hit ends the walk.
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        if !ANY_HIT && self.params.ordered {
            self.trace::<ANY_HIT, true, C>(ray, c)
        } else {
            self.trace::<ANY_HIT, false, C>(ray, c)
        }
    }

    fn walk_point<C: CounterSink>(
        &self,
        p: raybench_geom::Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<raybench_accel::PointHit> {
        point::closest_point_binary(self, p, max_radius, c)
    }
}
