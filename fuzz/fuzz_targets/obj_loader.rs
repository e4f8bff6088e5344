//! Arbitrary bytes through the OBJ loader, at the entry point the CLI uses (`load_obj` reads the
//! file and calls `load_obj_bytes`).
//!
//! Besides "no panic" (libfuzzer-sys aborts on any panic, even one the loader contains with
//! `catch_unwind` around tobj: such a panic means the loader's own scan missed a rule), the
//! target checks what the loader promises:
//! * an error names the input first and is one short line;
//! * tobj never rejects what the scan accepted (an `Obj` error without a line number);
//! * a loaded scene has triangles, and none with a vertex Embree would drop.
//!
//! The same checks run on stable Rust in crates/scenes/tests/malformed_obj/mutation_fuzz.rs
//! (`mutation_fuzz_the_loader`); keep the two in step.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raybench_geom::EMBREE_LARGE;
use raybench_scenes::{Scene, SceneError, load_obj_bytes};
use std::path::Path;

const NAME: &str = "fuzz.obj";

fuzz_target!(|data: &[u8]| {
    match load_obj_bytes(Path::new(NAME), data) {
        Ok(scene) => check_loaded(&scene),
        Err(e) => check_rejected(&e),
    }
});

fn check_loaded(scene: &Scene) {
    assert!(!scene.mesh.is_empty(), "a scene without triangles");
    for t in scene.mesh.triangles() {
        for p in [t.v0, t.v1, t.v2] {
            assert!(
                p.is_finite() && p.abs().max_element() <= EMBREE_LARGE,
                "a kept triangle has the vertex {p}"
            );
        }
    }
}

fn check_rejected(e: &SceneError) {
    let message = e.to_string();
    assert!(
        message.starts_with(&format!("{NAME}: "))
            && !message.contains('\n')
            && message.len() <= 400,
        "unclear message: {message:?}"
    );
    assert!(
        !matches!(e, SceneError::Obj { line: None, .. }),
        "tobj rejected what the scan accepted (no line): {message}"
    );
}
