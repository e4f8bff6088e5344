//! The fixture table: every file in `tests/fixtures/malformed/`, what the loader must do with
//! it, and why.

/// What the loader must do with a fixture.
#[derive(Debug)]
pub(crate) enum Outcome {
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
pub(crate) struct Removed {
    pub(crate) non_finite: u64,
    pub(crate) too_large: u64,
    pub(crate) degenerate_kept: u64,
}

const CLEAN: Removed = Removed {
    non_finite: 0,
    too_large: 0,
    degenerate_kept: 0,
};

pub(crate) struct Fixture {
    pub(crate) file: &'static str,
    pub(crate) outcome: Outcome,
    /// Why this is the right outcome (the OBJ format or the loader's policy).
    pub(crate) why: &'static str,
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

pub(crate) const FIXTURES: &[Fixture] = &[
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
        why: "`nan` parses as a float; policy (docs/validation.md, E5): triangles Embree ignores are \
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
        why: "tobj panics on this in debug builds (docs/validation.md, Loader); the scan rejects it first",
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
        why: "tobj reads a `vn` index of 0 as absent (docs/validation.md, Loader); positions are intact",
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
        why: "not a keyword: policy (obj/scan/state.rs) rejects garbage, while tobj would skip it",
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
