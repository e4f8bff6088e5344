//! The reports raybench writes, one module per kind (`report.json`, `verify.json`,
//! `watertight.json`), the diff of two run reports behind `raybench compare`, and the atomic
//! JSON writer they share.

pub mod agreement;
pub mod compare;
pub mod run;
pub mod verify;
pub mod watertight;

use serde::Serialize;
use std::path::Path;

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
