//! `watertight.json`: the schema of what `raybench watertight` writes.

use super::{Header, write_json_atomic};
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Embree's pass mark for `watertight_*` in robust mode (tutorials/verify/verify.cpp).
pub const EMBREE_ROBUST_BAR: f64 = 2e-5;

/// One mesh at one place.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Case {
    pub name: String,
    /// The generator spec.
    pub spec: String,
    /// Added to every vertex in f64, then rounded to f32 once.
    pub shift: [f64; 3],
}

/// Bumped whenever a field of `watertight.json` changes meaning, is renamed or disappears.
pub const WATERTIGHT_SCHEMA_VERSION: u32 = 1;

/// `watertight.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WatertightReport {
    #[serde(flatten)]
    pub header: Header,
    pub seed: u64,
    pub embree_robust_bar: f64,
    pub cases: Vec<CaseRecord>,
    pub results: Vec<MissRate>,
    /// Per structure over every case.
    pub totals: Vec<MissRate>,
    pub errors: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CaseRecord {
    pub case: Case,
    pub triangles: usize,
    pub edge_rays: usize,
    pub vertex_rays: usize,
    /// Generated rays the f64 test did not confirm as crossings (left out of every rate).
    pub dropped: usize,
}

/// Rays traced and missed, and how many of each were aimed at a vertex (the rest at edges).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    pub rays: usize,
    pub misses: usize,
    pub vertex_rays: usize,
    pub vertex_misses: usize,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, o: Tally) {
        self.rays += o.rays;
        self.misses += o.misses;
        self.vertex_rays += o.vertex_rays;
        self.vertex_misses += o.vertex_misses;
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MissRate {
    pub case: String,
    pub structure: String,
    pub rays: usize,
    pub misses: usize,
    /// Of `rays` and `misses`, those aimed at vertices (the rest were aimed at edges).
    pub vertex_rays: usize,
    pub vertex_misses: usize,
    pub miss_rate: f64,
    /// 95 % upper bound: 3/n with no miss (rule of three), else the observed rate.
    pub upper95: f64,
}

impl MissRate {
    pub fn new(case: &str, structure: &str, t: Tally) -> MissRate {
        let n = t.rays.max(1) as f64;
        let rate = t.misses as f64 / n;
        MissRate {
            case: case.to_string(),
            structure: structure.to_string(),
            rays: t.rays,
            misses: t.misses,
            vertex_rays: t.vertex_rays,
            vertex_misses: t.vertex_misses,
            miss_rate: rate,
            upper95: if t.misses == 0 {
                (3.0 / n).min(1.0)
            } else {
                rate
            },
        }
    }

    /// Against Embree's bar: within it, over it, or too few rays to tell.
    pub fn judgement(&self) -> &'static str {
        if self.miss_rate > EMBREE_ROBUST_BAR {
            "over the bar"
        } else if self.upper95 > EMBREE_ROBUST_BAR {
            "0 misses, too few rays to show <= 2e-5"
        } else {
            "within the bar"
        }
    }
}

impl WatertightReport {
    pub fn write_atomic(&self, dir: &Path) -> Result<PathBuf> {
        write_json_atomic(dir, "watertight.json", self)
    }
}
