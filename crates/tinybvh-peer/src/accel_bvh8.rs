//! `peer-tinybvh-bvh8`: tinybvh's BVH8_CPU (the 8-wide layout of Wald et al., "Embree ray
//! tracing kernels", as tinybvh implements it for AVX2): the binned SAH Wald BVH, its leaves
//! split to at most four triangles, collapsed to an MBVH8 and converted into 256-byte nodes
//! (eight child boxes tested at once, children visited in an order precomputed per ray-direction
//! octant) and 192-byte leaves of four triangles tested four-wide with an approximate reciprocal
//! (`_mm_rcp_ps` and one Newton step). BVH8_CPU copies the triangles into its leaves, so the
//! binary BVH and the MBVH8 are kept only for `validate()`. Trade-off: the fastest tinybvh
//! layout on a CPU, but it exists only when Rust is compiled with AVX2 (tinybvh-rs implements
//! its `Intersector` under `cfg(target_feature = "avx2")`). Caveats: any hit is the closest-hit
//! traversal; BVH8_CPU accepts only `t < hit.t`, so `hit.t` starts one ulp above `t_max`.

/// Whether this build offers `peer-tinybvh-bvh8`.
pub const BVH8_AVAILABLE: bool = cfg!(target_feature = "avx2");

/// Why a build without AVX2 does not offer it.
pub const BVH8_UNAVAILABLE_REASON: &str = "tinybvh-rs implements BVH8_CPU's traversal only when Rust is compiled with AVX2; build with RUSTFLAGS=\"-C target-cpu=native\" to get it";

#[cfg(target_feature = "avx2")]
pub use imp::{TinyBvh8, TinyBvh8Params};

#[cfg(target_feature = "avx2")]
mod imp {
    use crate::accel_wald::wald_stats;
    use crate::build_mode::BuildMode;
    use crate::ray::CppRay;
    use crate::wald::{OwnedWald, positions};
    use crate::{CXX_MARCH, validate};
    use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory};
    use raybench_geom::{Ray, TriangleMesh};
    use serde::Serialize;
    use std::sync::Arc;
    use tinybvh_rs::{Intersector, bvh8_cpu, mbvh};

    /// Bytes of one BVH8_CPU interior node and one four-triangle leaf (`sizeof` measured with
    /// g++ 12, tinybvh 1.6.8 as bundled): the memory figure multiplies the MBVH8's counts.
    const NODE_BYTES: u64 = 256;
    const LEAF_BYTES: u64 = 192;

    #[derive(Clone, Debug, Serialize)]
    pub struct TinyBvh8Params {
        /// Not a knob: the ISA the C++ side was compiled for ([`CXX_MARCH`]).
        pub cxx_march: &'static str,
    }

    impl Default for TinyBvh8Params {
        fn default() -> Self {
            TinyBvh8Params {
                cxx_march: CXX_MARCH,
            }
        }
    }

    struct Built {
        /// Declared first, dropped first: it holds shallow copies of the MBVH8 and binary BVH
        /// (tinybvh marks them not owned, and its traversal reads only its own blocks).
        bvh8: bvh8_cpu::BVH,
        mbvh: mbvh::BVHData,
        wald: OwnedWald,
    }

    #[derive(Debug)]
    pub struct TinyBvh8 {
        built: Option<Built>,
        stats: BuildStats,
        memory: Memory,
    }

    impl std::fmt::Debug for Built {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.debug_struct("Built").field("wald", &self.wald).finish()
        }
    }

    // SAFETY: as for `TinyBvh` (see its impls), and in tiny_bvh.h 1.6.8: `BVH8_CPU::Intersect` is
    // `const`, keeps its node and distance stacks in local arrays, reads `bvh8Data`, the null
    // `opmap` and the read-only static `idxLUT256` table, and writes only the caller's `Ray`; the
    // MBVH8 and binary BVH are read only by `validate()` through tinybvh-rs's `&self` slices.
    unsafe impl Send for TinyBvh8 {}
    // SAFETY: see the `Send` impl above: `&TinyBvh8` reaches only read-only C++ methods.
    unsafe impl Sync for TinyBvh8 {}

    impl TinyBvh8 {
        /// The binary BVH's and the MBVH8's invariants (see [`validate`]); the BVH8_CPU blocks
        /// themselves are not exposed by tinybvh-rs.
        pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
            let Some(b) = &self.built else {
                return match mesh.len() {
                    0 => Ok(()),
                    n => Err(format!("no BVH over {n} triangles")),
                };
            };
            validate::wald(b.wald.bvh(), b.wald.positions(), true)?;
            validate::mbvh8(&b.mbvh, b.wald.bvh().indices().len())
        }
    }

    fn memory(mbvh: &mbvh::BVHData) -> Memory {
        let nodes = mbvh.nodes();
        let (mut interior, mut leaves) = (0, 0);
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            if nodes[i].is_leaf() {
                leaves += 1;
            } else {
                interior += 1;
                stack.extend(
                    nodes[i]
                        .child
                        .iter()
                        .filter(|&&c| c != 0)
                        .map(|&c| c as usize),
                );
            }
        }
        Memory {
            nodes: interior * NODE_BYTES,
            indices: 0,
            primitives: leaves * LEAF_BYTES,
        }
    }

    impl Accel for TinyBvh8 {
        type Params = TinyBvh8Params;

        fn build(mesh: Arc<TriangleMesh>, _params: &TinyBvh8Params) -> Result<Self, BuildError> {
            if mesh.is_empty() {
                return Ok(TinyBvh8 {
                    built: None,
                    stats: BuildStats::default(),
                    memory: Memory::default(),
                });
            }
            let backend = |e: tinybvh_rs::Error| BuildError::Backend(e.to_string());
            let mut wald = OwnedWald::build(positions(&mesh), BuildMode::Binned)
                .map_err(BuildError::Backend)?;
            wald.split_leaves(4);
            let m = mbvh::BVH::new(wald.bvh());
            let bvh8 = bvh8_cpu::BVH::new(&m).map_err(backend)?;
            let mbvh = m.data();
            let mut stats = wald_stats(&wald);
            stats
                .extra
                .insert("mbvh8_nodes".into(), mbvh.nodes().len() as f64);
            let memory = memory(&mbvh);
            Ok(TinyBvh8 {
                built: Some(Built { bvh8, mbvh, wald }),
                stats,
                memory,
            })
        }

        fn name(&self) -> &str {
            "peer-tinybvh-bvh8"
        }

        raybench_accel::uncounted_queries!();

        raybench_accel::no_closest_point!();

        #[inline]
        fn intersect(&self, ray: &Ray) -> Option<Hit> {
            let b = self.built.as_ref()?;
            let mut r = CppRay::new(ray, true)?;
            b.bvh8.intersect(&mut r.ray);
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

        /// An estimate from the MBVH8 the crate exposes: its reachable interior nodes and
        /// leaves times BVH8_CPU's node and leaf sizes, the blocks `ConvertFrom` writes.
        fn memory(&self) -> Memory {
            self.memory
        }
    }
}
