//! Wide BVHs — 8 children per node ([`Bvh8`]), 4 ([`Bvh4`]) or 16 ([`Bvh16`]) — collapsed from
//! the binary SAH tree, traversed with one SIMD box test per node (see docs/results/ for where
//! they stand against Embree).
//!
//! Collapse (`collapse.rs`): by default each wide node's children are chosen for the least SAH cost
//! of the whole wide tree, by dynamic programming over the binary tree (`optimal.rs`,
//! [`Collapse::Optimal`], as in Ylitie, Karras and Laine 2017); the greedy collapse of Wald et al.
//! 2008 ("Getting rid of packets") and Embree's BVH4/BVH8 builders ([`Collapse::Greedy`]) starts
//! from a binary node's two children and repeatedly opens the child with the largest surface area
//! until it has `W` children or only leaves remain. Either way, slots still empty are then filled
//! by splitting the largest leaves of more than one `Tri4` in two (`fill_slots`, as Embree's
//! builder splits every child until the node is full). The wide tree has about a third (8 wide) or
//! half (4 wide) of the binary tree's depth, so a ray walks fewer, wider nodes: fewer dependent
//! memory fetches. The trade-off between the widths: a 4-wide node is two cache lines and one
//! 4-lane SSE test per axis, an 8-wide node four lines and one 8-lane AVX2 test, a 16-wide node
//! eight lines and one 16-lane AVX-512 test (two AVX2 passes without AVX-512F), and fewer of them
//! on a ray's path: a quarter fewer node steps at 16 than at 8 on the race suite.
//!
//! Traversal (`walk.rs`) is ordered: the children a ray enters are sorted by entry distance,
//! the farther ones pushed with that distance and skipped when popped beyond the closest hit.
//! Every child entered is prefetched before the ordering, so the fetch of the subtrees pushed
//! for later overlaps the walk below the nearest.
//!
//! Leaves are [`Tri4`]s (`pack.rs`): the binary builder prices a leaf by the `Tri4`s it fills
//! (`leaf_block = 4`), and one SSE Möller–Trumbore test answers for four triangles; with AVX2
//! a leaf's `Tri4`s are tested two at a time, eight lanes a pass (`avx2/`), with the same
//! answers. An 8-wide node is tested in one 8-lane AVX2 pass per axis when the CPU has AVX2
//! (detected at build time) and in two 4-lane SSE passes otherwise (`kernels.rs`); every
//! kernel is the scalar slab test lane for lane and passes the same conformance tests.
//! Coherent batches may be traced in packets, for closest or any hit: sixteen rays a packet
//! with AVX-512F (`packets.rs`), eight with AVX2 alone (`packets8.rs`).
//!
//! Caveat: the collapse only regroups the binary builder's partitions (and splits leaves), so
//! the wide tree is as good as the binary SAH build under it; and the knobs
//! ([`WideParams::default`]) are tuned for the 8-wide AVX2 walk on the project machine.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod collapse;
#[cfg(target_arch = "x86_64")]
mod frustum;
mod kernels;
mod node;
mod optimal;
mod pack;
#[cfg(target_arch = "x86_64")]
mod packet_node;
#[cfg(target_arch = "x86_64")]
mod packet_switch;
#[cfg(target_arch = "x86_64")]
mod packets;
#[cfg(target_arch = "x86_64")]
mod packets8;
mod params;
mod quantized;
mod stats;
mod validate;
mod walk;

pub use node::WideNode;
pub use params::{Collapse, NodeFormat, NodeSimd, PacketFloors, WideParams};
pub use quantized::{Bvh8Compressed, Bvh8Compressed16, BvhQuantized, node::Plane, node::QNode};

pub(crate) use node::quad;
pub(crate) use walk::{STACK, with_stack};

use crate::build;
use crate::node::ChildRef;
use collapse::{Binary, collapse_tree};
use pack::{fill_tri4s, number_tri4s};
use raybench_accel::{
    Accel, BuildError, BuildStats, CounterSink, Hit, Memory, NoCount, PreparedRays, Walk,
};
#[cfg(target_arch = "x86_64")]
use raybench_geom::PacketWalk;
use raybench_geom::{Aabb, Ray, RayError, Tri4, TriangleMesh, Vec3};
use std::sync::Arc;

/// The widest node built (and the size of every traversal stack).
pub const MAX_WIDTH: usize = 16;

/// A wide BVH of `W`-child nodes. A leaf reference is `{ index: first Tri4, count:
/// triangles }`; its triangles fill `count.div_ceil(4)` consecutive `Tri4`s, lane by lane.
#[derive(Debug)]
pub struct BvhWide<const W: usize> {
    params: WideParams,
    nodes: Vec<WideNode<W>>,
    root: ChildRef,
    root_bounds: Aabb,
    /// Leaf triangles, four to a `Tri4`, each lane with its mesh index
    /// ([`NO_PRIM`](raybench_geom::NO_PRIM) unused).
    tri4s: Vec<Tri4>,
    /// What spatial splits did (`None` without them).
    spatial: Option<build::SpatialReport>,
    /// The mesh as built, for closest-point queries (exact vertices).
    mesh: Arc<TriangleMesh>,
    #[cfg(target_arch = "x86_64")]
    avx2: Option<avx2::Avx2Nodes>,
    /// The packet walk for coherent batches, when asked for and the CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    coherent: Option<PacketWalk>,
    /// What the reinsertion optimizer did to the binary tree, when it ran.
    reinsertion: Option<crate::ReinsertStats>,
}

