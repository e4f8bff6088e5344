//! Files that appear whole or not at all: every file raybench writes (reports, dumps, charts,
//! pictures, exported scenes) is written to a temporary file beside its target, flushed to
//! disk, then renamed over the target. A failure at any step removes the temporary file, and
//! so does an interrupt: the temporary files being written are listed while they exist, and
//! the Ctrl-C handler ([`crate::interrupt`]) removes them before the process exits. Only a
//! `kill -9` between `create` and `rename` can leave a `.<name>.<pid>.tmp` behind; a target is
//! never truncated.

use anyhow::{Context, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporary files being written now.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A temporary file listed in [`LIVE`] from creation until it is renamed or removed.
struct Temporary(PathBuf);

impl Temporary {
    fn new(path: PathBuf) -> Temporary {
        live().push(path.clone());
        Temporary(path)
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        live().retain(|p| p != &self.0);
    }
}

/// Removes every temporary file being written (the interrupt handler's clean-up).
pub fn remove_temporaries() {
    for p in live().drain(..) {
        let _ = std::fs::remove_file(&p);
    }
}

/// The temporary name used for `path`: hidden, and unique per process.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes `bytes` to `path` atomically (see the module documentation).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes what `fill` writes to `path` atomically, streaming it (see the module
/// documentation).
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let tmp = Temporary::new(temp_path(path));
    let result = (|| -> Result<()> {
        let f = std::fs::File::create(&tmp.0)
            .with_context(|| format!("creating {}", tmp.0.display()))?;
        let mut w = BufWriter::new(f);
        fill(&mut w)
            .and_then(|()| w.flush())
            .with_context(|| format!("writing {}", tmp.0.display()))?;
        let f = w
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("writing {}", tmp.0.display()))?;
        f.sync_all()
            .with_context(|| format!("writing {}", tmp.0.display()))?;
        std::fs::rename(&tmp.0, path)
            .with_context(|| format!("renaming {} to {}", tmp.0.display(), path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp.0);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-atomic-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn replaces_the_target_and_leaves_no_temporary_file() {
        let d = scratch("ok");
        let target = d.join("a.bin");
        write_atomic(&target, b"first").unwrap();
        write_atomic(&target, b"second").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"second");
        assert_eq!(entries(&d), ["a.bin"]);
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_failed_rename_removes_the_temporary_file() {
        // The target is a non-empty directory: the rename fails after the write succeeded.
        let d = scratch("fail");
        let target = d.join("taken");
        std::fs::create_dir_all(target.join("inside")).unwrap();
        let err = write_atomic(&target, b"data").unwrap_err();
        assert!(format!("{err:#}").contains("taken"), "{err:#}");
        assert_eq!(entries(&d), ["taken"]);
        std::fs::remove_dir_all(d).unwrap();
    }
}
