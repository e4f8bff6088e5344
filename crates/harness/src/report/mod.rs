//! The reports raybench writes, one module per kind (`report.json`, `verify.json`,
//! `watertight.json`), the diff of two run reports behind `raybench compare`, and what the
//! kinds share: the header every report opens with, the atomic JSON writer and the reader.

pub mod agreement;
pub mod claims;
pub mod compare;
pub mod interval;
pub mod run;
pub mod verify;
pub mod watertight;

use crate::env::Environment;
use anyhow::{Context, Result, ensure};
use raybench_scenes::input::read_input;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

/// What every report opens with: its format version, the raybench that wrote it and the
/// environment it ran in. Each report flattens it, so these keys stay at the top level.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Header {
    /// The version of this kind of report's format (see each kind's `SCHEMA_VERSION`).
    pub schema_version: u32,
    pub tool_version: String,
    pub environment: Environment,
}

impl Header {
    /// The header of a report written now by this raybench.
    pub fn new(schema_version: u32, environment: Environment) -> Header {
        Header {
            schema_version,
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            environment,
        }
    }
}

/// Reads a report of kind `T` from `path`. A schema version outside `versions` is refused
/// before the rest is parsed, so a report from another raybench fails with its version named,
/// not with a missing field.
pub fn read_report<T: DeserializeOwned>(path: &Path, versions: RangeInclusive<u32>) -> Result<T> {
    #[derive(Deserialize)]
    struct Version {
        schema_version: Option<u32>,
    }
    let bytes = read_input(path)?;
    let found = serde_json::from_slice::<Version>(&bytes)
        .with_context(|| format!("parsing {}", path.display()))?
        .schema_version;
    ensure!(
        found.is_some_and(|v| versions.contains(&v)),
        "{}: schema_version {} is not one this raybench reads ({} to {})",
        path.display(),
        found.map_or("absent".to_string(), |v| v.to_string()),
        versions.start(),
        versions.end()
    );
    serde_json::from_slice(&bytes).with_context(|| format!("parsing {}", path.display()))
}

/// Serialises `value` as pretty JSON into `dir/name`, atomically, creating `dir` if needed.
pub fn write_json_atomic<T: Serialize>(dir: &Path, name: &str, value: &T) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let target = dir.join(name);
    let json = serde_json::to_vec_pretty(value).with_context(|| format!("serialising {name}"))?;
    crate::atomic::write_atomic(&target, &json)?;
    Ok(target)
}
