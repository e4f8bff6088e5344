//! The checks of one closest-point answer: on its own (on the triangle it names, at the
//! distance it reports, within the radius), and against brute force (its class).

use raybench_accel::{Accel, BruteForce, Counters, PointHit};
use raybench_geom::{Aabb, Triangle, TriangleMesh, Vec3, distance_to_triangle_f64};
use std::ops::AddAssign;
use std::sync::Arc;

/// How one query compared with brute force.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointVerdict {
    BothNone,
    Exact,
    WithinTolerance,
    Tie,
    Boundary,
    Mismatch,
}

/// How many queries fell in each class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointCounts {
    pub both_none: u64,
    pub exact: u64,
    pub within_tolerance: u64,
    pub tie: u64,
    pub boundary: u64,
    pub mismatch: u64,
}

impl PointCounts {
    pub fn add(&mut self, v: PointVerdict) {
        let slot = match v {
            PointVerdict::BothNone => &mut self.both_none,
            PointVerdict::Exact => &mut self.exact,
            PointVerdict::WithinTolerance => &mut self.within_tolerance,
            PointVerdict::Tie => &mut self.tie,
            PointVerdict::Boundary => &mut self.boundary,
            PointVerdict::Mismatch => &mut self.mismatch,
        };
        *slot += 1;
    }

    /// Queries that found a triangle and agreed with brute force.
    pub fn answered(&self) -> u64 {
        self.exact + self.within_tolerance + self.tie
    }
}

impl AddAssign for PointCounts {
    fn add_assign(&mut self, o: PointCounts) {
        self.both_none += o.both_none;
        self.exact += o.exact;
        self.within_tolerance += o.within_tolerance;
        self.tie += o.tie;
        self.boundary += o.boundary;
        self.mismatch += o.mismatch;
    }
}

/// Exact distance from `p` to `tri` in f64 (geom's reference for checking answers, a different
/// route from the `closest_point_on_triangle` every structure uses).
pub fn exact_distance(p: Vec3, tri: &Triangle) -> f64 {
    distance_to_triangle_f64(p, tri)
}

/// Absolute distance tolerance for queries at `p` on `mesh` (shared with the harness: see
/// [`raybench_accel::classify_points::point_tolerance`]).
pub fn tolerance(mesh_bounds: &Aabb, p: Vec3) -> f64 {
    raybench_accel::classify_points::point_tolerance(mesh_bounds, p)
}

/// The checks one answer must pass on its own, whatever brute force says.
fn check_answer(
    mesh: &TriangleMesh,
    p: Vec3,
    radius: f32,
    h: &PointHit,
    tol: f64,
) -> Result<(), String> {
    if h.prim as usize >= mesh.len() {
        return Err(format!(
            "prim {} out of range ({} triangles)",
            h.prim,
            mesh.len()
        ));
    }
    let tri = mesh.triangle(h.prim as usize);
    let off_triangle = exact_distance(h.point, &tri);
    if off_triangle > tol {
        return Err(format!(
            "point {} is {off_triangle:e} away from triangle {}",
            h.point, h.prim
        ));
    }
    let measured = (h.point.as_dvec3() - p.as_dvec3()).length();
    if (h.distance as f64 - measured).abs() > tol {
        return Err(format!(
            "distance {} but |point - p| = {measured}",
            h.distance
        ));
    }
    if h.distance as f64 > radius as f64 + tol {
        return Err(format!(
            "distance {} beyond the radius {radius}",
            h.distance
        ));
    }
    Ok(())
}

/// Classifies `ours` against brute force's `expected` (see the module documentation; the
/// rule itself is [`raybench_accel::classify_points::classify_point`], which the harness uses
/// against Embree).
pub fn classify_point(
    mesh: &TriangleMesh,
    p: Vec3,
    radius: f32,
    ours: Option<PointHit>,
    expected: Option<PointHit>,
    tol: f64,
) -> PointVerdict {
    use raybench_accel::classify::Verdict;
    match raybench_accel::classify_points::classify_point(mesh, p, radius, ours, expected, tol) {
        Verdict::BothMiss => PointVerdict::BothNone,
        Verdict::Exact => PointVerdict::Exact,
        Verdict::WithinTolerance => PointVerdict::WithinTolerance,
        Verdict::Tie => PointVerdict::Tie,
        Verdict::Boundary => PointVerdict::Boundary,
        Verdict::EdgeAmbiguous | Verdict::Mismatch => PointVerdict::Mismatch,
    }
}

