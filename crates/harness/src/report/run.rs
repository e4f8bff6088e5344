//! `report.json`: the data model, written atomically and read back with serde.
//!
//! Every float in the report is finite: a miss is an explicit `null` hit, never `t = inf`
//! (serde_json writes non-finite floats as `null` and then cannot read them back), and exact
//! ray and hit values are carried as hex bit patterns so a disputed ray can be replayed.

use super::agreement::Agreement;
use super::{Header, read_report, write_json_atomic};
use raybench_accel::classify::Tolerance;
use raybench_accel::{BuildStats, Counters, Memory};
use raybench_geom::RemovedTriangles;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Bumped whenever a field changes meaning, is renamed or disappears.
pub const SCHEMA_VERSION: u32 = 2;

/// The oldest schema version still read (version 1 through the old names of the fields of
/// [`WorkloadResult`] and [`WorkloadRecord`]).
pub const OLDEST_READABLE: u32 = 1;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    #[serde(flatten)]
    pub header: Header,
    pub run: RunSettings,
    pub scenes: Vec<SceneRecord>,
    pub results: Vec<ResultEntry>,
    /// Things the reader should know: skipped structures, absent optional scenes, …
    pub notes: Vec<String>,
    /// Scenes or structures that failed (the rest of the run went on).
    pub errors: Vec<String>,
    /// The claims this run's data decides (see [`super::claims`]); empty in older reports.
    #[serde(default)]
    pub claims: Vec<super::claims::Claim>,
    /// Full-resolution pictures of the primary view, one entry per scene that has them (see
    /// docs/report-format.md, "Pictures"); empty in older reports and runs without pictures.
    #[serde(default)]
    pub pictures: Vec<crate::pipeline::picture::PictureSet>,
    /// Present when the run was interrupted: it holds the scenes it finished, and what is left
    /// to run (`raybench run --resume DIR` runs it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub incomplete: Option<Incomplete>,
}

/// What an interrupted run left undone.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Incomplete {
    pub reason: String,
    /// The scene requests not finished, in order (the one being measured when the run stopped
    /// first: its partial results are not in the report).
    pub remaining: Vec<RequestRecord>,
}

/// A scene request as the run was given it, so a resumed run asks for the same scenes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RequestRecord {
    /// A generator spec or an `.obj` path.
    Spec(String),
    /// A suite's OBJ entry (resolved path).
    File {
        path: std::path::PathBuf,
        optional: bool,
    },
}

impl From<&raybench_scenes::SceneRequest> for RequestRecord {
    fn from(r: &raybench_scenes::SceneRequest) -> Self {
        match r {
            raybench_scenes::SceneRequest::Spec(s) => RequestRecord::Spec(s.clone()),
            raybench_scenes::SceneRequest::File { path, optional } => RequestRecord::File {
                path: path.clone(),
                optional: *optional,
            },
        }
    }
}

impl From<&RequestRecord> for raybench_scenes::SceneRequest {
    fn from(r: &RequestRecord) -> Self {
        match r {
            RequestRecord::Spec(s) => raybench_scenes::SceneRequest::Spec(s.clone()),
            RequestRecord::File { path, optional } => raybench_scenes::SceneRequest::File {
                path: path.clone(),
                optional: *optional,
            },
        }
    }
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
    /// `--time-budget` in seconds: extra rounds while ratios are imprecise (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_budget_s: Option<f64>,
    pub tolerance: Tolerance,
    pub structures: Vec<String>,
    pub workloads: Vec<String>,
    /// Recursion control of the `whitted` workload.
    pub whitted: raybench_scenes::WhittedParams,
    /// Keep per-pixel pictures (absent in older reports: true).
    #[serde(default = "yes")]
    pub images: bool,
    /// Skip structures above their suite triangle limit (absent in older reports: false).
    #[serde(default)]
    pub suite_limits: bool,
    /// Flush-to-zero and denormals-are-zero on every worker (absent in older reports: false).
    #[serde(default)]
    pub ftz_daz: bool,
    /// Width of the full-resolution pictures (absent in older reports: 0, none drawn).
    #[serde(default)]
    pub picture_width: u32,
}

fn yes() -> bool {
    true
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
    /// Rays, or query points for a point workload.
    #[serde(alias = "rays")]
    pub queries: usize,
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
    /// Build time divided by the reference's in this run: the median of the per-round ratios
    /// (the ratio of the medians in reports without samples).
    pub build_ratio_to_reference: Option<f64>,
    /// Its confidence interval over the rounds (absent with fewer than two rounds, and in
    /// older reports).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_ratio_interval: Option<super::interval::Interval>,
    pub memory_bytes: u64,
    pub memory: Memory,
    pub build_stats: BuildStats,
    pub workloads: Vec<WorkloadResult>,
    /// Workloads the structure cannot answer (a peer crate without closest-point queries): run
    /// for no one, reported as "not offered", never as a number. Absent when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_offered: Vec<String>,
    /// Per-pixel pictures of the primary workload (absent when it was not run).
    #[serde(default)]
    pub primary_image: Option<crate::pipeline::images::PrimaryImage>,
}

