//! Malformed and unusual OBJ input, data-driven: every file in `tests/fixtures/malformed/` has
//! a row in [`FIXTURES`] saying what the loader must do with it and why, decided from the OBJ
//! format and the loader's documented policy (crates/scenes/src/obj/; docs/validation.md,
//! Loader):
//!
//! * rejected: the message starts with the file's path, then `line N:` when one line is at
//!   fault (whole-file problems such as "no triangles" have no line), then the reason;
//! * loaded: legal OBJ (or a legal tolerance), with the triangles kept, the triangles removed or
//!   flagged as Embree would (NaN/inf/beyond 1.844e18, zero area) and the loader's notes.
//!
//! Each load runs inside `catch_unwind`, so a panic is reported as that fixture's failure.
//! Inputs too big to keep as files (a 100k-vertex face, 50 MB lines) are generated in
//! `big_inputs.rs`.
//!
//! The `#[ignore]`d `mutation_fuzz_the_loader` (`mutation_fuzz.rs`) is the stable-Rust fallback
//! for the cargo-fuzz target in `fuzz/`: millions of seeded mutations of these fixtures (see
//! README, "Fuzzing").

mod big_inputs;
mod mutation_fuzz;
mod table;

use raybench_geom::RemovedTriangles;
use raybench_scenes::{Scene, SceneError, load_obj, load_obj_bytes};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use table::{FIXTURES, Outcome, Removed};

fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/malformed")
}

/// The result of one load, or the panic message as an error of this test.
fn load_catching_panics(
    load: impl FnOnce() -> Result<Scene, SceneError>,
) -> Result<Result<Scene, SceneError>, String> {
    catch_unwind(AssertUnwindSafe(load)).map_err(|panic| {
        panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".to_owned())
    })
}

/// `Err` says how the outcome differs from `expected`.
fn check_outcome(
    path: &Path,
    got: Result<Scene, SceneError>,
    expected: &Outcome,
) -> Result<(), String> {
    match (got, expected) {
        (Err(e), Outcome::Rejected { line, reason }) => {
            check_error(path, &e.to_string(), *line, reason)
        }
        (
            Ok(scene),
            Outcome::Loads {
                triangles,
                removed,
                notes,
            },
        ) => check_scene(&scene, *triangles, removed, notes),
        (Err(e), Outcome::Loads { .. }) => Err(format!("expected a scene, got the error: {e}")),
        (Ok(scene), Outcome::Rejected { .. }) => Err(format!(
            "expected an error, but it loaded {} triangles (notes {:?})",
            scene.mesh.len(),
            scene.loader_notes
        )),
    }
}

fn check_error(
    path: &Path,
    message: &str,
    line: Option<usize>,
    reason: &str,
) -> Result<(), String> {
    let prefix = match line {
        Some(n) => format!("{}: line {n}: ", path.display()),
        None => format!("{}: ", path.display()),
    };
    if !message.starts_with(&prefix) {
        return Err(format!("message does not start with `{prefix}`: {message}"));
    }
    if line.is_none() && message[prefix.len()..].starts_with("line ") {
        return Err(format!(
            "expected a whole-file error, got a line: {message}"
        ));
    }
    if !message.contains(reason) {
        return Err(format!("message lacks `{reason}`: {message}"));
    }
    if message.contains('\n') || message.len() > 400 {
        return Err(format!("message is not one short line: {message:?}"));
    }
    Ok(())
}

fn check_scene(
    scene: &Scene,
    triangles: usize,
    removed: &Removed,
    notes: &[&str],
) -> Result<(), String> {
    let expected_removed = RemovedTriangles {
        bad_index: 0,
        non_finite: removed.non_finite,
        too_large: removed.too_large,
        degenerate_kept: removed.degenerate_kept,
    };
    if scene.mesh.len() != triangles || scene.removed != expected_removed {
        return Err(format!(
            "loaded {} triangles, removed {:?}; expected {triangles}, {expected_removed:?}",
            scene.mesh.len(),
            scene.removed
        ));
    }
    let notes_match = scene.loader_notes.len() == notes.len()
        && notes
            .iter()
            .all(|n| scene.loader_notes.iter().any(|got| got.contains(n)));
    if !notes_match {
        return Err(format!(
            "notes {:?}, expected {notes:?}",
            scene.loader_notes
        ));
    }
    Ok(())
}

#[test]
fn every_fixture_gives_its_documented_outcome() {
    let mut failures = Vec::new();
    for fixture in FIXTURES {
        let path = fixtures_dir().join(fixture.file);
        let result = load_catching_panics(|| load_obj(&path))
            .map_err(|panic| format!("PANIC: {panic}"))
            .and_then(|got| check_outcome(&path, got, &fixture.outcome));
        if let Err(problem) = result {
            failures.push(format!(
                "{}: {problem}\n    (expected because: {})",
                fixture.file, fixture.why
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} fixtures failed:\n{}",
        failures.len(),
        FIXTURES.len(),
        failures.join("\n")
    );
}

#[test]
fn every_fixture_file_has_a_row_and_every_row_a_file() {
    let mut on_disk: Vec<String> = std::fs::read_dir(fixtures_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".obj"))
        .collect();
    on_disk.sort();
    let mut in_table: Vec<String> = FIXTURES.iter().map(|f| f.file.to_owned()).collect();
    in_table.sort();
    assert_eq!(on_disk, in_table, "fixtures on disk vs rows in FIXTURES");
    in_table.dedup();
    assert_eq!(in_table.len(), FIXTURES.len(), "a fixture has two rows");
    let rejected = FIXTURES
        .iter()
        .filter(|f| matches!(f.outcome, Outcome::Rejected { .. }))
        .count();
    assert!(
        rejected >= 20,
        "at least 20 malformed files must be rejected; {rejected} are"
    );
}

/// The fuzz target's entry point answers exactly as the CLI's (`load_obj` reads the file and
/// calls `load_obj_bytes`): same scene or the same message.
#[test]
fn loading_bytes_answers_exactly_as_loading_the_file() {
    for fixture in FIXTURES {
        let path = fixtures_dir().join(fixture.file);
        let bytes = std::fs::read(&path).unwrap();
        let describe = |r: Result<Scene, SceneError>| match r {
            Ok(s) => format!(
                "{} triangles {:?} {:?} {:?}",
                s.mesh.len(),
                s.removed,
                s.loader_notes,
                s.name
            ),
            Err(e) => e.to_string(),
        };
        assert_eq!(
            describe(load_obj(&path)),
            describe(load_obj_bytes(&path, &bytes)),
            "{}",
            fixture.file
        );
    }
}

fn big_input_name() -> &'static Path {
    Path::new("generated.obj")
}
