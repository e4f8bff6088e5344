//! Which tinybvh builder makes the binary BVH every tinybvh entry starts from.

use serde::Serialize;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BuildMode {
    /// `BVH::Build`: binned SAH over triangle centroids (8 bins, tinybvh's default `BVHBINS`),
    /// multithreaded with tinybvh's own C++ threads from 50,000 triangles (`MT_BUILD_THRESHOLD`).
    #[default]
    Binned,
    /// `BVH::BuildHQ`: SBVH, binned SAH with spatial splits (Stich et al. 2009); triangles may be
    /// referenced by several leaves.
    Spatial,
}
