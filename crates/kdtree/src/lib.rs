//! raybench-kdtree: k-d trees (axis-aligned BSP trees) over triangles.
//!
//! A k-d tree partitions space, not primitives: its cells do not overlap, so traversal walks
//! them strictly front to back and may stop at the first cell that yields a hit, at the price
//! of triangles referenced by every cell they cross. Built in place into a depth-first array of
//! 8-byte nodes plus one reference array ([`build`], [`Node`]), traversed from that flat form
//! with a small on-stack mailbox (`traverse.rs` has the details). Closest-point queries walk
//! the same tree nearest child first, pruned by the distance to each cell (`points.rs`); the
//! zero-area triangles rays never hit live in a side tree only they walk. The registered
//! variants share the code:
//!
//! | name | builder | reference |
//! |---|---|---|
//! | `kd-sah` | SAH with perfect splits, event sweep, O(N log N) | Wald and Havran 2006 |
//! | `kd-median` | spatial median, round-robin axes | the textbook baseline |
//! | `kd-packets` | `kd-sah`, coherent batches walked sixteen rays at a time (`packets.rs`; eight with AVX2 alone, `packets8.rs`) | Wald 2004 |
//! | `kd-sah-exhaustive` | `kd-sah`, walked without early exit: what stopping at the first hit saves | — |
#![deny(unsafe_code)] // allowed only in the packet walks, `packets.rs` and `packets8.rs`

pub mod build;
pub mod clip;
mod node;
#[cfg(target_arch = "x86_64")]
mod packets;
#[cfg(target_arch = "x86_64")]
mod packets8;
mod points;
mod traverse;
mod validate;

pub use node::{MAX_DEPTH, Node};

use build::Selection;
use raybench_accel::{
    Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, PreparedRays, Walk,
};
#[cfg(target_arch = "x86_64")]
use raybench_geom::PacketWalk;
use raybench_geom::{Aabb, Ray, RayError, Tri4, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// How split planes are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Builder {
    /// Surface area heuristic over every candidate plane of the clipped triangle bounds.
    #[default]
    Sah,
    /// The middle of the cell, axes in turn (x, y, z, x, …; a flat axis is skipped).
    Median,
}

/// The named knobs of a k-d tree, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KdParams {
    pub builder: Builder,
    /// SAH cost of stepping through an interior node (`K_T`), for the builder's decisions.
    pub traversal_cost: f32,
    /// SAH cost of one ray–triangle test (`K_I`), for the builder's decisions. The ratio to
    /// `traversal_cost` is what matters; see [`KdParams::sah`] for where it was measured.
    pub intersection_cost: f32,
    /// Factor on the cost of a split that leaves one side empty (Wald and Havran's `λ`): below
    /// 1 it rewards cutting off empty space. 1 disables it.
    pub empty_bonus: f32,
    /// Deepest leaf; `None` means Havran's `round(8 + 1.3 log2 N)` for cost-driven splits,
    /// past which cells of more than 64 triangles are still cut while a plane separates them
    /// (down to [`MAX_DEPTH`]). A value set here is a hard limit. Never more than [`MAX_DEPTH`].
    pub max_depth: Option<u32>,
    /// A node with at most this many triangles is a leaf without trying any split. The SAH
    /// builder also stops whenever no split is cheaper than intersecting every triangle.
    pub leaf_size: u32,
    /// Trace coherent batches (`Accel::prepare_coherent_rays`: camera rays in scanline order,
    /// and the shadow rays from their hits) as packets of sixteen rays on CPUs with AVX-512F,
    /// of eight on CPUs with AVX2 alone, for closest or any hit; other batches and other CPUs
    /// take the single-ray walk.
    pub packets: bool,
    /// Record tested triangles in a small per-ray table so a triangle referenced by several
    /// leaves is tested once (skips are counted as `mailbox_skips`).
    pub mailbox: bool,
    /// Stop a closest-hit walk once no pending cell can hold a nearer hit (the k-d tree's
    /// early termination). Off only in `kd-sah-exhaustive`, which walks every cell the ray's
    /// segment crosses, to measure what stopping saves; answers are the same either way.
    pub early_exit: bool,
    /// Nodes with more triangles than this build their two subtrees on two rayon tasks (near
    /// the root only: a handful of tasks per worker thread).
    pub parallel_threshold: u32,
    /// The build refuses with [`BuildError::TooLarge`] when the memory it needs before the
    /// first reference (triangle copies, event scratch) exceeds this, and otherwise gives the
    /// tree only as many references as fit within it (see `build::Share`).
    pub memory_limit_bytes: u64,
}

impl Default for KdParams {
    fn default() -> Self {
        KdParams::sah()
    }
}

impl KdParams {
    /// 8 GiB: a third of this VM's memory, as the grid and octree use.
    pub const MEMORY_LIMIT: u64 = 8 << 30;

