//! What the scenes tests share: fixture files written to a fresh temporary directory per test
//! and removed afterwards, generated scenes, rejected specs and mesh hashes.
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

/// A generated scene, or a panic naming the spec.
pub fn scene(spec: &str, seed: u64) -> raybench_scenes::Scene {
    raybench_scenes::generate(spec, seed).unwrap_or_else(|e| panic!("{spec}: {e}"))
}

/// The error message of a spec that must be rejected.
pub fn error_of(spec: &str) -> String {
    match raybench_scenes::generate(spec, 1) {
        Ok(s) => panic!("`{spec}` was accepted ({} triangles)", s.mesh.len()),
        Err(e) => e.to_string(),
    }
}

/// Every spec of `cases` is rejected with a message that names the spec first and contains
/// the expected text.
pub fn assert_rejected(cases: &[(&str, &str)]) {
    for &(spec, expected) in cases {
        let msg = error_of(spec);
        assert!(
            msg.starts_with(&format!("generator spec `{spec}`")),
            "{msg}"
        );
        assert!(
            msg.contains(expected),
            "`{spec}`: expected `{expected}` in: {msg}"
        );
    }
}

pub fn within_5_percent(made: usize, target: usize) -> bool {
    made.abs_diff(target) * 20 <= target
}

/// FNV-1a over every position's bits and every index: equal hashes mean the same mesh.
pub fn mesh_hash(s: &raybench_scenes::Scene) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for p in s.mesh.positions() {
        p.to_array().iter().for_each(|c| eat(c.to_bits()));
    }
    for t in s.mesh.indices() {
        t.iter().for_each(|&i| eat(i));
    }
    h
}
