//! Peers: the Rust crates a user would otherwise pick (`bvh`, `obvhs`, `parry3d`, `kdtree-ray`,
//! `tinybvh-rs` through the `raybench-tinybvh-peer` crate, which holds its `unsafe`),
//! wrapped as `peer-*` entries so they are built from the same mesh, traced with the same rays
//! and checked with the same validation classes as raybench's own structures. Each wrapper goes
//! through the crate's public API only; where a crate hands back candidate primitives rather
//! than hits, the query is finished here with raybench's two-sided Möller–Trumbore
//! ([`MollerTriangle`], Embree's fast-mode arrangement), which the entry's description says.
//! Peers cannot count their own work (`has_counters() == false`), and a peer's mismatches are
//! findings about that crate, not something to paper over here. Behind the harness feature
//! `peers` (on by default).

mod bvh_crate;
mod entries;
mod kdtree_ray;
mod obvhs;
mod parry;

pub use bvh_crate::{BvhCrate, BvhCrateParams};
pub use entries::{entries, unavailable};
pub use kdtree_ray::{KdtreeRay, KdtreeRayParams};
pub use obvhs::{Obvhs, ObvhsParams};
pub use parry::{Parry, ParryParams};

use raybench_accel::{Hit, Nearest, PointHit};
use raybench_geom::{MollerTriangle, Ray, TriangleMesh, Vec3};

/// The mesh's triangles in the layout raybench's Möller–Trumbore reads, in mesh order.
pub(crate) fn moller_triangles(mesh: &TriangleMesh) -> Vec<MollerTriangle> {
    mesh.triangles().map(|t| MollerTriangle::new(&t)).collect()
}

/// The closest hit among `candidates` (mesh primitive indices, any order, repeats allowed):
/// each tested with raybench's Möller–Trumbore on a ray shortened to the best hit so far, the
/// lower index winning equal `t` (BruteForce's rule, so ties do not depend on visit order).
#[inline]
pub(crate) fn closest_among(
    tris: &[MollerTriangle],
    ray: &Ray,
    candidates: impl Iterator<Item = usize>,
) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut r = *ray;
    for prim in candidates {
        let Some(h) = tris[prim].intersect(&r) else {
            continue;
        };
        if best.is_some_and(|b| h.t > b.t || (h.t == b.t && prim as u32 > b.prim)) {
            continue;
        }
        best = Some(Hit::from_tri_hit(prim as u32, h));
        r = r.with_t_max(h.t);
    }
    best
}

/// Any hit among `candidates`, raybench's Möller–Trumbore on each until one hits.
#[inline]
pub(crate) fn any_among(
    tris: &[MollerTriangle],
    ray: &Ray,
    mut candidates: impl Iterator<Item = usize>,
) -> bool {
    candidates.any(|prim| tris[prim].intersect(ray).is_some())
}

/// The answer to a closest-point query whose nearest triangle a crate found (`prim`), put in
/// raybench's terms: the exact nearest point and distance recomputed by [`Nearest`], so the
/// radius and an unanswerable query are handled as for every other structure.
pub(crate) fn point_answer(
    mesh: &TriangleMesh,
    p: Vec3,
    max_radius: f32,
    prim: Option<usize>,
) -> Option<PointHit> {
    let mut nearest = Nearest::within(p, max_radius)?;
    let prim = prim?;
    nearest.test_triangle(p, prim as u32, &mesh.triangle(prim));
    nearest.into_hit()
}