    /// `kd-sah`. `K_I / K_T = 0.25`: a leaf tests four triangles in one Tri4 pass that costs
    /// about one node step, so a triangle costs about a quarter of a step. Measured in
    /// interleaved rounds against 0.75 (the best value when leaves were tested one triangle at a
    /// time), 0.5, 0.15 and 0.1 on the bunny, Sponza, conference, teapot and generated scenes of
    /// other kinds and sizes (hair, city, terrain, soup, a 200k sphere): against 0.75, random
    /// rays 5–45 % faster on every scene, primary rays level or faster but on Sponza (−9 %, and
    /// −10 % as packets),
    /// builds 1.3–1.9× faster with a quarter to a half of the nodes; lower values build faster
    /// still but lose packets on Sponza and the city. `λ = 0.8` (Wald and Havran's) against no
    /// bonus; `leaf_size = 0`, as 1 and 2 changed nothing (the cost decides). See
    /// docs/experiments.md, k-d tree.
    pub fn sah() -> KdParams {
        KdParams {
            builder: Builder::Sah,
            traversal_cost: 1.0,
            intersection_cost: 0.25,
            empty_bonus: 0.8,
            max_depth: None,
            leaf_size: 0,
            packets: false,
            mailbox: true,
            early_exit: true,
            parallel_threshold: 16_384,
            memory_limit_bytes: KdParams::MEMORY_LIMIT,
        }
    }

    /// `kd-median`: cells cut in the middle, axes in turn, leaves of at most 4 triangles (or at
    /// the depth limit, which the median tree reaches on every real scene: it is the baseline,
    /// not tuned).
    pub fn median() -> KdParams {
        KdParams {
            builder: Builder::Median,
            leaf_size: 4,
            ..KdParams::sah()
        }
    }

    /// `kd-packets`: `kd-sah` with coherent batches traced as packets.
    pub fn packets() -> KdParams {
        KdParams {
            packets: true,
            ..KdParams::sah()
        }
    }

    /// `kd-sah-exhaustive`: the `kd-sah` tree walked without early termination.
    pub fn exhaustive() -> KdParams {
        KdParams {
            early_exit: false,
            ..KdParams::sah()
        }
    }

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        let base = match (self.builder, self.packets) {
            (Builder::Sah, true) => "kd-packets",
            (Builder::Sah, false) => "kd-sah",
            (Builder::Median, true) => "kd-median-packets",
            (Builder::Median, false) => "kd-median",
        };
        let base = if self.early_exit {
            base.to_string()
        } else {
            format!("{base}-exhaustive")
        };
        if self.mailbox {
            base
        } else {
            format!("{base}-nomailbox")
        }
    }
}

/// A flattened k-d tree: nodes depth-first, one reference array with each leaf padded to a
/// multiple of four, and beside it the leaves' triangles four to a [`Tri4`] in Embree's
/// precomputed layout (`build/pack.rs`).
#[derive(Debug)]
pub struct KdTree {
    name: String,
    params: KdParams,
    nodes: Vec<Node>,
    /// Leaf contents: slots (`prim_ids[slot]` is the mesh index), each leaf a contiguous range
    /// starting at a multiple of four and padded with `build::pack::PAD`.
    refs: Vec<u32>,
    /// The triangles of `refs`, lane for lane: reference `r` is lane `r % 4` of Tri4 `r / 4`,
    /// with the mesh index as its id.
    tri4s: Vec<Tri4>,
    prim_ids: Vec<u32>,
    /// The root cell: the bounds of every referenced triangle.
    bounds: Aabb,
    /// The deepest leaf may lie this deep: the resolved `max_depth`, or deeper where cells of
    /// more than `build::LARGE_LEAF` triangles were cut past it (sizes the traversal stacks).
    depth_limit: u32,
    stats: BuildStats,
    /// Which triangles this tree holds: the hittable ones, or (the side tree) the zero-area ones.
    selection: Selection,
    /// The mesh, for the exact vertices closest-point queries need (the stored triangles are
    /// in Möller–Trumbore's edge form, which does not give the vertices back bit for bit).
    mesh: Arc<TriangleMesh>,
    /// The zero-area triangles rays never hit, in a tree of their own that only closest-point
    /// queries walk (`None` when the mesh has none; see [`build`]).
    zero_area: Option<Box<KdTree>>,
    /// Set when coherent batches are traced as packets (`packets` and AVX2 detected).
    #[cfg(target_arch = "x86_64")]
    coherent: Option<PacketWalk>,
}

impl KdTree {
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    pub fn refs(&self) -> &[u32] {
        &self.refs
    }

    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    pub fn params(&self) -> &KdParams {
        &self.params
    }

    pub fn bounds(&self) -> &Aabb {
        &self.bounds
    }