/// Checks `accel.closest_point` and `closest_point_counted` against brute force on every point
/// at `radius`. `Err` names the first failing point (with its bits, to replay it).
pub fn check_points(
    accel: &dyn Accel,
    mesh: &Arc<TriangleMesh>,
    points: &[Vec3],
    radius: f32,
) -> Result<PointCounts, String> {
    let oracle = BruteForce::build(mesh.clone(), &Default::default())
        .map_err(|e| format!("brute force failed to build: {e}"))?;
    let bounds = mesh.bounds();
    let mut counts = PointCounts::default();
    for (i, &p) in points.iter().enumerate() {
        let fail = |what: String| {
            format!(
                "{}: point {i} {p} (bits {:08x?}), radius {radius}: {what}",
                accel.name(),
                p.to_array().map(f32::to_bits)
            )
        };
        let tol = tolerance(&bounds, p);
        let ours = accel.closest_point(p, radius);
        let counted = accel.closest_point_counted(p, radius, &mut Counters::default());
        if counted != ours {
            return Err(fail(format!(
                "closest_point_counted {counted:?} but closest_point {ours:?}"
            )));
        }
        if let Some(h) = &ours {
            check_answer(mesh, p, radius, h, tol).map_err(fail)?;
        }
        let expected = oracle.closest_point(p, radius);
        let verdict = classify_point(mesh, p, radius, ours, expected, tol);
        if verdict == PointVerdict::Mismatch {
            return Err(fail(format!("{ours:?}, brute force {expected:?}")));
        }
        counts.add(verdict);
    }
    Ok(counts)
}

/// The counters of `accel`'s closest-point walk, summed over `points` at `radius`.
pub fn counted_work(accel: &dyn Accel, points: &[Vec3], radius: f32) -> Counters {
    let mut c = Counters::default();
    for &p in points {
        accel.closest_point_counted(p, radius, &mut c);
    }
    c
}

/// [`check_points`] at an infinite radius, where every point must be answered, then at 0.25
/// and at 0; panics with the first failure.
pub fn check_points_at_radii(accel: &dyn Accel, mesh: &Arc<TriangleMesh>, points: &[Vec3]) {
    for radius in [f32::INFINITY, 0.25, 0.0] {
        let counts = check_points(accel, mesh, points, radius).unwrap_or_else(|e| panic!("{e}"));
        if radius == f32::INFINITY {
            assert_eq!(counts.answered(), points.len() as u64, "{counts:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::points::cases::{INF, from_tris};
    use crate::points::point_conformance;

    /// The oracle checked against itself: every class the checker can produce, and a planted
    /// wrong answer that it must reject.
    #[test]
    fn brute_force_conforms_and_a_wrong_answer_is_caught() {
        let counts = point_conformance::<BruteForce>(&Default::default(), &crate::no_validation);
        assert_eq!(counts.mismatch, 0);
        assert!(
            counts.both_none > 100,
            "the finite radii leave points unanswered: {counts:?}"
        );
        let m = from_tris(&[
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::Z, Vec3::Z + Vec3::X, Vec3::Z + Vec3::Y),
        ]);
        let p = Vec3::new(0.2, 0.2, 0.1);
        let right = BruteForce::build(m.clone(), &Default::default())
            .unwrap()
            .closest_point(p, INF);
        assert_eq!(right.map(|h| h.prim), Some(0));
        let wrong = Some(PointHit {
            prim: 1,
            point: Vec3::new(0.2, 0.2, 1.0),
            distance: 0.9,
        });
        let tol = tolerance(&m.bounds(), p);
        assert_eq!(
            classify_point(&m, p, INF, wrong, right, tol),
            PointVerdict::Mismatch
        );
        assert_eq!(
            classify_point(&m, p, INF, None, right, tol),
            PointVerdict::Mismatch
        );
        assert_eq!(
            classify_point(&m, p, 0.1, None, right, tol),
            PointVerdict::Boundary
        );
        // Answers that are wrong on their own: a point off its triangle, a distance that is
        // not |point - p|, a distance beyond the radius.
        let h = right.unwrap();
        let off = PointHit {
            point: Vec3::new(0.2, 0.2, 0.01),
            ..h
        };
        assert!(check_answer(&m, p, INF, &off, tol).is_err());
        let misreported = PointHit {
            distance: 0.05,
            ..h
        };
        assert!(check_answer(&m, p, INF, &misreported, tol).is_err());
        assert!(check_answer(&m, p, 0.05, &h, tol).is_err());
        assert!(check_answer(&m, p, INF, &h, tol).is_ok());
        let twin = from_tris(&[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 2]);
        let other = right.map(|h| PointHit { prim: 1, ..h });
        assert_eq!(
            classify_point(&twin, p, INF, other, right, tol),
            PointVerdict::Tie
        );
    }
}
