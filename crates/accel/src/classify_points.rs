//! Deciding whether two closest-point answers for the same query agree: the point analogue of
//! [`crate::classify`], shared by the conformance suite (testkit, against brute force) and the
//! harness (`run` and `verify`, against Embree's `rtcPointQuery`).
//!
//! Each query falls in one [`Verdict`] (the ray classes, read for points): `BothMiss` (neither
//! found a triangle within the radius); `Exact` (same answer, bit for bit); `WithinTolerance`
//! (same triangle, distances within [`point_tolerance`]); `Tie` (different triangles, and an f64
//! recomputation says both are equally far within the tolerance); `Boundary` (one answer, the
//! other none, and the distance found equals the radius within the tolerance); `Mismatch`
//! (anything else: a bug). Points have no edge ambiguity: `EdgeAmbiguous` never occurs.

use crate::PointHit;
use crate::classify::Verdict;
use raybench_geom::{Aabb, TriangleMesh, Vec3, distance_to_triangle_f64};

/// Tolerance in f32 ulps (machine epsilon times the largest |coordinate| of the mesh and the
/// point). `closest_point_on_triangle` is within one ulp of the f64 reference (geom's
/// dense-sampling test measures 0.63), and the f32 distance adds about one more; 8 leaves room
/// without hiding a wrong triangle.
pub const POINT_TOLERANCE_ULPS: f64 = 8.0;

/// Absolute distance tolerance for queries at `p` on a mesh with `mesh_bounds`:
/// [`POINT_TOLERANCE_ULPS`] f32 ulps of the largest coordinate magnitude involved (with a floor
/// for scenes at the origin's scale).
pub fn point_tolerance(mesh_bounds: &Aabb, p: Vec3) -> f64 {
    let mut scale = p.abs().max_element() as f64;
    if !mesh_bounds.is_empty() {
        scale = scale
            .max(mesh_bounds.min.abs().max_element() as f64)
            .max(mesh_bounds.max.abs().max_element() as f64);
    }
    POINT_TOLERANCE_ULPS * f32::EPSILON as f64 * scale.max(f32::MIN_POSITIVE as f64)
}

/// Classifies `ours` against `reference` for the query at `p` with `radius` (see the module
/// documentation). `tol` is usually [`point_tolerance`].
pub fn classify_point(
    mesh: &TriangleMesh,
    p: Vec3,
    radius: f32,
    ours: Option<PointHit>,
    reference: Option<PointHit>,
    tol: f64,
) -> Verdict {
    match (ours, reference) {
        (None, None) => Verdict::BothMiss,
        (Some(h), None) | (None, Some(h)) => {
            if (h.distance as f64 - radius as f64).abs() <= tol {
                Verdict::Boundary
            } else {
                Verdict::Mismatch
            }
        }
        (Some(a), Some(b)) if a == b => Verdict::Exact,
        (Some(a), Some(b)) => {
            if (a.distance as f64 - b.distance as f64).abs() > tol {
                Verdict::Mismatch
            } else if a.prim == b.prim {
                Verdict::WithinTolerance
            } else {
                equidistant(mesh, p, a.prim, b.prim, tol)
            }
        }
    }
}

/// `Tie` when the two triangles are equally far from `p` in f64 (within `tol`), else `Mismatch`.
/// A prim index out of range is a mismatch (a structure answered a triangle that does not exist).
fn equidistant(mesh: &TriangleMesh, p: Vec3, a: u32, b: u32, tol: f64) -> Verdict {
    let in_range = |prim: u32| (prim as usize) < mesh.len();
    if !(in_range(a) && in_range(b)) {
        return Verdict::Mismatch;
    }
    let da = distance_to_triangle_f64(p, &mesh.triangle(a as usize));
    let db = distance_to_triangle_f64(p, &mesh.triangle(b as usize));
    if (da - db).abs() <= tol {
        Verdict::Tie
    } else {
        Verdict::Mismatch
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Triangle;

    /// Two unit triangles mirrored about z = 0: every point on the z axis is equally far from both.
    fn mirrored() -> TriangleMesh {
        let up = Triangle::new(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        );
        let down = Triangle::new(
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
        );
        TriangleMesh::from_triangles(&[up, down]).unwrap().0
    }

    fn hit(prim: u32, z: f32, distance: f32) -> Option<PointHit> {
        Some(PointHit {
            prim,
            point: Vec3::new(0.0, 0.0, z),
            distance,
        })
    }

    #[test]
    fn every_class_is_reachable() {
        let mesh = mirrored();
        let p = Vec3::ZERO;
        let tol = point_tolerance(&mesh.bounds(), p);
        let c = |a, b| classify_point(&mesh, p, f32::INFINITY, a, b, tol);
        assert_eq!(c(None, None), Verdict::BothMiss);
        assert_eq!(c(hit(0, 1.0, 1.0), hit(0, 1.0, 1.0)), Verdict::Exact);
        let one_ulp_more = f32::from_bits(1.0f32.to_bits() + 1);
        assert_eq!(
            c(hit(0, 1.0, one_ulp_more), hit(0, 1.0, 1.0)),
            Verdict::WithinTolerance
        );
        assert_eq!(c(hit(1, -1.0, 1.0), hit(0, 1.0, 1.0)), Verdict::Tie);
        assert_eq!(c(hit(0, 1.0, 1.5), hit(0, 1.0, 1.0)), Verdict::Mismatch);
        assert_eq!(
            c(None, hit(0, 1.0, 1.0)),
            Verdict::Mismatch,
            "infinite radius"
        );
        assert_eq!(
            c(hit(7, 1.0, 1.0), hit(0, 1.0, 1.0)),
            Verdict::Mismatch,
            "no triangle 7"
        );
        let at_radius = classify_point(&mesh, p, 1.0, None, hit(0, 1.0, 1.0), tol);
        assert_eq!(at_radius, Verdict::Boundary);
    }

    #[test]
    fn a_nearer_triangle_at_the_same_reported_distance_is_no_tie() {
        // Ours claims triangle 1 is 1.0 away, but it is 3.0 away from (0, 0, 2): a lie, not a tie.
        let mesh = mirrored();
        let p = Vec3::new(0.0, 0.0, 2.0);
        let tol = point_tolerance(&mesh.bounds(), p);
        let verdict = classify_point(
            &mesh,
            p,
            f32::INFINITY,
            hit(1, -1.0, 1.0),
            hit(0, 1.0, 1.0),
            tol,
        );
        assert_eq!(verdict, Verdict::Mismatch);
    }
}
