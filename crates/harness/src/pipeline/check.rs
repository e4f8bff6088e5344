//! Checks a structure's answers against the reference's, ray by ray (or query point by query
//! point), with the validation classes of `raybench_accel::classify` (and `classify_points`).

use super::measure::Answers;
use crate::report::agreement::{Agreement, DisputedPoint, DisputedRay};
use raybench_accel::classify::{Tolerance, Verdict, VerdictCounts, classify, classify_occlusion};
use raybench_accel::classify_points::{classify_point, point_tolerance};
use raybench_accel::{Accel, PointHit};
use raybench_geom::{Ray, TriangleMesh, Vec3};

/// Disputed rays kept per class in the report.
const KEEP_EXAMPLES: usize = 10;

/// The two structures whose answers are checked against each other (any-hit disagreements
/// are arbitrated by asking both for their closest hits).
pub struct Sides<'a> {
    pub ours: &'a dyn Accel,
    pub reference: &'a dyn Accel,
    pub reference_name: &'a str,
}

impl std::fmt::Debug for Sides<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sides")
            .field("ours", &self.ours.name())
            .field("reference", &self.reference.name())
            .finish()
    }
}

/// Classifies every ray; also returns each ray's disagreement level (see `disagreement`).
/// Any-hit disagreements are arbitrated through both sides' closest hits, computed for the
/// disputed rays only.
pub fn check_answers(
    mesh: &TriangleMesh,
    rays: &[Ray],
    ours: &Answers,
    reference: &Answers,
    sides: &Sides<'_>,
    tol: &Tolerance,
) -> (Agreement, Vec<u8>) {
    let mut counts = VerdictCounts::default();
    let mut levels = Vec::with_capacity(rays.len());
    let mut mismatches = Vec::new();
    let mut ambiguous = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let (verdict, a, b) = match (ours, reference) {
            (Answers::Closest(a), Answers::Closest(b)) => {
                (classify(mesh, ray, a[i], b[i], tol), a[i], b[i])
            }
            (Answers::Any(a), Answers::Any(b)) => {
                let closest = || (sides.ours.intersect(ray), sides.reference.intersect(ray));
                let v = classify_occlusion(mesh, ray, a[i], b[i], closest, tol);
                // Occlusion answers carry no hit; disputed ones show the closest hits.
                let (ha, hb) = if a[i] == b[i] {
                    (None, None)
                } else {
                    closest()
                };
                (v, ha, hb)
            }
            _ => unreachable!("answers of one workload share a kind"),
        };
        counts.add(verdict);
        levels.push(disagreement(verdict));
        let bucket = match verdict {
            Verdict::Mismatch => &mut mismatches,
            Verdict::Boundary | Verdict::EdgeAmbiguous => &mut ambiguous,
            _ => continue,
        };
        if bucket.len() < KEEP_EXAMPLES {
            bucket.push(DisputedRay::new(i, verdict_name(verdict), ray, a, b));
        }
    }
    let mut v = Agreement::new(sides.reference_name, counts);
    v.first_mismatches = mismatches;
    v.first_ambiguous = ambiguous;
    (v, levels)
}

/// For the "disagrees with the reference" image: 0 agrees, 1 differs for an explained reason,
/// 2 a mismatch.
fn disagreement(v: Verdict) -> u8 {
    match v {
        Verdict::BothMiss | Verdict::Exact | Verdict::WithinTolerance => 0,
        Verdict::Tie | Verdict::Boundary | Verdict::EdgeAmbiguous => 1,
        Verdict::Mismatch => 2,
    }
}

pub fn verdict_name(v: Verdict) -> &'static str {
    match v {
        Verdict::BothMiss => "both_miss",
        Verdict::Exact => "exact",
        Verdict::WithinTolerance => "within_tolerance",
        Verdict::Tie => "tie",
        Verdict::Boundary => "boundary",
        Verdict::EdgeAmbiguous => "edge_ambiguous",
        Verdict::Mismatch => "mismatch",
    }
}

/// Classifies every closest-point answer against the reference's (`classify_points`: the
/// tolerance scales with the magnitude of the scene and the point); the first mismatches are
/// kept with the point's bits.
pub fn check_points(
    mesh: &TriangleMesh,
    points: &[Vec3],
    radius: f32,
    ours: &[Option<PointHit>],
    reference: &[Option<PointHit>],
    reference_name: &str,
) -> Agreement {
    let bounds = mesh.bounds();
    let mut counts = VerdictCounts::default();
    let mut mismatches = Vec::new();
    for (i, ((&p, &a), &b)) in points.iter().zip(ours).zip(reference).enumerate() {
        let verdict = classify_point(mesh, p, radius, a, b, point_tolerance(&bounds, p));
        counts.add(verdict);
        if verdict == Verdict::Mismatch && mismatches.len() < KEEP_EXAMPLES {
            let name = verdict_name(verdict);
            mismatches.push(DisputedPoint::new(i, name, p, radius, a, b));
        }
    }
    let mut v = Agreement::new(reference_name, counts);
    v.first_point_mismatches = mismatches;
    v
}

/// Queries where the counted walk answered differently from the timed path.
pub fn counted_point_differences(timed: &[Option<PointHit>], counted: &[Option<PointHit>]) -> u64 {
    let differing = timed.iter().zip(counted).filter(|(a, b)| a != b).count();
    (differing + timed.len().abs_diff(counted.len())) as u64
}

/// How the counted walk's answers compare with the timed path's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathDifferences {
    /// Rays answered differently for no reason the f64 arbiter accepts: a bug in one of the
    /// two paths.
    pub differs: u64,
    /// Rays answered differently for an explained reason, classified like any disagreement
    /// with a reference: a tie (a packet walk meets triangles in another order than the
    /// single-ray walk, and keeps the other of two equally near ones), an edge-ambiguous ray
    /// (two entry points of one library, such as Embree's stream and single-ray calls,
    /// deciding a ray that grazes an edge differently), a boundary hit or a `t` within
    /// tolerance.
    pub explained: u64,
}

/// Compares the counted walk's answers with the timed path's, ray by ray, classifying every
/// difference with the validation classes. `accel` answers the closest hits an any-hit
/// dispute is arbitrated with.
pub fn counted_path_differences(
    mesh: &TriangleMesh,
    rays: &[Ray],
    timed: &Answers,
    counted: &Answers,
    tol: &Tolerance,
    accel: &dyn Accel,
) -> PathDifferences {
    let mut d = PathDifferences::default();
    let mut count = |verdict: Verdict| match verdict {
        Verdict::Mismatch => d.differs += 1,
        _ => d.explained += 1,
    };
    match (timed, counted) {
        (Answers::Closest(a), Answers::Closest(b)) => {
            for ((x, y), ray) in a.iter().zip(b).zip(rays) {
                if x != y {
                    count(classify(mesh, ray, *x, *y, tol));
                }
            }
        }
        (Answers::Any(a), Answers::Any(b)) => {
            for ((&x, &y), ray) in a.iter().zip(b).zip(rays) {
                if x != y {
                    let hits = || (accel.intersect(ray), accel.intersect(ray));
                    count(classify_occlusion(mesh, ray, x, y, hits, tol));
                }
            }
        }
        _ => d.differs = timed.len() as u64,
    }
    d
}
