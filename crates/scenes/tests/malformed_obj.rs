//! Malformed and unusual OBJ input, data-driven: every file in `tests/fixtures/malformed/` has
//! a row in [`FIXTURES`] saying what the loader must do with it and why, decided from the OBJ
//! format and the loader's documented policy (crates/scenes/src/obj/mod.rs and scan.rs):
//!
//! * rejected: the message starts with the file's path, then `line N:` when one line is at
//!   fault (whole-file problems such as "no triangles" have no line), then the reason;
//! * loaded: legal OBJ (or a legal tolerance), with the triangles kept, the triangles removed or
//!   flagged as Embree would (NaN/inf/beyond 1.844e18, zero area) and the loader's notes.
//!
//! Each load runs inside `catch_unwind`, so a panic is reported as that fixture's failure.
//! Inputs too big to keep as files (a 100k-vertex face, 50 MB lines) are generated here.
//!
//! The `#[ignore]`d `mutation_fuzz_the_loader` is the stable-Rust fallback for the cargo-fuzz
//! target in `fuzz/`: millions of seeded mutations of these fixtures (see README, "Fuzzing").

use raybench_geom::{EMBREE_LARGE, RemovedTriangles};
use raybench_scenes::{Scene, SceneError, load_obj, load_obj_bytes};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

/// What the loader must do with a fixture.
#[derive(Debug)]
enum Outcome {
    /// An error whose message is `<path>: line <line>: …` (or `<path>: …` when `line` is None)
    /// and contains `reason`.
    Rejected {
        line: Option<usize>,
        reason: &'static str,
    },
    /// A scene with `triangles` triangles, these removal counts, and a note containing each of
    /// `notes` (no other notes).
    Loads {
        triangles: usize,
        removed: Removed,
        notes: &'static [&'static str],
    },
}

/// [`RemovedTriangles`] in a form a `const` table can hold.
#[derive(Debug, Default)]
struct Removed {
    non_finite: u64,
    too_large: u64,
    degenerate_kept: u64,
}

const CLEAN: Removed = Removed {
    non_finite: 0,
    too_large: 0,
    degenerate_kept: 0,
};

struct Fixture {
    file: &'static str,
    outcome: Outcome,
    /// Why this is the right outcome (the OBJ format or the loader's policy).
    why: &'static str,
}

const fn rejected(line: usize, reason: &'static str) -> Outcome {
    Outcome::Rejected {
        line: Some(line),
        reason,
    }
}

const fn rejected_whole_file(reason: &'static str) -> Outcome {
    Outcome::Rejected { line: None, reason }
}

const fn loads(triangles: usize, removed: Removed, notes: &'static [&'static str]) -> Outcome {
    Outcome::Loads {
        triangles,
        removed,
        notes,
    }
}

