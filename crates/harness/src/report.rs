//! `report.json`: the data model, written atomically and read back with serde.
//!
//! Every float in the report is finite: a miss is an explicit `null` hit, never `t = inf`
//! (serde_json writes non-finite floats as `null` and then cannot read them back), and exact
//! ray and hit values are carried as hex bit patterns so a disputed ray can be replayed.

use crate::env::Environment;
use raybench_accel::classify::{Tolerance, VerdictCounts};
use raybench_accel::{BuildStats, Counters, Hit, Memory, PointHit};
use raybench_geom::{Ray, RemovedTriangles, Vec3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Bumped whenever a field changes meaning or disappears.
pub const SCHEMA_VERSION: u32 = 1;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    pub schema_version: u32,
    pub tool_version: String,
    pub environment: Environment,
    pub run: RunSettings,
    pub scenes: Vec<SceneRecord>,
    pub results: Vec<ResultEntry>,
    /// Things the reader should know: skipped structures, absent optional scenes, …
    pub notes: Vec<String>,
    /// Scenes or structures that failed (the rest of the run went on).
    pub errors: Vec<String>,
}

/// The knobs of the run itself.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunSettings {
    pub suite: Option<String>,
    pub seed: u64,
    pub rays: usize,
    /// Query points per closest-point workload (0 in reports older than point workloads).
    #[serde(default)]
    pub points: usize,
    pub threads: usize,
    pub reference: String,
    pub build_runs: usize,
    pub trace_runs: usize,
    pub tolerance: Tolerance,
    pub structures: Vec<String>,
    pub workloads: Vec<String>,
    /// Recursion control of the `whitted` workload.
    pub whitted: raybench_scenes::WhittedParams,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneRecord {
    pub name: String,
    pub source: serde_json::Value,
    pub triangles: TriangleCounts,
    pub load_ms: f64,
    pub loader_notes: Vec<String>,
    pub view: serde_json::Value,
    /// Workloads as generated for this scene (same rays for every structure).
    pub workloads: Vec<WorkloadRecord>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WorkloadRecord {
    pub workload: String,
    /// Queries: rays, or query points for a point workload.
    pub rays: usize,
    pub any_hit: bool,
    /// A closest-point workload (`points-near`, `points-volume`), asked with an infinite radius.
    #[serde(default)]
    pub point_query: bool,
    /// Primary image size, where the workload is an image.
    pub width: Option<u32>,
    pub height: Option<u32>,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct TriangleCounts {
    /// Triangles the loader or generator produced.
    pub loaded: u64,
    /// Removed before any structure saw them (what Embree would silently ignore).
    pub removed: u64,
    pub removed_by_reason: RemovedTriangles,
    /// Triangles every structure traces (`loaded - removed`).
    pub traced: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ResultEntry {
    pub scene: String,
    pub triangles: TriangleCounts,
    pub structure: String,
    pub params: serde_json::Value,
    pub build: Timing,
    /// Build median divided by the reference's build median in this run.
    pub build_ratio_to_reference: Option<f64>,
    pub memory_bytes: u64,
    pub memory: Memory,
    pub build_stats: BuildStats,
    pub workloads: Vec<WorkloadResult>,
    /// Per-pixel pictures of the primary workload (absent when it was not run).
    #[serde(default)]
    pub primary_image: Option<crate::images::PrimaryImage>,
}

/// Wall-clock build time over `runs` builds after one warm-up build.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Timing {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub runs: usize,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Throughput {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub runs: usize,
}

/// One structure on one workload. For a closest-point workload (`point_query`), `rays` counts
/// query points, `mrays_per_s` is millions of queries per second, `counters_per_ray` is per
/// query (`prim_tests` = point–triangle distance tests) and the validation classes count
/// queries (`both_miss` = neither found a triangle).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WorkloadResult {
    pub workload: String,
    /// Queries: rays, or query points for a point workload.
    pub rays: usize,
    pub any_hit: bool,
    /// True for a closest-point workload (absent in older reports: false).
    #[serde(default)]
    pub point_query: bool,
    /// Millions of queries per second: rays, or closest-point queries when `point_query`.
    pub mrays_per_s: Throughput,
    /// Median throughput divided by the reference's in this run (> 1: faster than reference).
    pub speedup_vs_reference: Option<f64>,
    /// `None` for structures that cannot count their work (Embree).
    pub counters_per_ray: Option<CountersPerRay>,
    pub counters_total: Option<Counters>,
    pub validation: Validation,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct CountersPerRay {
    pub nodes: f64,
    pub leaves: f64,
    pub prim_tests: f64,
    pub cells: f64,
    pub mailbox_skips: f64,
}

impl CountersPerRay {
    pub fn from_total(c: &Counters, rays: usize) -> CountersPerRay {
        let n = rays.max(1) as f64;
        CountersPerRay {
            nodes: c.nodes as f64 / n,
            leaves: c.leaves as f64 / n,
            prim_tests: c.prim_tests as f64 / n,
            cells: c.cells as f64 / n,
            mailbox_skips: c.mailbox_skips as f64 / n,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Validation {
    pub reference: String,
    /// Rays per class: `both_miss`, `exact`, `within_tolerance`, `tie`, `boundary`,
    /// `edge_ambiguous`, `mismatch` (written flat into this object).
    #[serde(flatten)]
    pub counts: VerdictCounts,
    /// Rays where the counted path answered differently from the timed path (a bug).
    pub counted_path_differs: u64,
    /// Rays where the timed path (a packet walk of coherent rays) and the counted single-ray
    /// walk report different triangles at the same distance: an order-decided tie, not a bug.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub counted_path_ties: u64,
    /// With 0 mismatches in n rays, the 95 % upper bound on the mismatch rate (rule of three).
    pub mismatch_rate_upper95: f64,
    pub first_mismatches: Vec<DisputedRay>,
    /// First few explained disagreements (boundary, edge-ambiguous), for replay.
    pub first_ambiguous: Vec<DisputedRay>,
    /// Point workloads: the first mismatched queries, with the point's bits for replay.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub first_point_mismatches: Vec<DisputedPoint>,
}

impl Validation {
    pub fn new(reference: &str, counts: VerdictCounts) -> Validation {
        let n = counts.total().max(1) as f64;
        let upper95 = if counts.mismatch == 0 {
            (3.0 / n).min(1.0)
        } else {
            counts.mismatch as f64 / n
        };
        Validation {
            reference: reference.to_string(),
            counts,
            counted_path_differs: 0,
            counted_path_ties: 0,
            mismatch_rate_upper95: upper95,
            first_mismatches: Vec::new(),
            first_ambiguous: Vec::new(),
            first_point_mismatches: Vec::new(),
        }
    }

    pub fn rays(&self) -> u64 {
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

impl Report {
    /// Writes `dir/report.json` atomically (see [`crate::atomic`]): readers never see a
    /// half-written report, and a failed write leaves no temporary file.
    pub fn write_atomic(&self, dir: &Path) -> anyhow::Result<std::path::PathBuf> {
        write_json_atomic(dir, "report.json", self)
    }

    pub fn read(path: &Path) -> anyhow::Result<Report> {
        use anyhow::Context;
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let report: Report = serde_json::from_slice(&bytes)
            .with_context(|| format!("parsing {}", path.display()))?;
        anyhow::ensure!(
            report.schema_version == SCHEMA_VERSION,
            "{}: schema_version {} is not the supported {}",
            path.display(),
            report.schema_version,
            SCHEMA_VERSION
        );
        Ok(report)
    }

    /// Total mismatches over every structure, scene and workload.
    pub fn mismatches(&self) -> u64 {
        self.results
            .iter()
            .flat_map(|r| &r.workloads)
            .map(|w| w.validation.counts.mismatch + w.validation.counted_path_differs)
            .sum()
    }
}

/// True for a closest-point workload's name (`points-near`, `points-volume`).
pub fn is_point_workload(workload: &str) -> bool {
    workload
        .parse::<raybench_scenes::Workload>()
        .is_ok_and(|w| w.is_point_query())
}

/// What a workload's `mrays_per_s` counts: "Mqueries/s" for closest-point workloads,
/// "Mrays/s" for ray workloads.
pub fn throughput_unit(workload: &str) -> &'static str {
    if is_point_workload(workload) {
        "Mqueries/s"
    } else {
        "Mrays/s"
    }
}

/// Serialises `value` as pretty JSON into `dir/name`, atomically, creating `dir` if needed.
pub fn write_json_atomic<T: Serialize>(
    dir: &Path,
    name: &str,
    value: &T,
) -> anyhow::Result<std::path::PathBuf> {
    use anyhow::Context;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let target = dir.join(name);
    let json = serde_json::to_vec_pretty(value).with_context(|| format!("serialising {name}"))?;
    crate::atomic::write_atomic(&target, &json)?;
    Ok(target)
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}
