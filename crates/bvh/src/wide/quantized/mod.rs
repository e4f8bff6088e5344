//! The compressed 8-wide BVHs (`bvh8-compressed`, `bvh8-compressed16`): the `bvh8-binned`
//! tree with every node's child boxes quantized to 8-bit planes (128 bytes a node instead of
//! 256) or 16-bit ones (192 bytes).
//!
//! Algorithm: as the compressed wide BVHs of Ylitie, Karras and Laine ("Efficient incoherent
//! ray traversal on GPUs through compressed wide BVHs", HPG 2017) and Embree's quantized
//! BVH8 nodes, each node stores per axis an origin and a power-of-two step covering the union
//! of its children, and each child plane as an integer counted in steps from the origin,
//! minima rounded down and maxima up, so a decoded box always holds the float box
//! (`node.rs`). The tree, leaves and child order are the float tree's (built by [`Bvh8`] and
//! converted); only the node format differs, so the report isolates what compression buys.
//! The box test decodes a node's planes (one widening conversion, a multiply and an add per
//! plane with AVX2) and runs the float kernel's slab test on them (`kernels.rs`, `walk.rs`).
//!
//! Trade-off: the box test reads one cache line (8 bits) or two (16 bits) instead of three,
//! for six decodes per node test on the walk's critical path; and a rounded-out box lets some
//! rays into children the float box would have kept them out of (more nodes and leaves
//! visited; the closest hit is the same). It can pay only when node fetches miss the caches;
//! measured on the project machine, where the scenes' trees fit in them, both formats are
//! slower than `bvh8-binned` (docs/experiments.md, "Compressed wide BVH"). The ray walk tests
//! the root's children on a float copy of the root node: rounded out, they stick out of the
//! scene's box, and every ray leaving the scene from its outer face (shadow rays from a roof)
//! would walk down to the leaf it starts on. Caveats: below the root, with 8-bit planes a child
//! grows by up to a 255th of its node's extent per side, so a flat leaf box (a wall) gains a
//! thickness and a ray leaving the wall enters the leaf it starts on; the child references are
//! kept whole (8 bytes each) rather than compressed to offsets, which would need each node's
//! children contiguous.

mod kernels;
pub mod node;
mod point;
mod validate;
mod walk;

use super::node::WideNode;
use super::{Bvh8, NodeFormat, WideParams};
use crate::node::ChildRef;
use node::{Plane, QNode, QWIDTH};
use raybench_accel::{
    Accel, BuildError, BuildStats, CounterSink, Hit, Memory, NoCount, PreparedRays, Walk,
};
use raybench_geom::{Aabb, Ray, Tri4, TriangleMesh, Vec3};
use std::sync::Arc;

/// An 8-wide BVH of quantized nodes ([`QNode`]) with planes of type `P`; leaves as
/// [`Bvh8`]'s, a leaf reference is `{ index: first Tri4, count: triangles }`.
#[derive(Debug)]
pub struct BvhQuantized<P: Plane> {
    params: WideParams,
    nodes: Vec<QNode<P>>,
    root: ChildRef,
    /// The root node with its children's boxes in floats, which the ray walk tests instead of
    /// the quantized root (see the module note); all empty slots when the root is a leaf.
    root_node: WideNode<QWIDTH>,
    root_bounds: Aabb,
    tri4s: Vec<Tri4>,
    mesh: Arc<TriangleMesh>,
    /// The float tree's shape and cost (the same tree), with the quantization's figures.
    stats: BuildStats,
    #[cfg(target_arch = "x86_64")]
    avx2: Option<super::avx2::Avx2Nodes>,
}

/// 8-bit planes, 128-byte nodes: the registry's `bvh8-compressed`.
pub type Bvh8Compressed = BvhQuantized<u8>;
/// 16-bit planes, 192-byte nodes: the registry's `bvh8-compressed16`.
pub type Bvh8Compressed16 = BvhQuantized<u16>;

impl<P: Plane> BvhQuantized<P> {
    pub fn nodes(&self) -> &[QNode<P>] {
        &self.nodes
    }

    pub fn tri4s(&self) -> &[Tri4] {
        &self.tri4s
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

    /// Mean over all children of the decoded box's surface area over the float box's: what
    /// the rounding costs in entered boxes (1 would be lossless).
    fn area_growth(float: &Bvh8, nodes: &[QNode<P>]) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for (f, q) in float.nodes().iter().zip(nodes) {
            for i in 0..q.children() {
                let a = f.child_bounds(i).surface_area();
                if a > 0.0 {
                    sum += q.child_bounds(i).surface_area() / a;
                    n += 1;
                }
            }
        }
        if n == 0 { 1.0 } else { sum / n as f64 }
    }
}

