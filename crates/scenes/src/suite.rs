//! Suite manifests: JSON files in the repository's `bench-scenes/` naming scenes, structures,
//! workloads and the ray and point counts of a benchmark run.

use crate::{SceneError, Workload};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One benchmark suite, as read from a manifest.
#[derive(Deserialize, Serialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    pub name: String,
    pub description: String,
    pub scenes: Vec<SuiteScene>,
    /// Structure names as the harness knows them ("bvh-binned-sah", "embree-high", …).
    pub structures: Vec<String>,
    pub workloads: Vec<Workload>,
    /// Rays per workload (primary rays: about this many pixels).
    pub rays: usize,
    /// Query points per closest-point workload (`points-near`, `points-volume`); absent means
    /// the harness default. Separate from `rays` because a closest-point query costs about a
    /// hundred times a ray (bvh on the bunny: ~0.5 Mqueries/s near the surface).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<usize>,
    /// The seed of the scenes and rays when the command gives none; absent means the
    /// command's default (1). A suite of scenes held out from tuning names its own, so that
    /// it differs from the seed every tuning run used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// A scene of a suite: a [`generate`](fn@crate::generate) spec, or an OBJ file.
#[derive(Deserialize, Serialize, Clone, Debug, PartialEq)]
#[serde(untagged)]
pub enum SuiteScene {
    Generated(String),
    File {
        /// Relative to the directory of the manifest file.
        obj: String,
        /// An optional file that is absent is skipped with a note; present but broken is an error.
        #[serde(default)]
        optional: bool,
    },
}

/// Reads and checks a manifest: valid JSON of the right shape, no unknown fields, and at least
/// one scene, structure and workload, and a non-zero ray count.
pub fn load_suite(path: &Path) -> Result<Suite, SceneError> {
    let bytes = crate::input::read_input(path)?;
    let suite: Suite = serde_json::from_slice(&bytes).map_err(|source| SceneError::SuiteJson {
        path: path.to_owned(),
        source,
    })?;
    check_suite(&suite).map_err(|problem| SceneError::Suite {
        path: path.to_owned(),
        problem,
    })?;
    Ok(suite)
}

fn check_suite(suite: &Suite) -> Result<(), String> {
    let empty = [
        ("scenes", suite.scenes.is_empty()),
        ("structures", suite.structures.is_empty()),
        ("workloads", suite.workloads.is_empty()),
    ];
    if let Some((field, _)) = empty.iter().find(|(_, is_empty)| *is_empty) {
        return Err(format!("suite `{}` lists no {field}", suite.name));
    }
    if suite.rays == 0 {
        return Err(format!("suite `{}` has rays = 0", suite.name));
    }
    if suite.points == Some(0) {
        return Err(format!("suite `{}` has points = 0", suite.name));
    }
    Ok(())
}

/// The repository's `bench-scenes/` directory: `$RAYBENCH_SUITES` if set, else the directory
/// next to this crate's workspace.
pub fn suites_dir() -> PathBuf {
    match std::env::var_os("RAYBENCH_SUITES") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../bench-scenes")),
    }
}

/// Every `*.json` manifest in [`suites_dir`], sorted by file name. Any broken manifest is an error.
pub fn list_suites() -> Result<Vec<(PathBuf, Suite)>, SceneError> {
    let dir = suites_dir();
    let entries = std::fs::read_dir(&dir).map_err(|e| SceneError::io(&dir, e))?;
    let mut paths = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| SceneError::io(&dir, e))?.path();
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        {
            paths.push(path);
        }
    }
    paths.sort();
    paths
        .into_iter()
        .map(|p| load_suite(&p).map(|s| (p, s)))
        .collect()
}