const FIXTURES: &[Fixture] = &[
    // Truncated files.
    Fixture {
        file: "truncated_vertex.obj",
        outcome: rejected(3, "`v` needs 3 numbers, found 2"),
        why: "cut mid-line: a `v` needs x y z",
    },
    Fixture {
        file: "truncated_face.obj",
        outcome: loads(1, CLEAN, &["1 point/line elements skipped"]),
        why: "cut to `f 1 3`: a two-vertex element is legal OBJ (a line), not a surface, so it is \
              skipped and noted; the complete face before it loads",
    },
    Fixture {
        file: "truncated_keyword.obj",
        outcome: rejected(5, "`v` needs 3 numbers, found 0"),
        why: "cut right after a keyword",
    },
    Fixture {
        file: "missing_coordinate.obj",
        outcome: rejected(2, "`v` needs 3 numbers, found 2"),
        why: "`v 1 2` in the middle of the file",
    },
    // Numbers.
    Fixture {
        file: "number_two_dots.obj",
        outcome: rejected(4, "`1.2.3` is not a number"),
        why: "not a decimal number",
    },
    Fixture {
        file: "number_hex.obj",
        outcome: rejected(1, "`0x10` is not a number"),
        why: "OBJ numbers are decimal; hex is not read",
    },
    Fixture {
        file: "number_nan.obj",
        outcome: loads(
            1,
            Removed {
                non_finite: 1,
                ..CLEAN
            },
            &[],
        ),
        why: "`nan` parses as a float; policy (ARCHITECTURE.md): triangles Embree ignores are \
              removed and counted, the rest loads",
    },
    Fixture {
        file: "number_1e999.obj",
        outcome: loads(
            1,
            Removed {
                non_finite: 2,
                ..CLEAN
            },
            &[],
        ),
        why: "`1e999` overflows f32 to inf and `-inf` is inf: both triangles using them are \
              removed and counted",
    },
    Fixture {
        file: "number_beyond_embree.obj",
        outcome: loads(
            2,
            Removed {
                too_large: 1,
                ..CLEAN
            },
            &[],
        ),
        why: "2e18 is finite but beyond Embree's 1.844e18: its triangle is removed as Embree \
              would, and no far-coordinate note counts the removed vertex",
    },
    // Indices.
    Fixture {
        file: "index_out_of_range.obj",
        outcome: rejected(
            5,
            "vertex index 7 is out of range (the file has 3 `v` lines)",
        ),
        why: "refers to a vertex that does not exist",
    },
    Fixture {
        file: "index_zero.obj",
        outcome: rejected(4, "vertex index 0 (OBJ indices start at 1)"),
        why: "OBJ indices are 1-based",
    },
    Fixture {
        file: "index_negative_before_start.obj",
        outcome: rejected(
            4,
            "relative vertex index -4 reaches before the first `v` (3 defined so far)",
        ),
        why: "a relative index counts back from the vertices so far; -4 with 3 goes past the start",
    },
    Fixture {
        file: "index_huge.obj",
        outcome: rejected(4, "index `99999999999999999999` is too large"),
        why: "beyond any integer type; said as such, not as 'not an integer'",
    },
    Fixture {
        file: "index_not_integer.obj",
        outcome: rejected(4, "`3.0` is not an integer index"),
        why: "face indices are integers",
    },
    Fixture {
        file: "faces_before_any_vertex.obj",
        outcome: rejected(
            1,
            "vertex index 1 is out of range (the file has 0 `v` lines)",
        ),
        why: "a face in a file without vertices",
    },
    Fixture {
        file: "forward_reference.obj",
        outcome: loads(1, CLEAN, &[]),
        why: "a face before its vertices: tobj resolves indices when the object ends, so this is \
              accepted",
    },
    Fixture {
        file: "forward_reference_across_objects.obj",
        outcome: rejected(
            5,
            "vertex index 4 refers forward, but only 3 `v` lines come before its object ends at line 6",
        ),
        why: "tobj resolves indices per object: the 4th vertex comes after `o second`, too late \
              (tobj itself would fail without a line)",
    },
    // The v/vt/vn forms.
    Fixture {
        file: "slash_bad_part.obj",
        outcome: rejected(5, "`x` in `1/x/1` is not an integer index"),
        why: "every part of v/vt/vn is an integer or empty",
    },
    Fixture {
        file: "slash_too_many_parts.obj",
        outcome: rejected(4, "`1/1/1/1` has more than 3 slash-separated parts"),
        why: "at most v/vt/vn",
    },
    Fixture {
        file: "slash_no_vertex.obj",
        outcome: rejected(5, "`/1` has no vertex index"),
        why: "the vertex part is mandatory",
    },
    Fixture {
        file: "texcoord_out_of_range.obj",
        outcome: rejected(
            5,
            "texture-coordinate index 5 is out of range (the file has 1 `vt` lines)",
        ),
        why: "refers to a `vt` that does not exist",
    },
    Fixture {
        file: "texcoord_relative_too_far.obj",
        outcome: rejected(
            5,
            "relative texture-coordinate index -5 reaches before the first `vt` (1 defined so far)",
        ),
        why: "tobj panics on this in debug builds (reliability.md §4.1); the scan rejects it first",
    },
    Fixture {
        file: "texcoord_missing_ignored.obj",
        outcome: loads(1, CLEAN, &[]),
        why: "`f 1/1 2/2 3/3` in a file without `vt`: tobj ignores texture indices when there are \
              none, and raybench uses positions only",
    },
    Fixture {
        file: "normal_out_of_range.obj",
        outcome: rejected(
            5,
            "normal index 2 is out of range (the file has 1 `vn` lines)",
        ),
        why: "refers to a `vn` that does not exist",
    },
    Fixture {
        file: "normal_index_zero_ignored.obj",
        outcome: loads(1, CLEAN, &[]),
        why: "tobj reads a `vn` index of 0 as absent (reliability.md §4.1); positions are intact",
    },
    // Vertex forms.
    Fixture {
        file: "colour_mixed.obj",
        outcome: rejected(3, "`v` without a colour, but the `v` on line 1 has one"),
        why: "tobj keeps one colour list and fails, without a line, when a face uses an uncoloured \
              vertex: all or none",
    },
    Fixture {
        file: "colour_not_a_number.obj",
        outcome: rejected(
            1,
            "`v` colour needs 3 numbers (r g b): `red` is not a number",
        ),
        why: "tobj would silently keep a partial colour list and misalign it",
    },
    Fixture {
        file: "vertex_w_zero.obj",
        outcome: rejected(1, "`v` with w = 0"),
        why: "x/w, y/w, z/w with w = 0",
    },
    Fixture {
        file: "vertex_five_values.obj",
        outcome: rejected(
            1,
            "`v` with 5 values (expected 3, 4 with w, or 6 with a colour)",
        ),
        why: "no OBJ vertex form has 5 values",
    },
    // Other statements.
    Fixture {
        file: "face_without_vertices.obj",
        outcome: rejected(4, "`f` without vertices"),
        why: "an empty face",
    },
    Fixture {
        file: "garbage_line.obj",
        outcome: rejected(
            5,
            "`@@` is not an OBJ statement (garbage or a truncated file?)",
        ),
        why: "not a keyword: policy (scan.rs) rejects garbage, while tobj would skip it",
    },
    Fixture {
        file: "usemtl_without_name.obj",
        outcome: rejected(4, "`usemtl` without a material name"),
        why: "tobj's MaterialParseError, given a line",
    },
    Fixture {
        file: "mtllib_path_traversal.obj",
        outcome: loads(1, CLEAN, &["1 `mtllib` statements ignored"]),
        why: "materials are never read, so a path out of the folder opens nothing",
    },
    Fixture {
        file: "quad_pentagon_polyline.obj",
        outcome: loads(
            6,
            Removed {
                degenerate_kept: 1,
                ..CLEAN
            },
            &[
                "1 `l` polylines with 3+ vertices became polygons",
                "2 polygons with 4+ vertices fan-triangulated",
            ],
        ),
        why: "legal OBJ: a quad (2 triangles), a pentagon with three collinear corners (3, one of \
              zero area, kept and flagged) and an `l` tobj reads like `f` (1)",
    },
    Fixture {
        file: "degenerate_faces.obj",
        outcome: loads(
            4,
            Removed {
                degenerate_kept: 3,
                ..CLEAN
            },
            &[],
        ),
        why: "repeated indices are legal and give zero-area triangles: kept (never hit) and counted",
    },
    // No triangles at all.
    Fixture {
        file: "empty.obj",
        outcome: rejected_whole_file("no triangles (no vertices and no faces"),
        why: "0 bytes: tobj says Ok with nothing; policy: a scene needs triangles",
    },
    Fixture {
        file: "whitespace_only.obj",
        outcome: rejected_whole_file("no triangles (no vertices and no faces"),
        why: "blank lines only",
    },
    Fixture {
        file: "only_comments.obj",
        outcome: rejected_whole_file("no triangles (no vertices and no faces"),
        why: "comments only (one looks like a `v` line)",
    },
    Fixture {
        file: "only_vertices.obj",
        outcome: rejected_whole_file("no triangles (4 vertices but no faces)"),
        why: "a point cloud",
    },
    Fixture {
        file: "only_points_and_lines.obj",
        outcome: rejected_whole_file("no triangles (only 3 point/line elements"),
        why: "points and lines are not surfaces",
    },
    // Encodings and line endings.
    Fixture {
        file: "non_utf8_latin1.obj",
        outcome: rejected(2, "not UTF-8 text (invalid byte at column 6)"),
        why: "Latin-1 in a comment; tobj would say only 'read error'",
    },
    Fixture {
        file: "non_utf8_in_number.obj",
        outcome: rejected(3, "not UTF-8 text (invalid byte at column 6)"),
        why: "a 0xFF byte inside a number",
    },
    Fixture {
        file: "utf16.obj",
        outcome: rejected(
            1,
            "it starts with a UTF-16 byte-order mark: save it as UTF-8",
        ),
        why: "UTF-16 text is not UTF-8; the byte-order mark says which it is",
    },
    Fixture {
        file: "binary_garbage.obj",
        outcome: rejected(1, "it contains NUL bytes: binary data, not an OBJ file"),
        why: "a PNG header and random bytes",
    },
    Fixture {
        file: "nul_byte.obj",
        outcome: rejected(
            2,
            "column 6: control character \\u{0} (binary data, not OBJ text)",
        ),
        why: "valid UTF-8 but a NUL inside a number",
    },
    Fixture {
        file: "nul_in_comment.obj",
        outcome: rejected(
            1,
            "column 9: control character \\u{0} (binary data, not OBJ text)",
        ),
        why: "NUL bytes mean binary data even inside a comment",
    },
    Fixture {
        file: "byte_order_mark.obj",
        outcome: loads(1, CLEAN, &["UTF-8 byte-order mark skipped"]),
        why: "a UTF-8 byte-order mark is skipped (tobj would misread the first keyword)",
    },
    Fixture {
        file: "crlf.obj",
        outcome: loads(2, CLEAN, &[]),
        why: "Windows line endings are legal",
    },
    Fixture {
        file: "lone_cr.obj",
        outcome: rejected(1, "column 8: carriage return without a line feed"),
        why: "classic Mac OS line endings: tobj would read one giant line",
    },
    Fixture {
        file: "continuation_at_eof.obj",
        outcome: rejected(
            4,
            "line continuation (`\\` at the end of the line) is not supported",
        ),
        why: "the OBJ spec allows `\\` continuations, tobj does not; said plainly",
    },
    Fixture {
        file: "continuation_mid_file.obj",
        outcome: rejected(
            4,
            "line continuation (`\\` at the end of the line) is not supported",
        ),
        why: "as above, in the middle of the file",
    },
    Fixture {
        file: "tabs_and_spaces.obj",
        outcome: loads(1, CLEAN, &[]),
        why: "OBJ separates by any whitespace: tabs, runs of spaces, leading and trailing blanks",
    },
    Fixture {
        file: "unicode_whitespace.obj",
        outcome: loads(1, CLEAN, &[]),
        why: "no-break, ideographic and em spaces are Unicode whitespace; tobj splits on them too",
    },
    Fixture {
        file: "zero_width_space.obj",
        outcome: rejected(2, "`1\\u{200b}` is not a number"),
        why: "a zero-width space is not whitespace: the message shows it escaped",
    },
];

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
        "the issue asks for at least 20 malformed files; {rejected} are rejected"
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

