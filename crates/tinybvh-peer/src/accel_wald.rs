//! `peer-tinybvh` and `peer-tinybvh-hq`: tinybvh's binary "Wald" BVH (32-byte nodes holding a
//! box, a first-child-or-first-triangle index and a triangle count), built by `BVH::Build`
//! (binned SAH, 8 bins) or `BVH::BuildHQ` (SBVH: binned SAH with spatial splits, Stich et al.
//! 2009), traced by tinybvh's scalar `BVH::Intersect` (near child first, 256-entry stack,
//! Möller–Trumbore on each leaf triangle). Trade-off: the HQ build spends several times the
//! build time to cut overlapping boxes on scenes with long thin triangles. Caveat: any hit is
//! the closest-hit traversal (tinybvh-rs exposes no occlusion query), so shadow rays pay for a
//! full search.

use crate::build_mode::BuildMode;
use crate::ray::CppRay;
use crate::wald::{OwnedWald, positions};
use crate::{CXX_MARCH, validate};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory};
use raybench_geom::{Ray, TriangleMesh};
use serde::Serialize;
use std::sync::Arc;
use tinybvh_rs::Intersector;

#[derive(Clone, Debug, Serialize)]
pub struct TinyBvhParams {
    /// Binned SAH (`peer-tinybvh`) or SBVH (`peer-tinybvh-hq`).
    pub build: BuildMode,
    /// Not a knob: the ISA the C++ side was compiled for ([`CXX_MARCH`]), so reports carry it.
    pub cxx_march: &'static str,
}

impl Default for TinyBvhParams {
    fn default() -> Self {
        TinyBvhParams {
            build: BuildMode::Binned,
            cxx_march: CXX_MARCH,
        }
    }
}

#[derive(Debug)]
pub struct TinyBvh {
    name: &'static str,
    mode: BuildMode,
    /// `None` for an empty mesh (tinybvh aborts on an empty vertex array).
    wald: Option<OwnedWald>,
    stats: BuildStats,
}

// SAFETY: `TinyBvh` is `!Send`/`!Sync` only because cxx's opaque C++ types are. Read in tiny_bvh.h
// 1.6.8 (as bundled): the C++ `BVH` owns its node and index arrays (AlignedAlloc/AlignedFree,
// no thread affinity) and points at the positions `OwnedWald` owns, so moving it to another
// thread is sound. After the build this wrapper only calls `BVH::Intersect`, a `const` method
// whose state is all local (node pointer, a 256-entry stack array, a cost counter): it reads
// `bvhNode`, `primIdx`, `verts`, and the null `vertIdx`, `customIntersect` and `opmap`, and
// writes only the caller's `Ray`. The header has no `mutable` members; its statics (the AVX
// constants of `BVH`) and its two `thread_local` job systems are used by builds only. So
// concurrent `Intersect` calls on one built BVH share nothing they write.
unsafe impl Send for TinyBvh {}
// SAFETY: see the `Send` impl above: `&TinyBvh` reaches only the read-only `Intersect`.
unsafe impl Sync for TinyBvh {}

/// Shape of the Wald BVH: reachable nodes, leaves, depth and triangle references.
pub(crate) fn wald_stats(wald: &OwnedWald) -> BuildStats {
    let nodes = wald.bvh().nodes();
    let mut s = BuildStats::default();
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, depth)) = stack.pop() {
        let n = &nodes[i];
        s.nodes += 1;
        s.max_depth = s.max_depth.max(depth);
        if n.is_leaf() {
            s.leaves += 1;
            s.refs += u64::from(n.tri_count);
        } else {
            let c = n.left_first as usize;
            stack.extend([(c, depth + 1), (c + 1, depth + 1)]);
        }
    }
    // tinybvh's own SAH cost (its C_TRAV = C_INT = 1, its normalisation): not raybench's
    // `sah_cost`, so it is reported beside it, not as it.
    s.extra.insert(
        "tinybvh_sah_cost".to_string(),
        f64::from(wald.bvh().sah_cost(0)),
    );
    s
}

impl TinyBvh {
    /// The structure's invariants: those of the Wald BVH (see `validate::wald`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let Some(w) = &self.wald else {
            return match mesh.len() {
                0 => Ok(()),
                n => Err(format!("no BVH over {n} triangles")),
            };
        };
        if w.triangle_count() != mesh.len() {
            return Err("triangle count differs from the mesh".to_string());
        }
        validate::wald(w.bvh(), w.positions(), self.mode == BuildMode::Binned).map(|_| ())
    }
}

impl Accel for TinyBvh {
    type Params = TinyBvhParams;

    fn build(mesh: Arc<TriangleMesh>, params: &TinyBvhParams) -> Result<Self, BuildError> {
        let name = match params.build {
            BuildMode::Binned => "peer-tinybvh",
            BuildMode::Spatial => "peer-tinybvh-hq",
        };
        let wald = match mesh.len() {
            0 => None,
            _ => Some(
                OwnedWald::build(positions(&mesh), params.build).map_err(BuildError::Backend)?,
            ),
        };
        let stats = wald.as_ref().map(wald_stats).unwrap_or_default();
        Ok(TinyBvh {
            name,
            mode: params.build,
            wald,
            stats,
        })
    }

    fn name(&self) -> &str {
        self.name
    }

    raybench_accel::uncounted_queries!();

    raybench_accel::no_closest_point!();

    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let wald = self.wald.as_ref()?;
        let mut r = CppRay::new(ray, false)?;
        wald.bvh().intersect(&mut r.ray);
        r.hit(ray)
    }

    /// Closest hit standing in for any hit (tinybvh-rs exposes no occlusion query).
    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.intersect(ray).is_some()
    }

    fn build_stats(&self) -> BuildStats {
        self.stats.clone()
    }

    /// From the crate's node and index slices (32-byte nodes as used, 4-byte references) and
    /// the 16-byte-per-vertex position copy tinybvh reads its triangles from.
    fn memory(&self) -> Memory {
        let Some(w) = &self.wald else {
            return Memory::default();
        };
        Memory {
            nodes: size_of_val(w.bvh().nodes()) as u64,
            indices: (w.bvh().indices().len() * 4) as u64,
            primitives: size_of_val(w.positions()) as u64,
        }
    }
}
