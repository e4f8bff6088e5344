//! `verify.json`: the schema of what `raybench verify` writes, and reading it back.

use super::agreement::Agreement;
use super::run::TriangleCounts;
use super::{Header, read_report, write_json_atomic};
use anyhow::Result;
use raybench_accel::classify::{Tolerance, VerdictCounts};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Bumped whenever a field of `verify.json` changes meaning, is renamed or disappears.
pub const VERIFY_SCHEMA_VERSION: u32 = 2;

/// The oldest version still read (version 1 through the old names: `rays`,
/// `brute_force_rays`, `validations`).
pub const VERIFY_OLDEST_READABLE: u32 = 1;

/// `verify.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifyReport {
    #[serde(flatten)]
    pub header: Header,
    pub settings: VerifySettings,
    pub scenes: Vec<VerifiedScene>,
    /// One entry per scene × structure × workload, with one agreement record per reference.
    pub results: Vec<VerifiedWorkload>,
    /// Per structure × reference, summed over scenes and workloads (what the table prints).
    pub totals: Vec<AgreementRow>,
    pub notes: Vec<String>,
    pub errors: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifySettings {
    pub suite: Option<String>,
    pub seed: u64,
    pub rays: usize,
    /// Query points per closest-point workload (0 in files older than point workloads).
    #[serde(default)]
    pub points: usize,
    pub threads: usize,
    pub structures: Vec<String>,
    pub workloads: Vec<String>,
    pub references: Vec<String>,
    /// Ray–triangle tests brute force may spend per scene × workload.
    pub brute_force_budget: u64,
    pub tolerance: Tolerance,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifiedScene {
    /// The name results use (unique within the run).
    pub name: String,
    /// What `raybench replay --scene` takes to rebuild it (a spec or an OBJ path).
    pub spec: String,
    pub triangles: TriangleCounts,
    pub workloads: Vec<SampledWorkload>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SampledWorkload {
    pub workload: String,
    /// Rays, or query points for a point workload.
    #[serde(alias = "rays")]
    pub queries: usize,
    /// Queries the `bruteforce` reference checked (evenly spaced; all when affordable).
    #[serde(alias = "brute_force_rays")]
    pub brute_force_queries: usize,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifiedWorkload {
    pub scene: String,
    pub structure: String,
    pub workload: String,
    pub any_hit: bool,
    /// Queries this structure answered: every one, or the brute-force subsample for brute
    /// force.
    #[serde(alias = "rays")]
    pub queries: usize,
    pub subsampled: bool,
    /// Queries where the counted path answered differently from the timed path, unexplained
    /// (a bug).
    pub counted_path_differs: u64,
    /// Queries where the two paths differ for an explained reason (classified like any
    /// disagreement: tie, edge-ambiguous, boundary, within tolerance).
    #[serde(default)]
    pub counted_path_explained: u64,
    /// One per reference, in [`crate::pipeline::verify::REFERENCES`] order. Disputed queries
    /// carry their index in the workload's full list.
    #[serde(alias = "validations")]
    pub agreements: Vec<Agreement>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AgreementRow {
    pub structure: String,
    pub reference: String,
    #[serde(alias = "rays")]
    pub queries: u64,
    #[serde(flatten)]
    pub counts: VerdictCounts,
    pub counted_path_differs: u64,
    #[serde(default)]
    pub counted_path_explained: u64,
    pub mismatch_rate_upper95: f64,
    /// "0 mismatches in n rays (95% upper bound 3/n = …)" or "k mismatches in n rays".
    pub agreement: String,
}

impl VerifyReport {
    /// Mismatches against any reference plus counted-path differences: anything non-zero is a
    /// bug somewhere (exit status 2).
    pub fn mismatches(&self) -> u64 {
        self.results
            .iter()
            .map(|r| {
                r.counted_path_differs + r.agreements.iter().map(|v| v.counts.mismatch).sum::<u64>()
            })
            .sum()
    }

    /// Writes `dir/verify.json` atomically.
    pub fn write_atomic(&self, dir: &Path) -> Result<PathBuf> {
        write_json_atomic(dir, "verify.json", self)
    }

    pub fn read(path: &Path) -> Result<VerifyReport> {
        read_report(path, VERIFY_OLDEST_READABLE..=VERIFY_SCHEMA_VERSION)
    }
}
