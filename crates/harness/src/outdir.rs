//! Output directories that cannot lose or mix runs.
//!
//! A command claims its directory before any work ([`OutDir::claim`]):
//! * the directory is locked (an advisory `flock` on the directory itself, held until the
//!   command ends), so a second raybench writing to it fails at once instead of interleaving
//!   its files with the first one's;
//! * every path the command will write is checked for the right kind (`report.json` a
//!   directory, `charts` a file) before the work, not found at the final rename;
//! * files an earlier command left there are refused, or removed with `--force`, so every
//!   file in the directory belongs to one run;
//! * a file is created and removed to prove the directory writable.
//!
//! The default directory, `reports/<date>-<revision>`, is never reused: [`OutDir::claim_new`]
//! creates the first free name (`…-2`, `…-3`, …) with one atomic `mkdir`.

use anyhow::{Context, Result, bail};
use std::fs::{File, TryLockError};
use std::path::{Path, PathBuf};

/// Something a command writes into its directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    File(&'static str),
    Dir(&'static str),
    /// Every file whose name ends with this (the hit dumps' `*.hits`).
    FilesEndingWith(&'static str),
    /// Every file whose name starts with the first and ends with the second (the scene pages'
    /// `scene-*.html`).
    FilesLike(&'static str, &'static str),
}

/// What `run` writes: the report, then its drawing.
pub const RUN: &[Output] = &[
    Output::File("report.json"),
    Output::File("index.html"),
    Output::File("charts.html"),
    Output::File("details.html"),
    Output::FilesLike("scene-", ".html"),
    Output::Dir("charts"),
    Output::Dir("images"),
];
/// What `report` writes next to a report.
pub const DRAWING: &[Output] = &[
    Output::File("index.html"),
    Output::File("charts.html"),
    Output::File("details.html"),
    Output::FilesLike("scene-", ".html"),
    Output::Dir("charts"),
    Output::Dir("images"),
];
pub const VERIFY: &[Output] = &[Output::File("verify.json")];
pub const WATERTIGHT: &[Output] = &[Output::File("watertight.json")];
/// What `--dump-hits` writes.
pub const DUMPS: &[Output] = &[Output::File("index.json"), Output::FilesEndingWith(".hits")];

/// A claimed output directory; the lock lasts as long as this value.
#[derive(Debug)]
pub struct OutDir {
    path: PathBuf,
    _lock: File,
}

impl OutDir {
    /// Claims `dir` (creating it) for a command that writes `outputs` (see the module
    /// documentation). With `force`, earlier outputs of the right kind are removed; without,
    /// they are an error that names them.
    pub fn claim(dir: &Path, outputs: &[Output], force: bool) -> Result<OutDir> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{} cannot be created", dir.display()))?;
        let lock =
            File::open(dir).with_context(|| format!("{} cannot be opened", dir.display()))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => bail!(
                "{} is in use by another raybench command (it holds the directory's lock): wait \
                 for it to finish, or choose another directory",
                dir.display()
            ),
            Err(TryLockError::Error(e)) => {
                return Err(e).with_context(|| format!("locking {}", dir.display()));
            }
        }
        let stale = stale_outputs(dir, outputs)?;
        if !stale.is_empty() {
            if !force {
                bail!(
                    "{} already holds the output of an earlier command ({}): give --force to \
                     replace it, or choose another directory",
                    dir.display(),
                    names(&stale)
                );
            }
            for p in &stale {
                let removed = if p.is_dir() {
                    std::fs::remove_dir_all(p)
                } else {
                    std::fs::remove_file(p)
                };
                removed.with_context(|| format!("removing {} (--force)", p.display()))?;
            }
        }
        prove_writable(dir)?;
        Ok(OutDir {
            path: dir.to_owned(),
            _lock: lock,
        })
    }

    /// Claims the directory of an interrupted run to finish it (`raybench run --resume`): locked
    /// like [`OutDir::claim`], but what the interrupted run wrote (its incomplete report and
    /// the pictures of the scenes it finished) stays, to be completed.
    pub fn claim_to_resume(dir: &Path) -> Result<OutDir> {
        let lock =
            File::open(dir).with_context(|| format!("{} cannot be opened", dir.display()))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => bail!(
                "{} is in use by another raybench command (it holds the directory's lock)",
                dir.display()
            ),
            Err(TryLockError::Error(e)) => {
                return Err(e).with_context(|| format!("locking {}", dir.display()));
            }
        }
        prove_writable(dir)?;
        Ok(OutDir {
            path: dir.to_owned(),
            _lock: lock,
        })
    }

    /// Claims a new directory `base/name`, or `base/name-2`, `-3`, … if that exists: a new run
    /// never lands in an earlier run's directory.
    pub fn claim_new(base: &Path, name: &str, outputs: &[Output]) -> Result<OutDir> {
        std::fs::create_dir_all(base)
            .with_context(|| format!("{} cannot be created", base.display()))?;
        for i in 1..=10_000 {
            let candidate = match i {
                1 => base.join(name),
                _ => base.join(format!("{name}-{i}")),
            };
            match std::fs::create_dir(&candidate) {
                Ok(()) => return OutDir::claim(&candidate, outputs, false),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    return Err(e)
                        .with_context(|| format!("{} cannot be created", candidate.display()));
                }
            }
        }
        bail!(
            "{} holds 10,000 directories named {name}-N: give --out",
            base.display()
        )
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The paths of `outputs` that exist in `dir`; an error when one has the wrong kind, which
/// `--force` does not remove (it may be the user's own data).
fn stale_outputs(dir: &Path, outputs: &[Output]) -> Result<Vec<PathBuf>> {
    let mut stale = Vec::new();
    for &output in outputs {
        match output {
            Output::File(name) | Output::Dir(name) => {
                let p = dir.join(name);
                let Ok(meta) = std::fs::symlink_metadata(&p) else {
                    continue;
                };
                let want_dir = matches!(output, Output::Dir(_));
                if meta.is_dir() != want_dir || meta.file_type().is_symlink() {
                    bail!(
                        "{} is {} where raybench writes {}: remove or rename it, or choose \
                         another directory",
                        p.display(),
                        kind(&meta),
                        if want_dir { "a directory" } else { "a file" }
                    );
                }
                stale.push(p);
            }
            Output::FilesEndingWith(suffix) => files_like(dir, "", suffix, &mut stale)?,
            Output::FilesLike(prefix, suffix) => files_like(dir, prefix, suffix, &mut stale)?,
        }
    }
    Ok(stale)
}