fn load_generated(bytes: &[u8]) -> Result<Scene, SceneError> {
    load_catching_panics(|| load_obj_bytes(big_input_name(), bytes))
        .unwrap_or_else(|panic| panic!("PANIC: {panic}"))
}

/// A convex polygon with `n` corners on the unit circle, as one `f` line.
fn circle_polygon(n: usize, last_index: usize) -> String {
    let mut text = String::new();
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        text += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    text += "f";
    for i in 1..n {
        text += &format!(" {i}");
    }
    text + &format!(" {last_index}\n")
}

#[test]
fn a_face_with_100k_vertices_is_fan_triangulated() {
    let n = 100_000;
    let scene = load_generated(circle_polygon(n, n).as_bytes()).unwrap();
    assert_eq!(scene.mesh.len(), n - 2);
    assert_eq!(
        scene.loader_notes,
        ["1 polygons with 4+ vertices fan-triangulated"]
    );
    // The same face with its last corner out of range: named by line and index.
    let message = load_generated(circle_polygon(n, n + 1).as_bytes())
        .unwrap_err()
        .to_string();
    let expected = format!(
        "generated.obj: line {}: vertex index {} is out of range",
        n + 1,
        n + 1
    );
    assert!(message.starts_with(&expected), "{message}");
}

