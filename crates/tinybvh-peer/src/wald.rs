//! A tinybvh "Wald" BVH (binary, 32-byte nodes) together with the vertex array it reads.
//!
//! tinybvh-rs's `bvh::BVH<'a>` borrows the positions it was built over (tinybvh keeps a pointer
//! to them and reads them during every traversal), so an owner has to keep both side by side.
//! [`OwnedWald`] holds the positions in a boxed slice that is never moved out, resized or
//! written after the build, and declares the BVH first so that it is dropped before them.

use crate::build_mode::BuildMode;
use tinybvh_rs::bvh;

/// tinybvh's vertex format: x, y, z and an unused fourth float, three per triangle, mesh order.
pub(crate) fn positions(mesh: &raybench_geom::TriangleMesh) -> Box<[[f32; 4]]> {
    mesh.triangles()
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .map(|v| [v.x, v.y, v.z, 0.0])
        .collect()
}

pub(crate) struct OwnedWald {
    /// Declared before `positions`: fields drop in declaration order, so the BVH, which points
    /// into `positions`, is gone before they are freed.
    bvh: bvh::BVH<'static>,
    /// Never moved out of its box, resized or written after the build: the BVH reads it.
    positions: Box<[[f32; 4]]>,
}

impl std::fmt::Debug for OwnedWald {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OwnedWald")
            .field("nodes", &self.bvh.nodes().len())
            .field("triangles", &(self.positions.len() / 3))
            .finish()
    }
}

impl OwnedWald {
    /// Builds over `positions` (non-empty, a multiple of three vertices: tinybvh aborts the
    /// process on an empty vertex slice).
    pub(crate) fn build(positions: Box<[[f32; 4]]>, mode: BuildMode) -> Result<Self, String> {
        debug_assert!(!positions.is_empty() && positions.len().is_multiple_of(3));
        // SAFETY: the slice lives in a heap allocation owned by `positions`, which is stored in
        // the returned `OwnedWald` next to the BVH and never moved out of its box, resized or
        // written; the BVH field is dropped before `positions` (declaration order). The
        // `'static` slice itself never leaves this function, and `bvh()` lends the BVH only for
        // as long as `self` is borrowed: tinybvh-rs offers no way to get the positions or an
        // owned BVH back through `&BVH`. Moving the `Box` itself does not move the heap slice.
        let borrowed: &'static [[f32; 4]] =
            unsafe { &*std::ptr::from_ref::<[[f32; 4]]>(&positions) };
        let built = match mode {
            BuildMode::Binned => bvh::BVH::new(borrowed.into()),
            BuildMode::Spatial => bvh::BVH::new_hq(borrowed.into()),
        };
        let bvh = built.map_err(|e| e.to_string())?;
        Ok(OwnedWald { bvh, positions })
    }

    pub(crate) fn bvh(&self) -> &bvh::BVH<'static> {
        &self.bvh
    }

    /// Splits leaves to at most `max` triangles (BVH8_CPU's four-triangle leaves need it).
    #[cfg_attr(not(target_feature = "avx2"), allow(dead_code))]
    pub(crate) fn split_leaves(&mut self, max: u32) {
        self.bvh.split_leaves(max);
    }

    pub(crate) fn triangle_count(&self) -> usize {
        self.positions.len() / 3
    }

    pub(crate) fn positions(&self) -> &[[f32; 4]] {
        &self.positions
    }
}