/// Adds the files of `dir` named `prefix…suffix` to `found`.
fn files_like(dir: &Path, prefix: &str, suffix: &str, found: &mut Vec<PathBuf>) -> Result<()> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
    for entry in entries {
        let entry = entry.with_context(|| format!("listing {}", dir.display()))?;
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        let name = entry.file_name().to_string_lossy().into_owned();
        if is_file && name.starts_with(prefix) && name.ends_with(suffix) {
            found.push(entry.path());
        }
    }
    Ok(())
}

fn kind(meta: &std::fs::Metadata) -> &'static str {
    if meta.file_type().is_symlink() {
        "a symbolic link"
    } else if meta.is_dir() {
        "a directory"
    } else if meta.is_file() {
        "a file"
    } else {
        "a special file"
    }
}

/// `a, b, c` or `a, b, c and 7 more`, by file name.
fn names(paths: &[PathBuf]) -> String {
    let shown: Vec<String> = paths
        .iter()
        .take(4)
        .map(|p| {
            p.file_name().map_or_else(
                || p.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            )
        })
        .collect();
    match paths.len().saturating_sub(shown.len()) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

/// Creates and removes a file, so an unwritable directory fails before any work.
fn prove_writable(dir: &Path) -> Result<()> {
    let probe = dir.join(format!(".raybench-write-probe.{}", std::process::id()));
    File::create(&probe).with_context(|| format!("{} is not writable", dir.display()))?;
    std::fs::remove_file(&probe).with_context(|| format!("removing {}", probe.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-outdir-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_second_claim_of_a_locked_directory_fails_at_once() {
        let d = scratch("lock");
        let first = OutDir::claim(&d, RUN, false).unwrap();
        let err = OutDir::claim(&d, RUN, false).unwrap_err().to_string();
        assert!(
            err.contains("is in use by another raybench command"),
            "{err}"
        );
        drop(first);
        OutDir::claim(&d, RUN, false).unwrap();
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn earlier_outputs_are_refused_or_removed_with_force() {
        let d = scratch("stale");
        std::fs::write(d.join("report.json"), "{}").unwrap();
        std::fs::create_dir_all(d.join("charts")).unwrap();
        std::fs::write(d.join("charts/old.svg"), "<svg/>").unwrap();
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        let err = OutDir::claim(&d, RUN, false).unwrap_err().to_string();
        assert!(err.contains("(report.json, charts): give --force"), "{err}");
        OutDir::claim(&d, RUN, true).unwrap();
        assert!(!d.join("report.json").exists() && !d.join("charts").exists());
        assert!(
            d.join("notes.txt").exists(),
            "files raybench does not write are kept"
        );
        std::fs::remove_dir_all(d).unwrap();
    }

    /// A drawing of another report may have had other scenes: its scene pages go too.
    #[test]
    fn an_earlier_drawing_s_scene_pages_count_as_its_output() {
        let d = scratch("pages");
        std::fs::write(d.join("scene-old.html"), "<html>").unwrap();
        std::fs::write(d.join("scene-notes.txt"), "mine").unwrap();
        let err = OutDir::claim(&d, DRAWING, false).unwrap_err().to_string();
        assert!(err.contains("(scene-old.html): give --force"), "{err}");
        OutDir::claim(&d, DRAWING, true).unwrap();
        assert!(!d.join("scene-old.html").exists());
        assert!(d.join("scene-notes.txt").exists());
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_directory_where_a_file_goes_is_an_error_even_with_force() {
        let d = scratch("kind");
        std::fs::create_dir_all(d.join("report.json")).unwrap();
        let err = OutDir::claim(&d, RUN, true).unwrap_err().to_string();
        assert!(
            err.contains("report.json is a directory where raybench writes a file"),
            "{err}"
        );
        std::fs::remove_dir_all(&d).unwrap();
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("charts"), "x").unwrap();
        let err = OutDir::claim(&d, RUN, true).unwrap_err().to_string();
        assert!(
            err.contains("charts is a file where raybench writes a directory"),
            "{err}"
        );
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_file_where_the_directory_should_be_fails_before_any_work() {
        let d = scratch("notdir");
        let file = d.join("plain-file");
        std::fs::write(&file, b"x").unwrap();
        let err = format!(
            "{:#}",
            OutDir::claim(&file.join("sub"), RUN, false).unwrap_err()
        );
        assert!(
            err.contains("plain-file") && err.contains("cannot be created"),
            "{err}"
        );
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn new_directories_never_reuse_an_earlier_one() {
        let d = scratch("new");
        let a = OutDir::claim_new(&d, "2026-11-25-abc", RUN).unwrap();
        let b = OutDir::claim_new(&d, "2026-11-25-abc", RUN).unwrap();
        assert_eq!(a.path(), d.join("2026-11-25-abc"));
        assert_eq!(b.path(), d.join("2026-11-25-abc-2"));
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn dumps_of_an_earlier_run_are_found_by_suffix() {
        let d = scratch("dumps");
        std::fs::write(d.join("a__b__c.hits"), "x").unwrap();
        let err = OutDir::claim(&d, DUMPS, false).unwrap_err().to_string();
        assert!(err.contains("a__b__c.hits"), "{err}");
        OutDir::claim(&d, DUMPS, true).unwrap();
        assert!(!d.join("a__b__c.hits").exists());
        std::fs::remove_dir_all(d).unwrap();
    }
}
