//! The `peer-*` registry entries: one per wrapped crate, each description naming the crate,
//! its version and licence, the layout, how a query is finished and where memory comes from.

use super::{
    BvhCrate, BvhCrateParams, KdtreeRay, KdtreeRayParams, Obvhs, ObvhsParams, Parry, ParryParams,
};
use crate::registry::{StructureEntry, register};

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
    ]
}
