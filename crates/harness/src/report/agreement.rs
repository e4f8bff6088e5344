//! How a structure's answers agreed with a reference: the count of every validation class, and
//! the first disputed rays and points with the exact bits to replay them.

use raybench_accel::classify::VerdictCounts;
use raybench_accel::{Hit, PointHit};
use raybench_geom::{Ray, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Agreement {
    pub reference: String,
    /// Rays per class: `both_miss`, `exact`, `within_tolerance`, `tie`, `boundary`,
    /// `edge_ambiguous`, `mismatch` (written flat into this object).
    #[serde(flatten)]
    pub counts: VerdictCounts,
    /// Rays where the counted path answered differently from the timed path, unexplained (a
    /// mismatch between the two: a bug).
    pub counted_path_differs: u64,
    /// Rays where the two paths differ for an explained reason (a tie, an edge-ambiguous ray,
    /// a boundary hit, `t` within tolerance; see `pipeline::check::PathDifferences`).
    #[serde(default, skip_serializing_if = "is_zero", alias = "counted_path_ties")]
    pub counted_path_explained: u64,
    /// With 0 mismatches in n rays, the 95 % upper bound on the mismatch rate (rule of three).
    pub mismatch_rate_upper95: f64,
    pub first_mismatches: Vec<DisputedRay>,
    /// First few explained disagreements (boundary, edge-ambiguous), for replay.
    pub first_ambiguous: Vec<DisputedRay>,
    /// Point workloads: the first mismatched queries, with the point's bits for replay.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub first_point_mismatches: Vec<DisputedPoint>,
}

impl Agreement {
    pub fn new(reference: &str, counts: VerdictCounts) -> Agreement {
        let n = counts.total().max(1) as f64;
        let upper95 = if counts.mismatch == 0 {
            (3.0 / n).min(1.0)
        } else {
            counts.mismatch as f64 / n
        };
        Agreement {
            reference: reference.to_string(),
            counts,
            counted_path_differs: 0,
            counted_path_explained: 0,
            mismatch_rate_upper95: upper95,
            first_mismatches: Vec::new(),
            first_ambiguous: Vec::new(),
            first_point_mismatches: Vec::new(),
        }
    }

    pub fn queries(&self) -> u64 {
        self.counts.total()
    }
}

/// A ray two answers disagree on, with everything needed to replay it bit for bit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisputedRay {
    pub index: usize,
    pub verdict: String,
    /// origin xyz, dir xyz, t_min, t_max as hex f32 bit patterns.
    pub ray_bits: Vec<String>,
    pub ray: RayDecimal,
    /// `null` is a miss (or, for any-hit workloads, "not occluded").
    pub ours: Option<HitRecord>,
    pub reference: Option<HitRecord>,
}

/// The same ray in decimal, for people (inputs are always finite except `t_max = inf`,
/// written as `null`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RayDecimal {
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub t_min: f32,
    pub t_max: Option<f32>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HitRecord {
    pub prim: u32,
    pub t: f32,
    pub t_bits: String,
    pub u: f32,
    pub v: f32,
}

impl HitRecord {
    pub fn from_hit(h: &Hit) -> HitRecord {
        // Hits always have finite t (t <= t_max and t > t_min >= 0 with finite coordinates).
        HitRecord {
            prim: h.prim,
            t: h.t,
            t_bits: format!("{:#010x}", h.t.to_bits()),
            u: h.u,
            v: h.v,
        }
    }
}

impl DisputedRay {
    pub fn new(
        index: usize,
        verdict: &str,
        ray: &Ray,
        ours: Option<Hit>,
        reference: Option<Hit>,
    ) -> DisputedRay {
        DisputedRay {
            index,
            verdict: verdict.to_string(),
            ray_bits: ray.to_bits().iter().map(|b| format!("{b:#010x}")).collect(),
            ray: RayDecimal {
                origin: ray.origin().to_array(),
                dir: ray.dir().to_array(),
                t_min: ray.t_min(),
                t_max: ray.t_max().is_finite().then_some(ray.t_max()),
            },
            ours: ours.as_ref().map(HitRecord::from_hit),
            reference: reference.as_ref().map(HitRecord::from_hit),
        }
    }
}

/// A closest-point query two answers disagree on, with the bits to replay it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisputedPoint {
    pub index: usize,
    pub verdict: String,
    /// x, y, z as hex f32 bit patterns.
    pub point_bits: Vec<String>,
    pub point: [f32; 3],
    /// The search radius; `null` is infinite (the workloads' radius).
    pub radius: Option<f32>,
    /// `null`: no triangle within the radius.
    pub ours: Option<PointRecord>,
    pub reference: Option<PointRecord>,
}

/// A closest-point answer: the triangle, the nearest point on it and the distance (with bits).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointRecord {
    pub prim: u32,
    pub point: [f32; 3],
    pub distance: f32,
    pub distance_bits: String,
}

impl DisputedPoint {
    pub fn new(
        index: usize,
        verdict: &str,
        p: Vec3,
        radius: f32,
        ours: Option<PointHit>,
        reference: Option<PointHit>,
    ) -> DisputedPoint {
        let record = |h: PointHit| PointRecord {
            prim: h.prim,
            point: h.point.to_array(),
            distance: h.distance,
            distance_bits: format!("{:#010x}", h.distance.to_bits()),
        };
        DisputedPoint {
            index,
            verdict: verdict.to_string(),
            point_bits: p
                .to_array()
                .iter()
                .map(|c| format!("{:#010x}", c.to_bits()))
                .collect(),
            point: p.to_array(),
            radius: radius.is_finite().then_some(radius),
            ours: ours.map(record),
            reference: reference.map(record),
        }
    }
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}
