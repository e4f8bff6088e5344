//! Files that appear whole or not at all: every report, dump and chart is written to a
//! temporary file beside its target, flushed to disk, then renamed over the target. A failure
//! at any step removes the temporary file, so a failed or interrupted write leaves neither a
//! half-written file nor a stray temporary one (only a kill between `create` and `rename` can
//! leave a `.<name>.<pid>.tmp` behind, never a truncated target).

use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

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
    let tmp = temp_path(path);
    let result = (|| -> Result<()> {
        let mut f =
            std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        f.write_all(bytes)
            .and_then(|_| f.sync_all())
            .with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, path)
            .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Creates `dir` if needed and proves a file can be created in it, before any work is done:
/// an unwritable `--out` fails in a second, not after an hour of measuring.
pub fn ensure_writable_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("output directory {} cannot be created", dir.display()))?;
    let probe = temp_path(&dir.join("write-probe"));
    std::fs::File::create(&probe)
        .with_context(|| format!("output directory {} is not writable", dir.display()))?;
    std::fs::remove_file(&probe).with_context(|| format!("removing {}", probe.display()))
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

    #[test]
    fn a_file_where_the_directory_should_be_is_not_writable() {
        let d = scratch("notdir");
        let file = d.join("plain-file");
        std::fs::write(&file, b"x").unwrap();
        let err = ensure_writable_dir(&file.join("sub")).unwrap_err();
        assert!(format!("{err:#}").contains("plain-file"), "{err:#}");
        ensure_writable_dir(&d.join("fresh")).unwrap();
        assert_eq!(entries(&d.join("fresh")), Vec::<String>::new());
        std::fs::remove_dir_all(d).unwrap();
    }
}
