//! The name → structure registry. Adding a structure to raybench means one `register` line here
//! (see README, "Adding a structure"); a program that depends on raybench-harness adds its own
//! to a [`Registry`] instead (see README, "Benchmark your own structure").

mod limits;
mod program;

pub use program::{RegisterError, Registry};

use limits::limited;

use raybench_accel::{Accel, BruteForce, BruteForceParams, BuildError};
use raybench_bvh::{
    Bvh, Bvh4, Bvh8, Bvh8Compressed, Bvh8Compressed16, Bvh16, BvhParams, NodeFormat, PacketFloors,
    Reinsertion, WideParams,
};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::{TriangleMesh, TriangleTest};
use raybench_grid::{Grid, Grid2, Grid2Params, GridParams, SkipGrid, SkipGridParams};
use raybench_kdtree::{KdParams, KdTree};
use raybench_octree::{Octree, OctreeParams};
use std::sync::Arc;

/// What a build may depend on besides the mesh.
#[derive(Clone, Copy, Debug)]
pub struct BuildContext {
    /// Worker threads of this run (Embree's device gets `threads=N`; our builders use the
    /// rayon pool they run in).
    pub threads: usize,
    /// The most memory one build may take: each of our builders estimates what it needs
    /// before allocating and refuses with "scene too large" past this (its
    /// `memory_limit_bytes`); Embree's device refuses the allocation that would pass it.
    pub memory_limit_bytes: u64,
}

impl BuildContext {
    /// `threads` workers, and a memory limit of half of this machine's memory (its cgroup's
    /// limit where lower), at most the 8 GiB every builder defaults to (`registry/limits.rs`).
    pub fn new(threads: usize) -> Self {
        BuildContext {
            threads,
            memory_limit_bytes: limits::for_this_machine(),
        }
    }
}

/// A built structure and its parameters, as written into the report.
pub struct Built {
    pub accel: Box<dyn Accel>,
    pub params: serde_json::Value,
}

impl std::fmt::Debug for Built {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Built")
            .field("accel", &self.accel.name())
            .field("params", &self.params)
            .finish()
    }
}

type Builder = dyn Fn(Arc<TriangleMesh>, &BuildContext) -> Result<Built, BuildError> + Send + Sync;

#[derive(Clone)]
pub struct StructureEntry {
    pub name: &'static str,
    pub description: &'static str,
    /// Suites skip the structure above this many triangles (it would take too long); naming the
    /// structure explicitly with `--structures` always runs it.
    pub suite_triangle_limit: Option<usize>,
    /// Another crate's structure wrapped for comparison (`peer-*`), not one of raybench's own:
    /// `raybench list` shows these under their own heading.
    pub peer: bool,
    /// Added by the program running raybench ([`Registry::register`]), not built in: `raybench
    /// list` shows these under their own heading.
    pub registered: bool,
    builder: Arc<Builder>,
}

impl std::fmt::Debug for StructureEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StructureEntry")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// Whether a structure named in a report is a peer (another crate's structure): reports keep
/// names only, and every peer's name starts with `peer-`.
pub fn is_peer_name(structure: &str) -> bool {
    structure.starts_with("peer-")
}

impl StructureEntry {
    pub fn build(&self, mesh: Arc<TriangleMesh>, ctx: &BuildContext) -> Result<Built, BuildError> {
        (self.builder)(mesh, ctx)
    }

    /// Brute force: every ray tests every triangle, so its cost per ray grows with the scene
    /// and `verify` traces it on a budgeted subsample only.
    pub fn is_exhaustive(&self) -> bool {
        self.suite_triangle_limit == Some(BRUTE_FORCE_SUITE_LIMIT)
    }
}

pub(crate) fn register<A: Accel + 'static>(
    name: &'static str,
    description: &'static str,
    suite_triangle_limit: Option<usize>,
    params: impl Fn(&BuildContext) -> A::Params + Send + Sync + 'static,
) -> StructureEntry {
    let builder = move |mesh: Arc<TriangleMesh>, ctx: &BuildContext| {
        let p = params(ctx);
        let params = serde_json::to_value(&p).map_err(|e| BuildError::Backend(e.to_string()))?;
        Ok(Built {
            accel: Box::new(A::build(mesh, &p)?),
            params,
        })
    };
    StructureEntry {
        name,
        description,
        suite_triangle_limit,
        peer: false,
        registered: false,
        builder: Arc::new(builder),
    }
}

