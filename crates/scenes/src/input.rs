//! The one way raybench reads a file a user names: OBJ scenes, suite manifests, reports and
//! baselines all come through [`read_input`].
//!
//! Only regular files are read. A FIFO, a device (`/dev/zero`), a socket or a directory is an
//! error that says what the path is, before a byte is read: reading a FIFO blocks until a
//! writer appears, and a device can stream until memory runs out. The file is opened without
//! blocking (`O_NONBLOCK`, which a regular file ignores) and checked again on the open handle,
//! so a path swapped for a FIFO between the check and the open cannot hang the run either.
//! Files larger than [`max_input_bytes`] are refused before they are read; the limit is a
//! process-wide setting (`raybench --max-input-size`), so one flag raises it for every file a
//! command reads.

use std::fs::{File, Metadata};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The default size limit: 4 GiB, several times the largest real scene raybench ships with
/// (12 MB) and a sixth of the memory of the machine it was written on; raise it with
/// [`set_max_input_bytes`].
pub const DEFAULT_MAX_INPUT_BYTES: u64 = 4 << 30;

static MAX_INPUT_BYTES: AtomicU64 = AtomicU64::new(DEFAULT_MAX_INPUT_BYTES);

/// Sets the size limit of every file read from now on.
pub fn set_max_input_bytes(limit: u64) {
    MAX_INPUT_BYTES.store(limit, Ordering::Relaxed);
}

/// The size limit of a file read now.
pub fn max_input_bytes() -> u64 {
    MAX_INPUT_BYTES.load(Ordering::Relaxed)
}

/// Why a file was not read. Every message starts with the path.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{}: no such file", .path.display())]
    Missing { path: PathBuf },
    #[error("{}: is {what}, not a regular file", .path.display())]
    NotRegular { path: PathBuf, what: &'static str },
    #[error(
        "{}: {size} bytes, more than the input size limit of {limit} bytes (raise it with --max-input-size)",
        .path.display()
    )]
    TooLarge {
        path: PathBuf,
        size: u64,
        limit: u64,
    },
    #[error("{}: cannot read: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What kind of file `meta` describes, in words, when it is not a regular file.
fn not_regular(meta: &Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some(if t.is_dir() {
        "a directory"
    } else {
        "not a file"
    })
}

fn check(path: &Path, meta: &Metadata, limit: u64) -> Result<u64, InputError> {
    if let Some(what) = not_regular(meta) {
        return Err(InputError::NotRegular {
            path: path.to_owned(),
            what,
        });
    }
    let size = meta.len();
    if size > limit {
        return Err(InputError::TooLarge {
            path: path.to_owned(),
            size,
            limit,
        });
    }
    Ok(size)
}

fn io(path: &Path, source: std::io::Error) -> InputError {
    match source.kind() {
        std::io::ErrorKind::NotFound => InputError::Missing {
            path: path.to_owned(),
        },
        _ => InputError::Io {
            path: path.to_owned(),
            source,
        },
    }
}

/// Checks that `path` (after symbolic links) is a regular file within the size limit, without
/// opening it; returns its size.
pub fn check_input(path: &Path) -> Result<u64, InputError> {
    let meta = std::fs::metadata(path).map_err(|e| io(path, e))?;
    check(path, &meta, max_input_bytes())
}

/// Whether `path` is absent ("not found", including a missing parent folder). A path that
/// exists but cannot be inspected is not absent.
pub fn is_absent(path: &Path) -> bool {
    matches!(std::fs::metadata(path), Err(e) if e.kind() == std::io::ErrorKind::NotFound)
}

fn open(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // O_NONBLOCK: opening a FIFO without a writer returns at once instead of waiting.
        const O_NONBLOCK: i32 = 0o4000;
        options.custom_flags(O_NONBLOCK);
    }
    options.open(path)
}

/// The whole content of the regular file at `path` (see the module documentation).
pub fn read_input(path: &Path) -> Result<Vec<u8>, InputError> {
    read_within(path, max_input_bytes())
}

fn read_within(path: &Path, limit: u64) -> Result<Vec<u8>, InputError> {
    let meta = std::fs::metadata(path).map_err(|e| io(path, e))?;
    check(path, &meta, limit)?;
    let file = open(path).map_err(|e| io(path, e))?;
    let size = check(path, &file.metadata().map_err(|e| io(path, e))?, limit)?;
    let mut bytes = Vec::with_capacity(size as usize);
    // A file that grows while it is read stops at the limit, one byte over to notice it.
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(InputError::TooLarge {
            path: path.to_owned(),
            size: bytes.len() as u64,
            limit,
        });
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-input-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_regular_file_is_read_whole() {
        let d = scratch("ok");
        let p = d.join("a.txt");
        std::fs::write(&p, b"v 0 0 0\n").unwrap();
        assert_eq!(read_input(&p).unwrap(), b"v 0 0 0\n");
        assert_eq!(check_input(&p).unwrap(), 8);
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_directory_a_device_and_a_missing_path_are_named() {
        let d = scratch("kinds");
        let err = read_input(&d).unwrap_err().to_string();
        assert!(err.ends_with("is a directory, not a regular file"), "{err}");
        let err = read_input(Path::new("/dev/zero")).unwrap_err().to_string();
        assert_eq!(err, "/dev/zero: is a character device, not a regular file");
        let err = read_input(&d.join("nope.obj")).unwrap_err();
        assert!(matches!(err, InputError::Missing { .. }), "{err}");
        assert!(err.to_string().ends_with("nope.obj: no such file"), "{err}");
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_file_over_the_limit_is_refused_before_it_is_read() {
        let d = scratch("big");
        let p = d.join("big.obj");
        std::fs::write(&p, vec![b'#'; 1000]).unwrap();
        assert_eq!(read_within(&p, 1000).unwrap().len(), 1000);
        let err = read_within(&p, 999).unwrap_err().to_string();
        assert!(
            err.ends_with(
                "big.obj: 1000 bytes, more than the input size limit of 999 bytes (raise it with \
                 --max-input-size)"
            ),
            "{err}"
        );
        std::fs::remove_dir_all(d).unwrap();
    }

    /// A FIFO with no writer: reading it would block forever.
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let d = scratch("fifo");
        let p = d.join("scene.obj");
        let made = std::process::Command::new("mkfifo").arg(&p).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("NOT RUN: mkfifo is not available");
            return;
        }
        let err = read_input(&p).unwrap_err().to_string();
        assert!(
            err.ends_with("is a FIFO (named pipe), not a regular file"),
            "{err}"
        );
        // The handle check catches a FIFO even when the path check is skipped.
        let file = open(&p).unwrap();
        let err = check(&p, &file.metadata().unwrap(), u64::MAX)
            .unwrap_err()
            .to_string();
        assert!(err.contains("FIFO"), "{err}");
        std::fs::remove_dir_all(d).unwrap();
    }
}
