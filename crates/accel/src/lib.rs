//! raybench-accel: the one trait every structure implements, and what it reports.
//!
//! Small and stable on purpose: every structure crate and the harness depend on it.
//! * [`Accel`]: build, closest hit, any hit, the same two with [`Counters`], stats, memory.
//! * [`Walk`] and [`walk_queries!`]: a structure writes its traversal loops once; the macro
//!   forwards the six query methods of [`Accel`] to them.
//! * [`per_thread_stack!`]: a traversal stack kept per thread, lent to each walk.
//! * [`BruteForce`]: the O(N) oracle every structure is checked against.
//! * [`classify`]: the validation classes (docs/validation.md, Validation classes), deciding
//!   whether two answers agree.
#![forbid(unsafe_code)]

mod brute;
pub mod classify;
pub mod classify_points;
#[cfg(target_arch = "x86_64")]
pub mod coherent;
mod counters;
mod mailbox;
mod nearest;
mod per_thread;
mod uncounted;
mod walk;

pub use brute::{BruteForce, BruteForceParams};
pub use counters::{CounterSink, Counters, NoCount};
pub use mailbox::Mailbox;
pub use nearest::Nearest;
pub use raybench_geom as geom;
pub use walk::Walk;

use raybench_geom::{Ray, TriHit, TriangleMesh, Vec3};
use serde::{Deserialize, Serialize};
use std::any::Any;
use std::collections::BTreeMap;
use std::fmt::Debug;
use std::sync::Arc;

/// The closest (or any) hit of a ray. `prim` indexes the mesh the structure was built from, in
/// its original order, whatever order the structure keeps triangles in internally.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    /// Barycentric weight of the triangle's second vertex (Embree's `u`).
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex (Embree's `v`).
    pub v: f32,
}

impl Hit {
    /// The hit `h` of a ray–triangle test, on mesh triangle `prim`.
    #[inline(always)]
    pub fn from_tri_hit(prim: u32, h: TriHit) -> Hit {
        Hit {
            t: h.t,
            prim,
            u: h.u,
            v: h.v,
        }
    }
}

/// The answer to a closest-point query: the triangle nearest to the query point, the point on
/// it, and the Euclidean distance (`|point - query|`, computed in f32).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointHit {
    pub prim: u32,
    pub point: Vec3,
    pub distance: f32,
}

/// Shape of the built structure, for reports. The SAH cost uses the shared constants
/// ([`SAH_TRAVERSAL_COST`], [`SAH_INTERSECTION_COST`]) so structures are comparable.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildStats {
    pub nodes: u64,
    pub leaves: u64,
    pub max_depth: u32,
    /// Primitive references stored in leaves or cells (duplicates counted).
    pub refs: u64,
    /// SAH cost of the whole structure, where the structure has one.
    pub sah_cost: Option<f64>,
    /// Structure-specific figures (e.g. empty leaves, Embree's commit-only time).
    pub extra: BTreeMap<String, f64>,
}

/// SAH cost of stepping through one node, relative to [`SAH_INTERSECTION_COST`].
pub const SAH_TRAVERSAL_COST: f64 = 1.0;
/// SAH cost of one ray–triangle test.
pub const SAH_INTERSECTION_COST: f64 = 1.0;

/// Bytes a structure holds, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Memory {
    pub nodes: u64,
    pub indices: u64,
    /// Copies of triangle data (precomputed edges, reordered vertices).
    pub primitives: u64,
}

impl Memory {
    pub fn total(&self) -> u64 {
        self.nodes + self.indices + self.primitives
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The build would pass its memory limit, by an estimate made before allocating.
    #[error(
        "scene too large: the build would need about {}, over its memory limit of {}",
        amount(*.needed_bytes),
        amount(*.limit_bytes)
    )]
    TooLarge { needed_bytes: u64, limit_bytes: u64 },
    /// A build that cannot estimate its memory ahead (Embree's) was refused the allocation that
    /// would have taken it to `reached_bytes`, past its memory limit: it needs at least that.
    #[error(
        "scene too large: the build was refused memory at {}, past its memory limit of {}",
        amount(*.reached_bytes),
        amount(*.limit_bytes)
    )]
    MemoryLimitReached {
        reached_bytes: u64,
        limit_bytes: u64,
    },
    #[error("unsupported input: {0}")]
    Unsupported(String),
    #[error("backend error: {0}")]
    Backend(String),
}

/// An amount of memory for a message: in the largest binary unit that keeps it at 1 or more,
/// with two decimals, then the exact count of bytes, so that a need just past a limit still
/// reads as larger than it.
fn amount(bytes: u64) -> String {
    const UNITS: [(&str, u32); 3] = [("GiB", 30), ("MiB", 20), ("KiB", 10)];
    match UNITS.iter().find(|&&(_, shift)| bytes >> shift > 0) {
        Some(&(unit, shift)) => {
            format!(
                "{:.2} {unit} ({bytes} bytes)",
                bytes as f64 / (1u64 << shift) as f64
            )
        }
        None => format!("{bytes} bytes"),
    }
}

/// Rays converted into a structure's own layout, outside any timed region (see
/// [`Accel::prepare_rays`]). `Native` means "trace the `&[Ray]` as they are".
#[derive(Debug)]
pub enum PreparedRays {
    Native,
    Foreign(Box<dyn Any + Send + Sync>),
}