/// An Embree entry: Embree's own threads set to the run's, and the run's memory limit enforced
/// through the device's memory monitor (which counts what the build allocates, other Embree
/// entries' scenes on the device left out, as our builders' limits count their own build), so a
/// scene too large for the machine is an error in the report, not the kernel killing the run.
fn embree(base: EmbreeParams) -> impl Fn(&BuildContext) -> EmbreeParams + Send + Sync {
    move |ctx| EmbreeParams {
        threads: ctx.threads,
        memory_limit_bytes: Some(ctx.memory_limit_bytes),
        ..base.clone()
    }
}

/// Brute force tests every triangle: 20k triangles × 100k rays is already 2e9 tests per pass.
const BRUTE_FORCE_SUITE_LIMIT: usize = 20_000;

/// Every structure raybench itself knows, in the order reports list them: what
/// [`Registry::builtin`] starts from.
pub fn registry() -> Vec<StructureEntry> {
    #[cfg_attr(not(feature = "peers"), allow(unused_mut))]
    let mut all = own_structures();
    #[cfg(feature = "peers")]
    all.extend(crate::peers::entries());
    all
}

fn own_structures() -> Vec<StructureEntry> {
    vec![
        register::<BruteForce>(
            "bruteforce",
            "every triangle for every ray (Möller–Trumbore): the O(N) oracle",
            Some(BRUTE_FORCE_SUITE_LIMIT),
            |_| BruteForceParams {
                triangle_test: TriangleTest::MollerTrumbore,
            },
        ),
        register::<BruteForce>(
            "bruteforce-watertight",
            "every triangle for every ray (Woop–Benthin–Wald watertight test)",
            Some(BRUTE_FORCE_SUITE_LIMIT),
            |_| BruteForceParams {
                triangle_test: TriangleTest::Watertight,
            },
        ),
        register::<Bvh>(
            "bvh-median",
            "binary BVH, object median on the longest axis (the baseline), ordered traversal",
            None,
            limited(|_| BvhParams::median()),
        ),
        register::<Bvh>(
            "bvh-sweep",
            "binary BVH, full-sweep SAH (every split position, per axis), ordered traversal",
            None,
            limited(|_| BvhParams::sweep()),
        ),
        register::<Bvh>(
            "bvh-binned",
            "binary BVH, binned SAH (Wald 2007, 32 bins), ordered traversal",
            None,
            limited(|_| BvhParams::binned()),
        ),
        register::<Bvh>(
            "bvh-binned-reinsert",
            "the bvh-binned tree optimized by batched reinsertion (as bvh8-reinsert's binary tree), ordered traversal",
            None,
            limited(|_| BvhParams {
                reinsertion: Some(Reinsertion::default()),
                ..BvhParams::binned()
            }),
        ),
        register::<Bvh>(
            "bvh-binned-unordered",
            "the bvh-binned tree traversed in fixed child order (what ordering saves)",
            None,
            limited(|_| BvhParams::binned_unordered()),
        ),
        register::<Bvh4>(
            "bvh4-binned",
            "4-wide BVH collapsed from a binned SAH tree priced for SIMD 4-triangle leaves (empty slots filled by splitting leaves), 4-lane box test of 4 children, AVX2 leaves test two Tri4s a pass (AVX-512 registers when present, SSE fallback), ordered",
            None,
            limited(|_| WideParams::for_width(4)),
        ),
        register::<Bvh8>(
            "bvh8-binned",
            "8-wide BVH collapsed from a binned SAH tree priced for SIMD 4-triangle leaves (empty slots filled by splitting leaves), AVX2 box test of 8 children and leaves test two Tri4s a pass (AVX-512 registers when present, SSE fallback), ordered",
            None,
            limited(|_| WideParams::for_width(8)),
        ),
        register::<Bvh16>(
            "bvh16-binned",
            "the bvh8-binned build and leaves collapsed into 16-wide nodes (512 bytes, eight cache lines; the SAH-optimal collapse plans 16 slots): a quarter fewer node steps a ray, one 16-lane AVX-512 box test per axis (two AVX2 passes without AVX-512F), ordered",
            None,
            limited(|_| WideParams::for_width(16)),
        ),
        register::<Bvh16>(
            "bvh16-sbvh",
            "the bvh16-binned walk and leaves over bvh8-sbvh's Split BVH (the same binary tree, collapsed into 16-wide nodes)",
            None,
            limited(|_| WideParams {
                width: 16,
                ..WideParams::sbvh()
            }),
        ),
        register::<Bvh8>(
            "bvh8-reinsert",
            "the bvh8-binned configuration with its binary tree optimized by batched reinsertion before the collapse (Bittner et al. 2013, Meister and Bittner 2018): per round the 1 % of nodes with the largest boxes (skipping those that found no better place before) each moved to where the SAH cost falls most, at most 16 rounds, until a round gains under 0.1 %",
            None,
            limited(|_| {
                let mut p = WideParams::for_width(8);
                p.binary.reinsertion = Some(Reinsertion::default());
                p
            }),
        ),
        register::<Bvh8>(
            "bvh8-sbvh",
            "the bvh8-binned walk and leaves over a Split BVH (Stich et al. 2009): binned object splits weighed against spatial splits that cut triangles at one of 15 slab planes per axis (16 slabs) (chopped binning, reference unsplitting), tried where the object split's children overlap by more than 1e-4 of the root's area and by at least 0.3 of the node's own, priced with a triangle test at 0.3 of a node step, references capped at 1.5 × the triangles",
            None,
            limited(|_| WideParams::sbvh()),
        ),
        register::<Bvh8>(
            "bvh8-sbvh-reinsert",
            "bvh8-sbvh's Split BVH optimized by bvh8-reinsert's reinsertion before the collapse (both techniques together: what they buy combined)",
            None,
            limited(|_| {
                let mut p = WideParams::sbvh();
                p.binary.reinsertion = Some(Reinsertion::default());
                p
            }),
        ),
        register::<Bvh8>(
            "bvh8-packets",
            "the bvh8-binned tree; coherent batches (primary rays for closest hit, shadow rays for any hit) traced sixteen consecutive rays a packet, one per AVX-512 lane (two packets of eight AVX2 lanes on a CPU without AVX-512F), but where a packet's walk shares few nodes and triangles among its rays, the next packets of its 256 rays ray by ray; every other batch ray by ray as bvh8-binned",
            None,
            limited(|_| WideParams {
                coherent_packets: true,
                packet_floors: PacketFloors::MEASURED,
                ..WideParams::for_width(8)
            }),
        ),
        register::<Bvh8>(
            "bvh8-sbvh-packets",
            "bvh8-sbvh's Split BVH traced as bvh8-packets traces: coherent batches (primary rays for closest hit, shadow rays for any hit) sixteen consecutive rays a packet, every other batch ray by ray (both techniques together: what they buy combined)",
            None,
            limited(|_| WideParams {
                coherent_packets: true,
                packet_floors: PacketFloors::MEASURED,
                ..WideParams::sbvh()
            }),
        ),
        register::<Bvh16>(
            "bvh16-sbvh-packets",
            "bvh16-sbvh's tree traced as bvh8-packets traces: coherent batches (primary rays for closest hit, shadow rays for any hit) sixteen consecutive rays a packet over 16-wide nodes, every other batch ray by ray as bvh16-sbvh",
            None,
            limited(|_| WideParams {
                width: 16,
                coherent_packets: true,
                packet_floors: PacketFloors::MEASURED,
                ..WideParams::sbvh()
            }),
        ),
        register::<Bvh8Compressed>(
            "bvh8-compressed",
            "the bvh8-binned tree (same collapse, same Tri4 leaves, same walk) with quantized nodes: per node and axis an f32 origin and a power-of-two step, each child plane one byte rounded outward, 128 bytes a node instead of 256; each plane row decoded in AVX2 registers before the same 8-lane box test",
            None,
            limited(|_| WideParams {
                node_format: NodeFormat::Quantized,
                ..WideParams::for_width(8)
            }),
        ),
        register::<Bvh8Compressed16>(
            "bvh8-compressed16",
            "bvh8-compressed with 16-bit planes: 192 bytes a node (the box test reads 112), boxes grown 257 times less than with bytes",
            None,
            limited(|_| WideParams {
                node_format: NodeFormat::Quantized16,
                ..WideParams::for_width(8)
            }),
        ),
        register::<KdTree>(
            "kd-sah",
            "k-d tree, SAH with perfect splits in O(N log N) (Wald–Havran 2006), termination by cost, leaves of Tri4 copies tested 4 lanes at a time, early exit, mailbox",
            None,
            limited(|_| KdParams::sah()),
        ),
        register::<KdTree>(
            "kd-packets",
            "the kd-sah tree; coherent batches (primary rays for closest hit, shadow rays for any hit) traced sixteen consecutive rays a packet, one per AVX-512 lane (two packets of eight AVX2 lanes on a CPU without AVX-512F; Wald 2004), every other batch ray by ray as kd-sah",
            None,
            limited(|_| KdParams::packets()),
        ),
        register::<KdTree>(
            "kd-sah-exhaustive",
            "the kd-sah tree walked to the end of every ray's segment, no early exit at the first hit (what stopping saves; same answers)",
            None,
            limited(|_| KdParams::exhaustive()),
        ),
        register::<KdTree>(
            "kd-median",
            "k-d tree, spatial median with round-robin axes (the baseline), early exit, mailbox",
            None,
            limited(|_| KdParams::median()),
        ),
        register::<Grid>(
            "grid-coarse",
            "uniform grid, λ = 1/8 cells per triangle (too few cells), exact insertion, 3D-DDA",
            None,
            limited(|_| GridParams::coarse()),
        ),
        register::<Grid>(
            "grid",
            "uniform grid, λ = 1 cell per triangle (Cleary–Wyvill), exact insertion, 3D-DDA, mailboxing, 4-wide tests",
            None,
            limited(|_| GridParams::default()),
        ),
        register::<Grid>(
            "grid-fine",
            "uniform grid, λ = 8 cells per triangle (too many cells), exact insertion, 3D-DDA",
            None,
            limited(|_| GridParams::fine()),
        ),
        register::<SkipGrid>(
            "grid-skip",
            "the λ = 1 uniform grid plus a distance field (per cell, the Chebyshev distance in cells to the nearest non-empty cell; Cohen–Sheffer proximity clouds): rays jump over the empty block around a cell 4 or more cells from a non-empty one, answers and triangle tests identical to grid's",
            None,
            limited(|_| SkipGridParams::default()),
        ),
        register::<Grid2>(
            "grid2",
            "hierarchical grid: the λ = 1 grid, whose cells of more than 8 triangles hold grids of λ = 2 over their triangles' extent where a cost model says a ray gains, 3 levels (Jevans–Wyvill; Kalojanov et al. 2011), exact insertion, 3D-DDA at every level, one mailbox",
            None,
            limited(|_| Grid2Params::default()),
        ),
        register::<Octree>(
            "octree",
            "octree, MAX_OBJ 8, MAX_DEPTH from the scene (at least 20, down to its smallest triangles, at most 32), exact insertion sorted on both cores, front-to-back (parametric) traversal with mailboxing",
            None,
            limited(|_| OctreeParams::default()),
        ),
        register::<EmbreeScene>(
            "embree-low",
            "Embree 3 BVH, RTC_BUILD_QUALITY_LOW (fast build)",
            None,
            embree(EmbreeParams::low()),
        ),
        register::<EmbreeScene>(
            "embree-medium",
            "Embree 3 BVH, RTC_BUILD_QUALITY_MEDIUM (Embree's default; the reference)",
            None,
            embree(EmbreeParams::medium()),
        ),
        register::<EmbreeScene>(
            "embree-medium-stream",
            "embree-medium; coherent closest-hit batches (primary rays) traced through rtcIntersect1M with RTC_INTERSECT_CONTEXT_FLAG_COHERENT (Embree's own packets), every other batch (shadow rays too) as embree-medium",
            None,
            embree(EmbreeParams::medium_stream()),
        ),
        register::<EmbreeScene>(
            "embree-medium-packet16",
            "embree-medium; coherent closest-hit batches (primary rays) traced through rtcIntersect16 with RTC_INTERSECT_CONTEXT_FLAG_COHERENT, sixteen consecutive rays a packet as bvh8-packets takes them (laid out outside timing, missing lanes of a last packet masked invalid), every other batch as embree-medium (shadow rays through rtcOccluded1: rtcOccluded16 misreports rays in a triangle's plane)",
            None,
            embree(EmbreeParams::medium_packet16()),
        ),
        register::<EmbreeScene>(
            "embree-medium-avx2",
            "embree-medium on Embree's AVX2 kernels (isa=avx2) instead of the widest the CPU has: what Embree's own choice of kernels buys on this machine, and a race on the instructions the 8-wide trees' walks use",
            None,
            embree(EmbreeParams::medium_on("avx2")),
        ),
        register::<EmbreeScene>(
            "embree-high",
            "Embree 3 BVH, RTC_BUILD_QUALITY_HIGH (spatial splits)",
            None,
            embree(EmbreeParams::high()),
        ),
        register::<EmbreeScene>(
            "embree-robust",
            "Embree 3 BVH, medium quality with RTC_SCENE_FLAG_ROBUST (watertight Plücker test)",
            None,
            embree(EmbreeParams::robust()),
        ),
    ]
}