const FIFTY_MB: usize = 50 << 20;

#[test]
fn a_50_mb_garbage_line_gives_a_short_message() {
    let mut text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_owned();
    text.push_str(&"x@".repeat(FIFTY_MB / 2));
    let message = load_generated(text.as_bytes()).unwrap_err().to_string();
    assert!(
        message.starts_with("generated.obj: line 5: `x@x@"),
        "{}",
        &message[..200.min(message.len())]
    );
    assert!(
        message.len() < 200,
        "the token is shortened: {} bytes",
        message.len()
    );
}

#[test]
fn a_50_mb_vertex_line_is_rejected_and_a_50_mb_comment_is_not() {
    let mut numbers = "v".to_owned();
    numbers.push_str(&" 1".repeat(FIFTY_MB / 2));
    let message = load_generated(numbers.as_bytes()).unwrap_err().to_string();
    let expected = format!("generated.obj: line 1: `v` with {} values", FIFTY_MB / 2);
    assert!(message.starts_with(&expected), "{message}");

    let mut comment = "#".to_owned();
    comment.push_str(&"-".repeat(FIFTY_MB));
    comment.push_str("\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(load_generated(comment.as_bytes()).unwrap().mesh.len(), 1);
}

/// A million `v` lines and one face: the scan and tobj stay linear.
#[test]
fn a_million_vertices_and_one_face_load() {
    let mut text = "v 0 0 0\n".repeat(1_000_000);
    text.push_str("v 1 0 0\nv 0 1 0\nf 1 -2 -1\n");
    let scene = load_generated(text.as_bytes()).unwrap();
    assert_eq!(scene.mesh.len(), 1);
    assert_eq!(
        scene.mesh.triangle(0).v2,
        raybench_scenes::Vec3::new(0.0, 1.0, 0.0)
    );
}

// ---------------------------------------------------------------------------------------------
// Stable-Rust fuzzing: seeded mutations of the fixtures.

mod mutation_fuzz {
    use super::*;
    use rand_core::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;
    use std::time::{Duration, Instant};

    /// Bytes that steer the parser: digits, signs, separators, line ends, escapes, binary.
    const INTERESTING_BYTES: &[u8] = b"0123456789-+./ \t\n\r\\#evfnlotg\x00\xff\x80";
    /// Tokens that reach the loader's rules: keywords, extreme numbers and indices, encodings.
    const TOKENS: &[&str] = &[
        "v ",
        "vt ",
        "vn ",
        "f ",
        "l ",
        "p ",
        "o x\n",
        "g\n",
        "s off\n",
        "usemtl\n",
        "usemtl m\n",
        "mtllib a.mtl\n",
        "-1",
        "-9",
        "0",
        "1",
        "2",
        "3",
        "4",
        "/",
        "//",
        "1/1/1",
        "-1/-1/-1",
        "99999999999999999999",
        "-99999999999999999999",
        "9223372036854775807",
        "-9223372036854775808",
        "1e999",
        "-1e999",
        "1e-999",
        "2e18",
        "1.8e18",
        "nan",
        "inf",
        "-0",
        "0x10",
        "1.2.3",
        "\\\n",
        "\r",
        "\r\n",
        "\n",
        "\u{feff}",
        "\u{200b}",
        "\u{a0}",
        " 1 2 3",
        " 0 0 0 1 1 1",
        "\nf 1 2 3\n",
        "\nv 0 0 0\n",
    ];
    /// Valid seeds besides the fixtures, so mutations start from files that load.
    const VALID: &[&str] = &[
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 3/1/1\nf -1 -2 -3\n",
        "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng b\nv 0 0 1\nf 1 2 4\nl 1 2 3\nf 1 2 3 4\n",
        "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 3 2 1\nf 1 2 3\n",
    ];
    const MAX_INPUT: usize = 64 << 10;

    fn seeds() -> Vec<Vec<u8>> {
        let mut seeds: Vec<Vec<u8>> = FIXTURES
            .iter()
            .map(|f| std::fs::read(fixtures_dir().join(f.file)).unwrap())
            .collect();
        seeds.extend(VALID.iter().map(|s| s.as_bytes().to_vec()));
        seeds
    }

    fn below(rng: &mut Pcg64Mcg, n: usize) -> usize {
        (rng.next_u64() % n.max(1) as u64) as usize
    }

    /// One random edit: flip, set, insert a token, delete, truncate, duplicate, splice, swap.
    fn mutate_once(input: &mut Vec<u8>, seeds: &[Vec<u8>], rng: &mut Pcg64Mcg) {
        let len = input.len();
        let at = below(rng, len + 1);
        match below(rng, 9) {
            0 if len > 0 => input[at.min(len - 1)] ^= 1 << below(rng, 8),
            1 if len > 0 => {
                input[at.min(len - 1)] = INTERESTING_BYTES[below(rng, INTERESTING_BYTES.len())]
            }
            2 | 3 => {
                let token = TOKENS[below(rng, TOKENS.len())].as_bytes();
                input.splice(at..at, token.iter().copied());
            }
            4 => {
                let end = (at + 1 + below(rng, 16)).min(len);
                input.drain(at.min(end)..end);
            }
            5 => input.truncate(at),
            6 => {
                let end = (at + 1 + below(rng, 64)).min(len);
                let copy = input[at.min(end)..end].to_vec();
                let to = below(rng, len + 1);
                input.splice(to..to, copy);
            }
            7 => {
                let other = &seeds[below(rng, seeds.len())];
                let from = below(rng, other.len() + 1);
                input.truncate(at);
                input.extend_from_slice(&other[from..]);
            }
            _ => swap_two_lines(input, rng),
        }
        input.truncate(MAX_INPUT);
    }

    fn swap_two_lines(input: &mut Vec<u8>, rng: &mut Pcg64Mcg) {
        let mut lines: Vec<Vec<u8>> = input.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
        let (a, b) = (below(rng, lines.len()), below(rng, lines.len()));
        lines.swap(a, b);
        *input = lines.join(&b'\n');
    }

    /// `Err` names the broken invariant: a panic; an error not naming the input first, or not
    /// one short line; a tobj rejection the scan let through (an `Obj` error without a line);
    /// a scene with no triangles or with a vertex Embree would drop.
    fn check_one(input: &[u8]) -> Result<&'static str, String> {
        let name = big_input_name();
        match load_catching_panics(|| load_obj_bytes(name, input)) {
            Err(panic) => Err(format!("panic: {panic}")),
            Ok(Ok(scene)) => check_loaded(&scene).map(|()| "loaded"),
            Ok(Err(e)) => check_rejected(&e),
        }
    }

    fn check_loaded(scene: &Scene) -> Result<(), String> {
        if scene.mesh.is_empty() {
            return Err("a scene without triangles".into());
        }
        let bad = scene
            .mesh
            .triangles()
            .flat_map(|t| [t.v0, t.v1, t.v2])
            .find(|p| !p.is_finite() || p.abs().max_element() > EMBREE_LARGE);
        match bad {
            Some(p) => Err(format!("a kept triangle has the vertex {p}")),
            None => Ok(()),
        }
    }

    fn check_rejected(e: &SceneError) -> Result<&'static str, String> {
        let message = e.to_string();
        if !message.starts_with("generated.obj: ") || message.contains('\n') || message.len() > 400
        {
            return Err(format!("unclear message: {message:?}"));
        }
        Ok(match e {
            SceneError::Obj { line: None, .. } => {
                return Err(format!(
                    "tobj rejected what the scan accepted (no line): {message}"
                ));
            }
            SceneError::Obj { .. } => "rejected with a line",
            SceneError::NotUtf8 { .. } => "not UTF-8",
            SceneError::NoTriangles { .. } => "no triangles",
            _ => "other error",
        })
    }

    fn env_u64(name: &str, default: u64) -> u64 {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    }

    /// Saves a failing input next to the temporary files and returns its path.
    fn save_failure(input: &[u8], seed: u64, iteration: u64) -> PathBuf {
        let path = std::env::temp_dir().join(format!("raybench-fuzz-{seed:#x}-{iteration}.obj"));
        std::fs::write(&path, input).unwrap();
        path
    }

    /// Stable-Rust fallback for `cargo fuzz run obj_loader`. Defaults: 3 minutes, no cap on
    /// inputs, seed 0x5eed_f022; override with RAYBENCH_FUZZ_SECONDS, RAYBENCH_FUZZ_ITERATIONS
    /// and RAYBENCH_FUZZ_SEED. A failure names the seed and iteration and saves the input.
    #[test]
    #[ignore = "minutes long: run by hand (README, \"Fuzzing the OBJ loader\")"]
    fn mutation_fuzz_the_loader() {
        let seed = env_u64("RAYBENCH_FUZZ_SEED", 0x5eed_f022);
        let iterations = env_u64("RAYBENCH_FUZZ_ITERATIONS", u64::MAX);
        let budget = Duration::from_secs(env_u64("RAYBENCH_FUZZ_SECONDS", 180));
        let seeds = seeds();
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut outcomes = std::collections::BTreeMap::<&str, u64>::new();
        let start = Instant::now();
        let mut ran = 0;
        while ran < iterations && start.elapsed() < budget {
            let mut input = seeds[below(&mut rng, seeds.len())].clone();
            for _ in 0..1 + below(&mut rng, 4) {
                mutate_once(&mut input, &seeds, &mut rng);
            }
            match check_one(&input) {
                Ok(outcome) => *outcomes.entry(outcome).or_default() += 1,
                Err(problem) => {
                    let saved = save_failure(&input, seed, ran);
                    panic!(
                        "seed {seed:#x}, input {ran} (saved as {}): {problem}",
                        saved.display()
                    );
                }
            }
            ran += 1;
        }
        eprintln!(
            "mutation fuzz: {ran} inputs in {:.0} s (seed {seed:#x}), no failure; outcomes {outcomes:?}",
            start.elapsed().as_secs_f64()
        );
        assert!(ran > 0);
    }

    /// The fuzzer's own check: a short seeded run in every test pass, so the harness cannot rot.
    #[test]
    fn a_short_mutation_run_finds_nothing() {
        let seeds = seeds();
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let mut loaded = 0;
        for i in 0..3000 {
            let mut input = seeds[below(&mut rng, seeds.len())].clone();
            mutate_once(&mut input, &seeds, &mut rng);
            match check_one(&input) {
                Ok("loaded") => loaded += 1,
                Ok(_) => {}
                Err(problem) => panic!(
                    "seed 7, input {i}: {problem}\n{:?}",
                    String::from_utf8_lossy(&input)
                ),
            }
        }
        assert!(
            loaded > 100,
            "mutations must also produce loadable files: {loaded}"
        );
    }
}
