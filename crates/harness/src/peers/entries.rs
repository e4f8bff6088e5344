//! The `peer-*` registry entries: one per wrapped crate, each description naming the crate,
//! its version and licence, the layout, how a query is finished and where memory comes from.

use super::{
    BvhCrate, BvhCrateParams, KdtreeRay, KdtreeRayParams, Obvhs, ObvhsParams, Parry, ParryParams,
};
use crate::registry::{StructureEntry, register};
use raybench_tinybvh_peer::{BuildMode, TinyBvh, TinyBvhParams};

fn peer(mut e: StructureEntry) -> StructureEntry {
    e.peer = true;
    e
}

pub fn entries() -> Vec<StructureEntry> {
    vec![
        peer(register::<BvhCrate>(
            "peer-bvh",
            "crate bvh 0.13.0 (svenstaro, MIT): binary SAH BVH (Bvh::build, single-threaded); traverse_iterator's candidates (every leaf box on the ray's line, no early exit) finished with raybench's two-sided Möller–Trumbore (the crate's triangle test culls back faces); closest point by the crate's nearest_to; memory from the crate's node and shape vectors",
            None,
            |_| BvhCrateParams {},
        )),
        peer(register::<Obvhs>(
            "peer-obvhs",
            "crate obvhs 0.4.0 (MIT OR Apache-2.0): PLOC BVH with reinsertion collapsed to a compressed 8-wide CWBVH (80-byte nodes), medium_build preset, the crate's CPU traversal; each leaf primitive tested in the traversal callback with raybench's two-sided Möller–Trumbore (the crate's Triangle::intersect gives no barycentrics); closest point not offered; memory from the crate's node and index vectors",
            None,
            |_| ObvhsParams::default(),
        )),
        peer(register::<Parry>(
            "peer-parry3d",
            "crate parry3d 0.31.1 (Dimforge, Apache-2.0): TriMesh's binary BVH and the crate's own ray cast and triangle test (rays with t_min > 0 cast from origin + t_min·dir); any hit is the same full closest-hit cast (as the crate's intersects_local_ray); closest point by the crate's point projection; memory from TriMesh::total_memory_size",
            None,
            |_| ParryParams {},
        )),
        peer(register::<KdtreeRay>(
            "peer-kdtree-ray",
            "crate kdtree-ray 1.2.2 (MIT): SAH k-d tree over triangle boxes (Wald–Havran build); its query returns an allocated candidate list (every leaf on the ray's line) finished with raybench's two-sided Möller–Trumbore; closest point not offered; memory: only the wrapper's triangle copies (the crate reports no size and hides its nodes)",
            None,
            |_| KdtreeRayParams {},
        )),
        peer(register::<TinyBvh>(
            "peer-tinybvh",
            "crate tinybvh-rs 0.1.0-beta.3 (MIT) over tinybvh 1.6.8 (C++, MIT; compiled with -march=native, params.cxx_march names the ISA): binary Wald BVH, BVH::Build (binned SAH, 8 bins), tinybvh's scalar traversal and Möller–Trumbore (which misses any triangle with |det| < 1e-6: small triangles, see docs/structures.md); any hit emulated with closest hit; t_min by moving the origin; closest point not offered; memory from the crate's node and index slices plus its vertex copy",
            None,
            |_| TinyBvhParams::default(),
        )),
        peer(register::<TinyBvh>(
            "peer-tinybvh-hq",
            "as peer-tinybvh, built with BVH::BuildHQ (SBVH: binned SAH with spatial splits)",
            None,
            |_| TinyBvhParams {
                build: BuildMode::Spatial,
                ..TinyBvhParams::default()
            },
        )),
        #[cfg(target_feature = "avx2")]
        peer(register::<raybench_tinybvh_peer::TinyBvh8>(
            "peer-tinybvh-bvh8",
            "as peer-tinybvh, leaves split to 4 triangles and converted through MBVH8 to BVH8_CPU (8-wide 256-byte nodes, 4-triangle leaves tested 4-wide with an approximate reciprocal); any hit emulated with closest hit; memory estimated from the MBVH8's node and leaf counts times BVH8_CPU's node and leaf sizes",
            None,
            |_| Default::default(),
        )),
    ]
}

/// Peers this build cannot offer, with the reason (`raybench list` shows them).
pub fn unavailable() -> Vec<(&'static str, &'static str)> {
    let mut out = Vec::new();
    if !raybench_tinybvh_peer::BVH8_AVAILABLE {
        out.push((
            "peer-tinybvh-bvh8",
            raybench_tinybvh_peer::BVH8_UNAVAILABLE_REASON,
        ));
    }
    out
}