/// Wall-clock build time over `runs` builds after one warm-up build.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Timing {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub runs: usize,
    /// Every timed build, in round order (absent in older reports).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub samples_ms: Vec<f64>,
}

/// Millions of queries per second over `runs` timed passes after one warm-up pass.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Throughput {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub runs: usize,
    /// Every timed pass, in round order (absent in older reports).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub samples: Vec<f64>,
}

impl Timing {
    pub fn from_samples(samples_ms: Vec<f64>) -> Timing {
        let (median_ms, min_ms, max_ms) = median_min_max(&samples_ms);
        Timing {
            median_ms,
            min_ms,
            max_ms,
            runs: samples_ms.len(),
            samples_ms,
        }
    }
}

impl Throughput {
    pub fn from_samples(samples: Vec<f64>) -> Throughput {
        let (median, min, max) = median_min_max(&samples);
        Throughput {
            median,
            min,
            max,
            runs: samples.len(),
            samples,
        }
    }
}

/// Median, minimum and maximum of samples (the median of an even count is the mean of the
/// middle two); zeros for none.
pub fn median_min_max(samples: &[f64]) -> (f64, f64, f64) {
    let Some((median, _)) = super::interval::median_with_interval(samples) else {
        return (0.0, 0.0, 0.0);
    };
    let min = samples.iter().copied().fold(f64::INFINITY, f64::min);
    let max = samples.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (median, min, max)
}

/// One structure on one workload. A query is a ray in a ray workload and a point in a
/// closest-point workload (`point_query`): there `prim_tests` counts point–triangle distance
/// tests and `both_miss` means neither side found a triangle. Reports of schema version 1 named
/// four fields after rays (`rays`, `mrays_per_s`, `counters_per_ray`, `validation`); they are
/// read under those names too.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WorkloadResult {
    pub workload: String,
    /// Rays, or query points for a point workload.
    #[serde(alias = "rays")]
    pub queries: usize,
    pub any_hit: bool,
    /// True for a closest-point workload (absent in older reports: false).
    #[serde(default)]
    pub point_query: bool,
    /// Millions of queries per second: rays, or closest-point queries when `point_query`.
    #[serde(alias = "mrays_per_s")]
    pub mqueries_per_s: Throughput,
    /// Throughput divided by the reference's in this run (> 1: faster than reference): the
    /// median of the per-round ratios (the ratio of the medians in reports without samples,
    /// and when either side was timed once).
    pub speedup_vs_reference: Option<f64>,
    /// Its confidence interval over the rounds (absent when either side was timed once, and
    /// in older reports).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speedup_interval: Option<super::interval::Interval>,
    /// `None` for structures that cannot count their work (Embree).
    #[serde(alias = "counters_per_ray")]
    pub counters_per_query: Option<CountersPerQuery>,
    pub counters_total: Option<Counters>,
    #[serde(alias = "validation")]
    pub agreement: Agreement,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct CountersPerQuery {
    pub nodes: f64,
    pub leaves: f64,
    pub prim_tests: f64,
    pub cells: f64,
    pub mailbox_skips: f64,
    /// Absent in reports written before jumps were counted: 0.
    #[serde(default)]
    pub jumps: f64,
}

impl CountersPerQuery {
    pub fn from_total(c: &Counters, queries: usize) -> CountersPerQuery {
        let n = queries.max(1) as f64;
        CountersPerQuery {
            nodes: c.nodes as f64 / n,
            leaves: c.leaves as f64 / n,
            prim_tests: c.prim_tests as f64 / n,
            cells: c.cells as f64 / n,
            mailbox_skips: c.mailbox_skips as f64 / n,
            jumps: c.jumps as f64 / n,
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
        read_report(path, OLDEST_READABLE..=SCHEMA_VERSION)
    }

    /// Total mismatches over every structure, scene and workload.
    pub fn mismatches(&self) -> u64 {
        self.results
            .iter()
            .flat_map(|r| &r.workloads)
            .map(|w| w.agreement.counts.mismatch + w.agreement.counted_path_differs)
            .sum()
    }
}

/// True for a closest-point workload's name (`points-near`, `points-volume`).
pub fn is_point_workload(workload: &str) -> bool {
    workload
        .parse::<raybench_scenes::Workload>()
        .is_ok_and(|w| w.is_point_query())
}

/// What a workload's `mqueries_per_s` counts: "Mqueries/s" for closest-point workloads,
/// "Mrays/s" for ray workloads.
pub fn throughput_unit(workload: &str) -> &'static str {
    if is_point_workload(workload) {
        "Mqueries/s"
    } else {
        "Mrays/s"
    }
}
