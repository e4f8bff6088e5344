//! raybench-geom: the geometric vocabulary shared by every structure and by the Embree binding.
//!
//! * [`Ray`]: origin, direction and the half-open segment `(t_min, t_max]`, with a reciprocal
//!   direction that stays correct for `±0` components.
//! * [`Aabb`]: axis-aligned box with a slab test that never produces NaN for axis-parallel rays
//!   and hits flat (zero-thickness) boxes.
//! * [`Triangle`] and [`TriangleMesh`], with the two ray–triangle tests raybench uses:
//!   Möller–Trumbore in the form Embree's fast mode uses, and the watertight test of
//!   Woop, Benthin and Wald (2013), whose per-ray set-up [`WatertightRay`] holds.
//! * [`Tri4`]: four triangles tested against one ray at once, bit-identical to the scalar
//!   Möller–Trumbore test (the wide BVH's leaves, the grid's triangle store).
//! * [`closest_point_on_triangle`] (Ericson's region test) and [`box_distance_squared`], for
//!   closest-point queries.
//! * [`SplitMix64`]: the one small seeded generator of the workspace.
//!
//! No acceleration structures, and no `unsafe` outside the packet kernels (`packet` for
//! AVX-512, `packet8` for AVX2) and the cache hint (`prefetch`).
#![deny(unsafe_code)] // allowed only in the packet kernels and the cache hint

mod aabb;
mod mesh;
#[cfg(target_arch = "x86_64")]
pub mod packet;
#[cfg(target_arch = "x86_64")]
pub mod packet8;
#[cfg(target_arch = "x86_64")]
mod packet_walk;
mod point;
mod prefetch;
mod ray;
pub mod rng;
pub mod tri4;
mod triangle;
pub mod tribox;
mod watertight;

pub use aabb::Aabb;
pub use glam::{DVec3, Vec3};
pub use mesh::{MeshError, RemovedTriangles, TriangleMesh};
#[cfg(target_arch = "x86_64")]
pub use packet_walk::PacketWalk;
pub use point::{
    box_distance_squared, closest_point_on_triangle, distance_to_triangle_f64, query_radius_squared,
};
pub use prefetch::prefetch;
pub use ray::{EMBREE_LARGE, Ray, RayError};
pub use rng::SplitMix64;
pub use tri4::{NO_PRIM, Tri4, Tri4Hits};
pub use triangle::{MollerTriangle, TriHit, Triangle, TriangleTest};
pub use watertight::{Vertices4, WatertightRay};

/// Largest finite value that still compares correctly: `max` of two floats, ignoring a NaN in
/// `candidate`. Written as a comparison so it compiles to one `maxss` (NaN in `candidate` keeps
/// `acc`); used by the slab test where `0 * inf` may produce NaN.
#[inline(always)]
pub fn max_keep(acc: f32, candidate: f32) -> f32 {
    if candidate > acc { candidate } else { acc }
}

/// `min` counterpart of [`max_keep`]: a NaN `candidate` leaves `acc` unchanged.
#[inline(always)]
pub fn min_keep(acc: f32, candidate: f32) -> f32 {
    if candidate < acc { candidate } else { acc }
}
