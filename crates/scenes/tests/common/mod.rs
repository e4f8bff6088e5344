//! Fixture files written to a fresh temporary directory per test and removed afterwards.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub struct Fixtures {
    dir: PathBuf,
}

impl Fixtures {
    /// A new empty directory, unique to this process and `test`.
    pub fn new(test: &str) -> Fixtures {
        let dir =
            std::env::temp_dir().join(format!("raybench-scenes-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Fixtures { dir }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let path = self.dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }
}

impl Drop for Fixtures {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// /work/shared/scenes as seen from this crate (absent on machines without the shared folder).
pub fn shared_scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes")
}