/// [`Accel`]'s methods, for the plane types that implement it (below).
impl<P: Plane> BvhQuantized<P> {
    fn build_quantized(
        mesh: Arc<TriangleMesh>,
        params: &WideParams,
    ) -> Result<BvhQuantized<P>, BuildError> {
        if params.node_format != P::FORMAT {
            return Err(BuildError::Unsupported(format!(
                "a {:?} BVH built with node_format = {:?}",
                P::FORMAT,
                params.node_format
            )));
        }
        if params.coherent_packets {
            return Err(BuildError::Unsupported(
                "packets on quantized nodes (the packet walk reads float nodes)".into(),
            ));
        }
        let float = Bvh8::build(
            mesh,
            &WideParams {
                node_format: NodeFormat::Float,
                ..params.clone()
            },
        )?;
        let nodes: Vec<QNode<P>> = {
            use rayon::prelude::*;
            float.nodes().par_iter().map(QNode::quantize).collect()
        };
        // An empty mesh has no nodes and a leaf root none: all slots empty then.
        let root_node = (!float.root.is_leaf())
            .then(|| float.nodes().get(float.root.index as usize).copied())
            .flatten()
            .unwrap_or_else(WideNode::empty);
        let mut stats = float.build_stats();
        stats
            .extra
            .insert("node_bytes".into(), std::mem::size_of::<QNode<P>>() as f64);
        stats
            .extra
            .insert("area_growth".into(), Self::area_growth(&float, &nodes));
        let super::BvhWide {
            root,
            root_bounds,
            tri4s,
            mesh,
            #[cfg(target_arch = "x86_64")]
            avx2,
            ..
        } = float;
        Ok(BvhQuantized {
            params: params.clone(),
            nodes,
            root,
            root_node,
            root_bounds,
            tri4s,
            mesh,
            stats,
            #[cfg(target_arch = "x86_64")]
            avx2,
        })
    }

    fn registered_name(&self) -> &'static str {
        match P::FORMAT {
            NodeFormat::Quantized16 => "bvh8-compressed16",
            _ => "bvh8-compressed",
        }
    }

    fn intersect_batch(&self, rays: &[Ray], first: usize, out: &mut [Option<Hit>]) {
        let rays = &rays[first..];
        super::walk::with_stack(|stack| {
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = self.avx2 {
                return kernels::intersect_all(self, k, rays, out, stack);
            }
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = self.trace::<false, _>(ray, stack, &mut NoCount);
            }
        })
    }

    fn occluded_batch(&self, rays: &[Ray], first: usize, out: &mut [bool]) {
        let rays = &rays[first..];
        super::walk::with_stack(|stack| {
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = self.avx2 {
                return kernels::occluded_all(self, k, rays, out, stack);
            }
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = self.trace::<true, _>(ray, stack, &mut NoCount).is_some();
            }
        })
    }

    fn memory_held(&self) -> Memory {
        Memory {
            nodes: (std::mem::size_of_val(self.nodes.as_slice())
                + std::mem::size_of::<WideNode<QWIDTH>>()) as u64,
            indices: 0,
            primitives: std::mem::size_of_val(self.tri4s.as_slice()) as u64,
        }
    }
}

/// [`Accel`] for each plane type, one impl per type rather than one generic impl, so that the
/// walks are compiled in this crate, with its optimisation (as for [`BvhWide`]).
macro_rules! accel_for_planes {
    ($($p:ty)*) => {$(
        impl Accel for BvhQuantized<$p> {
            type Params = WideParams;

            fn build(mesh: Arc<TriangleMesh>, params: &WideParams) -> Result<Self, BuildError> {
                Self::build_quantized(mesh, params)
            }

            fn name(&self) -> &str {
                self.registered_name()
            }

            raybench_accel::walk_queries!();

            fn intersect_prepared(
                &self,
                rays: &[Ray],
                _: &PreparedRays,
                first: usize,
                out: &mut [Option<Hit>],
            ) {
                self.intersect_batch(rays, first, out)
            }

            fn occluded_prepared(
                &self,
                rays: &[Ray],
                _: &PreparedRays,
                first: usize,
                out: &mut [bool],
            ) {
                self.occluded_batch(rays, first, out)
            }

            fn build_stats(&self) -> BuildStats {
                self.stats.clone()
            }

            fn memory(&self) -> Memory {
                self.memory_held()
            }
        }
    )*};
}

accel_for_planes!(u8 u16);

impl<P: Plane> Walk for BvhQuantized<P> {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace_single::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<raybench_accel::PointHit> {
        self.closest_point_walk(p, max_radius, c)
    }
}