/// An acceleration structure over one triangle mesh.
///
/// Closest hit and any hit both accept a hit at `t` only when `t_min < t <= t_max`.
/// Implementations run one traversal loop for all four queries, generic over "any hit" and a
/// counter sink whose non-counting form ([`NoCount`]) is zero-sized: implement [`Walk`] and
/// write [`walk_queries!`] in the `impl Accel` block.
pub trait Accel: Send + Sync {
    /// Named knobs; written into every report.
    type Params: Default + Clone + Debug + Serialize
    where
        Self: Sized;

    fn build(mesh: Arc<TriangleMesh>, params: &Self::Params) -> Result<Self, BuildError>
    where
        Self: Sized;

    /// Registered name, e.g. `bvh-binned-sah`, `embree-medium`.
    fn name(&self) -> &str;

    /// Closest hit: the timed path.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// Any hit: the timed path.
    fn occluded(&self, ray: &Ray) -> bool;
    /// The same walk as [`Accel::intersect`], counting its work.
    fn intersect_counted(&self, ray: &Ray, c: &mut Counters) -> Option<Hit>;
    fn occluded_counted(&self, ray: &Ray, c: &mut Counters) -> bool;

    /// Closest point: the triangle nearest to `p` within `max_radius` (inclusive:
    /// `distance <= max_radius`), `None` when no triangle is that close. `max_radius` may be
    /// `f32::INFINITY`. Zero-area triangles count (they have points). Every structure keeps its
    /// best answer in a [`Nearest`], so the rules are one: the lower prim index wins a tie, and
    /// a query Embree cannot take (a non-finite point, a coordinate beyond 1.844e18, a negative
    /// or NaN radius) is answered `None`.
    fn closest_point(&self, p: Vec3, max_radius: f32) -> Option<PointHit>;
    /// The same walk as [`Accel::closest_point`], counting nodes, leaves, cells and
    /// point–triangle distance tests (in `prim_tests`).
    fn closest_point_counted(&self, p: Vec3, max_radius: f32, c: &mut Counters)
    -> Option<PointHit>;

    /// Answers `points[first..first + out.len()]` (closest point within `max_radius`): the
    /// timed batch path. One dynamic call per batch, then this structure's own `closest_point`
    /// (statically dispatched), as rays pay through [`Accel::intersect_prepared`].
    fn closest_points(
        &self,
        points: &[Vec3],
        max_radius: f32,
        first: usize,
        out: &mut [Option<PointHit>],
    ) {
        for (o, &p) in out.iter_mut().zip(&points[first..]) {
            *o = self.closest_point(p, max_radius);
        }
    }

    fn build_stats(&self) -> BuildStats;
    fn memory(&self) -> Memory;

    /// False for structures whose work cannot be counted (Embree): reports show no counters.
    fn has_counters(&self) -> bool {
        true
    }

    /// False for structures that cannot answer closest-point queries (some peer crates): runs
    /// then report the closest-point workloads as "not offered" instead of timing them.
    fn offers_closest_point(&self) -> bool {
        true
    }

    /// Converts rays into this structure's layout and checks them; called outside timing.
    fn prepare_rays(&self, _rays: &[Ray]) -> Result<PreparedRays, raybench_geom::RayError> {
        Ok(PreparedRays::Native)
    }

    /// [`Accel::prepare_rays`] for a batch whose consecutive rays are coherent (camera rays in
    /// scanline order, as the `primary` workload makes them): a structure may then trace them
    /// in packets. Embree has the same hint (`RTC_INTERSECT_CONTEXT_FLAG_COHERENT`). The
    /// default ignores it.
    fn prepare_coherent_rays(&self, rays: &[Ray]) -> Result<PreparedRays, raybench_geom::RayError> {
        self.prepare_rays(rays)
    }

    /// Traces `rays[first..first + out.len()]` (closest hit): the timed batch path.
    fn intersect_prepared(
        &self,
        rays: &[Ray],
        _prepared: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.intersect(ray);
        }
    }

    /// Any-hit counterpart of [`Accel::intersect_prepared`].
    fn occluded_prepared(
        &self,
        rays: &[Ray],
        _prepared: &PreparedRays,
        first: usize,
        out: &mut [bool],
    ) {
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.occluded(ray);
        }
    }
}

/// Builds a structure and returns it as a trait object, with its parameters as JSON for reports.
pub fn build_dyn<A: Accel + 'static>(
    mesh: Arc<TriangleMesh>,
    params: &A::Params,
) -> Result<Box<dyn Accel>, BuildError> {
    Ok(Box::new(A::build(mesh, params)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A need just past its limit reads as larger than the limit; small amounts stay in bytes.
    #[test]
    fn too_large_names_both_amounts_in_units_and_bytes() {
        let e = BuildError::TooLarge {
            needed_bytes: 2_147_542_592,
            limit_bytes: 2 << 30,
        };
        assert_eq!(
            e.to_string(),
            "scene too large: the build would need about 2.00 GiB (2147542592 bytes), \
             over its memory limit of 2.00 GiB (2147483648 bytes)"
        );
        let e = BuildError::TooLarge {
            needed_bytes: 5 << 20,
            limit_bytes: 4096,
        };
        assert_eq!(
            e.to_string(),
            "scene too large: the build would need about 5.00 MiB (5242880 bytes), \
             over its memory limit of 4.00 KiB (4096 bytes)"
        );
        let e = BuildError::MemoryLimitReached {
            reached_bytes: 1_073_847_228,
            limit_bytes: 1 << 30,
        };
        assert_eq!(
            e.to_string(),
            "scene too large: the build was refused memory at 1.00 GiB (1073847228 bytes), \
             past its memory limit of 1.00 GiB (1073741824 bytes)"
        );
        assert_eq!(amount(1023), "1023 bytes");
    }
}