    /// Whether coherent batches are traced as packets (`packets` set and AVX2 present).
    pub fn packet_walk(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.coherent.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// Checks the invariants (see `validate.rs`): structure, split planes inside their cells,
    /// and every triangle referenced by exactly the leaves its clipped bounds reach.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        validate::validate(self, mesh)
    }
}

impl Accel for KdTree {
    type Params = KdParams;

    fn build(mesh: Arc<TriangleMesh>, params: &KdParams) -> Result<KdTree, BuildError> {
        let ok = |x: f32| x.is_finite() && x >= 0.0;
        if !(ok(params.traversal_cost)
            && params.intersection_cost.is_finite()
            && params.intersection_cost > 0.0
            && ok(params.empty_bonus))
        {
            return Err(BuildError::Unsupported(format!(
                "costs must be finite and non-negative and intersection_cost > 0 (got {params:?})"
            )));
        }
        // The side tree of zero-area triangles is built beside the main one.
        let has_zero_area = mesh.triangles().any(|t| Selection::ZeroArea.holds(&t));
        let (tree, side) = rayon::join(
            || KdTree::from_flat(&mesh, params, Selection::Hittable),
            || {
                has_zero_area
                    .then(|| KdTree::from_flat(&mesh, params, Selection::ZeroArea))
                    .transpose()
            },
        );
        let mut tree = tree?;
        if let Some(side) = side? {
            let extra = &mut tree.stats.extra;
            extra.insert("zero_area_tree_nodes".into(), side.stats.nodes as f64);
            extra.insert("zero_area_tree_refs".into(), side.stats.refs as f64);
            tree.zero_area = Some(Box::new(side));
        }
        Ok(tree)
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        self.stats.clone()
    }

    fn prepare_coherent_rays(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
        #[cfg(target_arch = "x86_64")]
        if self.coherent.is_some() {
            return Ok(raybench_accel::coherent::prepare_packets(rays));
        }
        self.prepare_rays(rays)
    }

    fn intersect_prepared(
        &self,
        rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(walk) = self.coherent
            && let Some(blocks) =
                raybench_accel::coherent::packet_blocks(prepared, first, out.len())
        {
            let rays = &rays[first..];
            return match walk {
                PacketWalk::Avx512(k) => packets::intersect_coherent(k, self, rays, blocks, out),
                PacketWalk::Avx2(k) => packets8::intersect_coherent(k, self, rays, blocks, out),
            };
        }
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.intersect(ray);
        }
    }

    fn occluded_prepared(
        &self,
        rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [bool],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(walk) = self.coherent
            && let Some(blocks) =
                raybench_accel::coherent::packet_blocks(prepared, first, out.len())
        {
            let rays = &rays[first..];
            return match walk {
                PacketWalk::Avx512(k) => packets::occluded_coherent(k, self, rays, blocks, out),
                PacketWalk::Avx2(k) => packets8::occluded_coherent(k, self, rays, blocks, out),
            };
        }
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.occluded(ray);
        }
    }

    /// Both trees; the mesh the point queries read vertices from is the caller's, not counted.
    fn memory(&self) -> Memory {
        let own = Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            indices: (std::mem::size_of_val(self.refs.as_slice())
                + std::mem::size_of_val(self.prim_ids.as_slice())) as u64,
            primitives: std::mem::size_of_val(self.tri4s.as_slice()) as u64,
        };
        match &self.zero_area {
            None => own,
            Some(side) => {
                let s = side.memory();
                Memory {
                    nodes: own.nodes + s.nodes,
                    indices: own.indices + s.indices,
                    primitives: own.primitives + s.primitives,
                }
            }
        }
    }
}

impl KdTree {
    /// Builds the tree over the `selection` of the mesh and flattens it.
    fn from_flat(
        mesh: &Arc<TriangleMesh>,
        params: &KdParams,
        selection: Selection,
    ) -> Result<KdTree, BuildError> {
        let flat = build::build(mesh, params, selection)?;
        Ok(KdTree {
            name: params.name(),
            params: params.clone(),
            nodes: flat.nodes,
            refs: flat.refs,
            tri4s: flat.tri4s,
            prim_ids: flat.prim_ids,
            bounds: flat.bounds,
            depth_limit: flat.deepest,
            stats: flat.stats,
            selection,
            mesh: mesh.clone(),
            zero_area: None,
            #[cfg(target_arch = "x86_64")]
            coherent: params.packets.then(|| PacketWalk::detect(true)).flatten(),
        })
    }
}

impl Walk for KdTree {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        match (self.params.mailbox, self.params.early_exit) {
            (true, true) => self.trace::<ANY_HIT, true, true, C>(ray, c),
            (false, true) => self.trace::<ANY_HIT, false, true, C>(ray, c),
            (true, false) => self.trace::<ANY_HIT, true, false, C>(ray, c),
            (false, false) => self.trace::<ANY_HIT, false, false, C>(ray, c),
        }
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.closest(p, max_radius, c)
    }
}