/// 8 children per node, tested in one AVX2 pass per axis: the structure that races Embree.
pub type Bvh8 = BvhWide<8>;
/// 4 children per node, tested in one SSE pass per axis: half the node bytes, twice the depth.
pub type Bvh4 = BvhWide<4>;
/// 16 children per node, tested in one AVX-512 pass per axis: twice the node bytes, three
/// quarters of the depth.
pub type Bvh16 = BvhWide<16>;

impl<const W: usize> BvhWide<W> {
    pub fn nodes(&self) -> &[WideNode<W>] {
        &self.nodes
    }

    /// The root: a node, or a leaf when the tree is a single leaf.
    pub(crate) fn root(&self) -> ChildRef {
        self.root
    }

    /// The leaves' `Tri4`s, in depth-first order.
    pub fn tri4s(&self) -> &[Tri4] {
        &self.tri4s
    }

    /// The parts the closest-point walk reads (`point.rs`).
    pub(crate) fn point_view(&self) -> crate::point::WideView<'_, W> {
        crate::point::WideView {
            root: self.root,
            root_bounds: &self.root_bounds,
            nodes: &self.nodes,
            tri4s: &self.tri4s,
            mesh: &self.mesh,
        }
    }

    pub fn params(&self) -> &WideParams {
        &self.params
    }

    /// Whether the AVX2 kernels test nodes and leaves (else SSE).
    pub fn uses_avx2(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.avx2.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// Whether coherent batches are traced in packets (`coherent_packets` asked for it and the
    /// CPU has AVX2).
    pub fn packet_walk(&self) -> bool {
        self.packet_lanes().is_some()
    }

    /// The rays a packet holds when coherent batches are traced in packets: 16 with AVX-512F,
    /// 8 with AVX2 alone or `NodeSimd::Avx2`.
    pub fn packet_lanes(&self) -> Option<usize> {
        #[cfg(target_arch = "x86_64")]
        return self.coherent.map(PacketWalk::lanes);
        #[cfg(not(target_arch = "x86_64"))]
        None
    }

    /// Whether the batch loops run with AVX-512VL's 32 vector registers (same arithmetic).
    pub fn avx512_registers(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.avx2.is_some_and(|k| k.wide_registers());
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}

/// [`Accel`]'s methods, for the widths that implement it (below).
impl<const W: usize> BvhWide<W> {
    fn build_wide(mesh: Arc<TriangleMesh>, params: &WideParams) -> Result<BvhWide<W>, BuildError> {
        if params.width as usize != W {
            return Err(BuildError::Unsupported(format!(
                "width {} in a {W}-wide BVH",
                params.width
            )));
        }
        if params.node_format != NodeFormat::Float {
            return Err(BuildError::Unsupported(
                "quantized nodes in a float BVH (see BvhQuantized)".into(),
            ));
        }
        let built = build::build(&mesh, &params.binary)?;
        let (mut flat, reinsertion) = build::reinsert::optimize(built, &params.binary);
        // The collapse leaves the leaves as triangle ranges; their `Tri4`s are numbered
        // afterwards and filled in parallel.
        let (nodes, root, leaves) = if flat.refs.is_empty() {
            (Vec::new(), ChildRef::default(), Vec::new())
        } else {
            let optimal = params.collapse == Collapse::Optimal;
            let binary = Binary::new(
                &flat.nodes,
                params.fill_slots,
                optimal.then_some(&params.binary),
            );
            let (mut nodes, mut root) = collapse_tree(&binary, &mut flat.refs, flat.root);
            let leaves = number_tri4s(&mut nodes, &mut root);
            (nodes, root, leaves)
        };
        let tri4s = fill_tri4s(&mesh, &flat.refs, &leaves);
        Ok(BvhWide {
            params: params.clone(),
            nodes,
            root,
            root_bounds: flat.root_bounds,
            tri4s,
            spatial: flat.spatial,
            mesh,
            #[cfg(target_arch = "x86_64")]
            avx2: match params.node_simd {
                NodeSimd::Auto => avx2::Avx2Nodes::detect(true),
                NodeSimd::Avx2 => avx2::Avx2Nodes::detect(false),
                NodeSimd::Sse => None,
            },
            #[cfg(target_arch = "x86_64")]
            coherent: params
                .coherent_packets
                // Eight lanes where the node kernels are held to AVX2, so that an AVX-512 CPU
                // runs (and tests) the AVX2 walk too.
                .then(|| PacketWalk::detect(params.node_simd != NodeSimd::Avx2))
                .flatten(),
            reinsertion,
        })
    }

    /// The registered names. A 4-wide tree or a 16-wide binned tree with `coherent_packets` is
    /// registered nowhere; the packet walk runs on it all the same (the conformance tests check
    /// it), under its tree's name.
    fn registered_name(&self) -> &'static str {
        match (W, self.params.coherent_packets) {
            (8, false)
                if self.params.binary.spatial_splits.is_some()
                    && self.params.binary.reinsertion.is_some() =>
            {
                "bvh8-sbvh-reinsert"
            }
            (8, false) if self.params.binary.spatial_splits.is_some() => "bvh8-sbvh",
            (8, true) if self.params.binary.spatial_splits.is_some() => "bvh8-sbvh-packets",
            (4, _) => "bvh4-binned",
            (16, true) if self.params.binary.spatial_splits.is_some() => "bvh16-sbvh-packets",
            (16, _) if self.params.binary.spatial_splits.is_some() => "bvh16-sbvh",
            (16, _) => "bvh16-binned",
            (_, false) if self.params.binary.reinsertion.is_some() => "bvh8-reinsert",
            (_, false) => "bvh8-binned",
            (_, true) => "bvh8-packets",
        }
    }

    /// With the packet walk, the rays are laid out in packets of sixteen, structure of arrays
    /// (as Embree's stream takes `RTCRayHit`s, converted outside timing); without it, as they
    /// are.
    fn prepare_coherent(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
        #[cfg(target_arch = "x86_64")]
        if self.coherent.is_some() {
            return Ok(raybench_accel::coherent::prepare_packets(rays));
        }
        Ok(PreparedRays::Native)
    }

    fn intersect_batch(
        &self,
        rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(walk) = self.coherent
            && let Some(packets) =
                raybench_accel::coherent::packet_blocks(prepared, first, out.len())
        {
            let rays = &rays[first..];
            return match walk {
                PacketWalk::Avx512(k) => {
                    packets::intersect_coherent(k, self, packets, rays, first, out)
                }
                PacketWalk::Avx2(k) => {
                    packets8::intersect_coherent(k, self, packets, rays, first, out)
                }
            };
        }
        let rays = &rays[first..];
        with_stack(|stack| {
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = self.avx2 {
                return avx2::intersect_all(self, k, rays, out, stack);
            }
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = self.trace::<false, _>(ray, stack, &mut NoCount);
            }
        })
    }

    fn occluded_batch(
        &self,
        rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [bool],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(walk) = self.coherent
            && let Some(packets) =
                raybench_accel::coherent::packet_blocks(prepared, first, out.len())
        {
            let rays = &rays[first..];
            return match walk {
                PacketWalk::Avx512(k) => {
                    packets::occluded_coherent(k, self, packets, rays, first, out)
                }
                PacketWalk::Avx2(k) => {
                    packets8::occluded_coherent(k, self, packets, rays, first, out)
                }
            };
        }
        let rays = &rays[first..];
        with_stack(|stack| {
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = self.avx2 {
                return avx2::occluded_all(self, k, rays, out, stack);
            }
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = self.trace::<true, _>(ray, stack, &mut NoCount).is_some();
            }
        })
    }

    fn stats_with_splits(&self) -> BuildStats {
        let mut stats = self.measure();
        build::spatial_stats(&mut stats, self.spatial, self.mesh.len());
        stats
    }

    fn memory_held(&self) -> Memory {
        Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            // Triangle ids live in the `Tri4`s.
            indices: 0,
            primitives: std::mem::size_of_val(self.tri4s.as_slice()) as u64,
        }
    }
}

