//! Closest-point queries through Embree's `rtcPointQuery`.
//!
//! Embree walks its BVH with a sphere (the query point and a radius) and calls a user callback
//! for every primitive in every leaf whose box the sphere reaches (all primitives of such a
//! leaf, even those outside the sphere: Embree keeps no per-primitive bounds). The callback
//! computes the exact point–triangle distance with the same function every raybench structure
//! uses ([`raybench_accel::Nearest`], i.e. `closest_point_on_triangle` and one acceptance rule),
//! and when it finds a nearer triangle it shrinks the query's radius and returns `true`, which
//! tells Embree to update its traversal state so farther subtrees are culled (rtcPointQuery(3),
//! rtcSetGeometryPointQueryFunction(3)). The scene needs no particular flag; a plain triangle
//! geometry without instancing has similarity scale 1, so distances need no rescaling.
//!
//! The distance work is therefore identical on both sides of the comparison; what differs is
//! Embree's tree, its box culling and the cost of an indirect call per primitive.

use raybench_accel::{Nearest, PointHit};
use raybench_embree_sys as sys;
use raybench_geom::{TriangleMesh, Vec3};

/// A fresh point-query context, as the header's inline `rtcInitPointQueryContext` makes it (no
/// instance on the stack). The header leaves the transform matrices uninitialised because they
/// are undefined while the stack is empty; here they are zeroed, since Rust has no
/// uninitialised plain values. bindgen cannot bind the function itself: it is an
/// `RTC_FORCEINLINE` function of `rtcore_common.h`, and `libembree3.so` exports no such symbol.
pub(crate) fn point_query_context() -> sys::RTCPointQueryContext {
    const LEVELS: usize = sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize;
    sys::RTCPointQueryContext {
        world2inst: [[0.0; 16]; LEVELS],
        inst2world: [[0.0; 16]; LEVELS],
        instID: [sys::RTC_INVALID_GEOMETRY_ID; LEVELS],
        instStackSize: 0,
    }
}

/// What the callback reads and updates through `userPtr` during one `rtcPointQuery`.
struct Search<'a> {
    mesh: &'a TriangleMesh,
    p: Vec3,
    nearest: Nearest,
}

/// The nearest triangle of `mesh` to `p` within `max_radius`, found by `rtcPointQuery` on
/// `scene`. Queries with no answer by definition (non-finite or huge point, negative or NaN
/// radius) return `None` before reaching Embree, as do empty meshes.
///
/// # Safety
/// `scene` must be a live, committed scene whose only geometry is a triangle geometry holding
/// `mesh`'s triangles in `mesh`'s order (what `EmbreeScene::build_on` makes), or no geometry
/// at all when `mesh` is empty.
pub(crate) unsafe fn closest_point(
    scene: sys::RTCScene,
    mesh: &TriangleMesh,
    p: Vec3,
    max_radius: f32,
) -> Option<PointHit> {
    let nearest = Nearest::within(p, max_radius)?;
    if mesh.is_empty() {
        return None;
    }
    let mut search = Search { mesh, p, nearest };
    let mut query = sys::RTCPointQuery {
        x: p.x,
        y: p.y,
        z: p.z,
        time: 0.0,
        radius: max_radius,
    };
    let mut context = point_query_context();
    let user: *mut Search<'_> = &mut search;
    // SAFETY: `scene` is live and committed, over `mesh` (this function's contract), so every
    // `primID` the callback sees indexes `mesh`. `query` is a 16-byte-aligned local with
    // a finite point within Embree's range and a radius in [0, inf] (checked by
    // `Nearest::within`), as rtcPointQuery(3) requires. `context` is initialised like
    // rtcInitPointQueryContext. `user` points to `search`, which outlives the call and is not
    // touched here until Embree returns; the callback is the only code that uses it meanwhile,
    // on this thread.
    unsafe {
        sys::rtcPointQuery(
            scene,
            &mut query,
            &mut context,
            Some(nearest_triangle_callback),
            user.cast(),
        );
    }
    search.nearest.into_hit()
}

/// The `RTCPointQueryFunction`: offers primitive `primID` to the search and, when it is kept,
/// shrinks the query radius to its distance and returns `true` (Embree then refreshes its
/// culling). Returns `false` when nothing changed. Never unwinds: an unexpected `primID` is
/// ignored rather than indexed.
unsafe extern "C" fn nearest_triangle_callback(
    args: *mut sys::RTCPointQueryFunctionArguments,
) -> bool {
    // SAFETY: Embree passes a valid, exclusive pointer to the arguments for the duration of the
    // call (rtcSetGeometryPointQueryFunction(3)).
    let args = unsafe { &mut *args };
    // SAFETY: `userPtr` is the `*mut Search` that `closest_point` passed to rtcPointQuery; the
    // `Search` lives on that caller's stack for the whole query, and no other reference to it
    // is live while Embree runs this callback.
    let search = unsafe { &mut *args.userPtr.cast::<Search<'_>>() };
    let prim = args.primID;
    if prim as usize >= search.mesh.len() {
        return false;
    }
    let tri = search.mesh.triangle(prim as usize);
    if !search.nearest.test_triangle(search.p, prim, &tri) {
        return false;
    }
    // SAFETY: `query` is the `RTCPointQuery` passed to rtcPointQuery, alive for the whole
    // query, and nothing else accesses it during the callback.
    let query = unsafe { &mut *args.query };
    // Never larger than the current radius (increasing it is undefined behaviour):
    // `sqrt(d2)` can round one ulp above the caller's radius when `d2` equals its square.
    query.radius = search.nearest.bound_d2().sqrt().min(query.radius);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn context_matches_rtc_init_point_query_context() {
        let ctx = point_query_context();
        assert_eq!(ctx.instStackSize, 0);
        assert_eq!(ctx.instID[0], sys::RTC_INVALID_GEOMETRY_ID);
    }
}