/// [`Accel`] for each width the node tests are made for (4, 8 and 16; no other width has it),
/// one impl per width rather than one generic impl: the walks and the build are then compiled
/// in this crate, with its optimisation, not in whichever crate first names a width (the
/// harness's test build is unoptimised, and its tests trace through these trees).
macro_rules! accel_for_widths {
    ($($w:literal)*) => {$(
        impl Accel for BvhWide<$w> {
            type Params = WideParams;

            fn build(mesh: Arc<TriangleMesh>, params: &WideParams) -> Result<Self, BuildError> {
                Self::build_wide(mesh, params)
            }

            fn name(&self) -> &str {
                self.registered_name()
            }

            raybench_accel::walk_queries!();

            fn prepare_coherent_rays(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
                self.prepare_coherent(rays)
            }

            fn intersect_prepared(
                &self,
                rays: &[Ray],
                prepared: &PreparedRays,
                first: usize,
                out: &mut [Option<Hit>],
            ) {
                self.intersect_batch(rays, prepared, first, out)
            }

            fn occluded_prepared(
                &self,
                rays: &[Ray],
                prepared: &PreparedRays,
                first: usize,
                out: &mut [bool],
            ) {
                self.occluded_batch(rays, prepared, first, out)
            }

            fn build_stats(&self) -> BuildStats {
                self.stats_with_splits()
            }

            fn memory(&self) -> Memory {
                self.memory_held()
            }
        }
    )*};
}

accel_for_widths!(4 8 16);

impl<const W: usize> Walk for BvhWide<W> {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace_single::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<raybench_accel::PointHit> {
        crate::point::closest_point_wide(&self.point_view(), p, max_radius, c)
    }
}
