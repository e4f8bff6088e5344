//! Our own line-by-line pass over an OBJ text, run before tobj.
//!
//! tobj reports only the kind of an error ("face vertex index out of bounds"), never the line,
//! and panics on one input (a relative `vt` index reaching too far back, in debug builds). This
//! scan mirrors tobj's rules for the statements it parses, so it finds the first offending line
//! and rejects it before tobj sees it. It also counts what tobj drops or changes silently (point
//! and line elements, `l` polylines turned into polygons, non-convex polygons that the fan
//! triangulation gets wrong, ignored free-form geometry) so the loader can say so in its notes.
//!
//! Some rules are stricter than tobj, because the input they reject means a corrupt, binary or
//! truncated file more often than an exotic exporter, and a clear error beats a silent guess:
//! * a line whose first word is not an OBJ statement (tobj ignores it);
//! * a NUL or other control byte anywhere (binary data), and a carriage return not followed by
//!   a line feed (classic Mac OS line endings: tobj would read the whole file as one line);
//! * a `\` line continuation (allowed by the OBJ spec, unsupported by tobj, which fails with
//!   no line number);
//! * `v` lines with a colour (`v x y z r g b`) mixed with `v` lines without one (tobj fails,
//!   without a line, as soon as a face uses an uncoloured vertex).
//!
//! tobj resolves positive indices when it closes a model (at an `o`/`g` after faces, and at the
//! end of the file), so a forward reference must be satisfied by then; the scan checks that at
//! the same points.

mod parse;
mod polygon;
mod state;

use state::State;

/// The first line the scan rejects.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct LineProblem {
    pub line: usize,
    pub problem: String,
}

/// What the scan learned about a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Scan {
    pub first_problem: Option<LineProblem>,
    pub vertices: u64,
    pub faces: u64,
    /// `f` with one or two vertices, `l` with two: dropped (`ignore_points`, `ignore_lines`).
    pub points_and_lines: u64,
    /// `l` with three or more vertices: tobj reads `l` exactly like `f`, so these become polygons.
    pub polylines_as_polygons: u64,
    /// `f` with four or more vertices, fan-triangulated by tobj.
    pub polygons: u64,
    /// Of those, the ones that are not convex: the fan may cover the wrong area.
    pub non_convex_polygons: u64,
    /// `p`, `curv`, `curv2`, `surf`: geometry tobj ignores.
    pub ignored_geometry: u64,
    pub mtllib_lines: u64,
    /// Statements with an unknown but well-formed keyword (vendor extensions): ignored, as
    /// tobj does, and counted so the loader can say so.
    pub unknown_statements: u64,
}

/// Totals needed to check positive (absolute) indices, which may refer forward.
#[derive(Default)]
struct Totals {
    v: usize,
    vt: usize,
    vn: usize,
}

/// Scans the whole text; stops collecting at the first problem.
pub(super) fn scan(text: &str) -> Scan {
    if let Some(problem) = binary_or_lone_cr(text) {
        return Scan {
            first_problem: Some(problem),
            ..Scan::default()
        };
    }
    let mut state = State::new(count_elements(text));
    let mut last_line = 0;
    for (i, line) in text.lines().enumerate() {
        state.line_number = i + 1;
        last_line = i + 1;
        if let Err(problem) = state.line(line) {
            state.scan.first_problem = Some(problem);
            return state.scan;
        }
    }
    // tobj closes the last model at the end of the file.
    if let Err(problem) = state.close_model(last_line) {
        state.scan.first_problem = Some(problem);
    }
    state.scan
}

/// The first NUL or other control character (binary data), or the first carriage return not
/// followed by a line feed, with its line and column (in characters).
fn binary_or_lone_cr(text: &str) -> Option<LineProblem> {
    let is_binary = |c: char| c.is_control() && !matches!(c, '\t' | '\n' | '\r' | '\x0b' | '\x0c');
    let mut chars = text.chars().peekable();
    let (mut line, mut column) = (1, 0);
    while let Some(c) = chars.next() {
        column += 1;
        let problem = if c == '\r' && chars.peek() != Some(&'\n') {
            "carriage return without a line feed (classic Mac OS line endings?): save the file \
             with \\n or \\r\\n line endings"
                .to_owned()
        } else if is_binary(c) {
            format!(
                "control character {} (binary data, not OBJ text)",
                c.escape_unicode()
            )
        } else {
            if c == '\n' {
                (line, column) = (line + 1, 0);
            }
            continue;
        };
        return Some(LineProblem {
            line,
            problem: format!("column {column}: {problem}"),
        });
    }
    None
}

fn count_elements(text: &str) -> Totals {
    let mut t = Totals::default();
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => t.v += 1,
            Some("vt") => t.vt += 1,
            Some("vn") => t.vn += 1,
            _ => {}
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::parse::shorten;
    use super::*;

    fn problem(text: &str) -> Option<LineProblem> {
        scan(text).first_problem
    }

    #[test]
    fn finds_the_offending_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\nf 1 2 4\n";
        let p = problem(text).unwrap();
        assert_eq!(p.line, 6);
        assert!(p.problem.contains("index 4 is out of range"), "{p:?}");
    }

    #[test]
    fn relative_indices_resolve_against_the_count_so_far() {
        assert_eq!(problem("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"), None);
        let p = problem("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(p.line, 2);
        assert!(p.problem.contains("reaches before"), "{p:?}");
    }

    #[test]
    fn forward_references_are_allowed() {
        assert_eq!(problem("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"), None);
    }

    #[test]
    fn texcoord_and_normal_indices_follow_tobj() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        // No `vt` in the file: tobj ignores vt indices entirely; 0 means absent.
        assert_eq!(problem(&format!("{base}f 1/9 2/9 3/9\n")), None);
        assert_eq!(problem(&format!("{base}vt 0 0\nf 1/0 2/0 3/0\n")), None);
        let p = problem(&format!("{base}vt 0 0\nf 1/-5 2/-5 3/-5\n")).unwrap();
        assert_eq!(p.line, 5);
        let p = problem(&format!("{base}vn 0 0 1\nf 1//2 2//2 3//2\n")).unwrap();
        assert!(p.problem.contains("normal index 2"), "{p:?}");
    }

    #[test]
    fn counts_what_tobj_drops_or_changes() {
        let text =
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1\nf 1 2\nl 1 2\nl 1 2 3\nf 1 2 3 4\np 1\n";
        let s = scan(text);
        assert_eq!(s.first_problem, None);
        assert_eq!(s.points_and_lines, 3);
        assert_eq!(s.polylines_as_polygons, 1);
        assert_eq!(s.polygons, 1);
        assert_eq!(s.non_convex_polygons, 0);
        assert_eq!(s.ignored_geometry, 1);
    }

    #[test]
    fn forward_references_must_be_satisfied_when_tobj_closes_the_object() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        // Satisfied before the object ends: fine, also across a `g` with no faces before it.
        assert_eq!(problem(&format!("o a\nf 1 2 3\n{tri}o b\n")), None);
        assert_eq!(problem(&format!("g a\ng b\nf 1 2 3\n{tri}")), None);
        // Not satisfied by the `o` that ends the object: the face's line is named.
        let p = problem("v 0 0 0\nf 1 2 3\no next\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(p.line, 2);
        assert!(
            p.problem
                .contains("vertex index 2 refers forward, but only 1 `v`"),
            "{p:?}"
        );
        assert!(p.problem.contains("ends at line 3"), "{p:?}");
        // The first failing face is named, not the one with the largest index.
        let p = problem("f 1 2 5\nf 1 2 3\nv 0 0 0\no x\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\n");
        assert_eq!(p.unwrap().line, 1);
        // tobj ignores texture indices of an object that closes before any `vt`.
        assert_eq!(problem(&format!("{tri}f 1/1 2/1 3/1\no x\nvt 0 0\n")), None);
        let p = problem(&format!("{tri}vt 0 0\nf 1/2 2/2 3/2\no x\nvt 1 1\n")).unwrap();
        assert!(
            p.problem
                .contains("texture-coordinate index 2 refers forward"),
            "{p:?}"
        );
    }

    #[test]
    fn binary_data_lone_carriage_returns_and_continuations_are_named() {
        let p = problem("v 0 0 0\nv 1\u{1} 0 0\n").unwrap();
        assert_eq!(
            (p.line, p.problem.as_str()),
            (
                2,
                "column 4: control character \\u{1} (binary data, not OBJ text)"
            )
        );
        let p = problem("v 0 0 0\r\nv 1 0 0\rv 0 1 0\r\n").unwrap();
        assert_eq!(p.line, 2);
        assert!(
            p.problem
                .starts_with("column 8: carriage return without a line feed"),
            "{p:?}"
        );
        for text in ["f 1 2 \\\n3\n", "f 1 2\\\n3\n", "v 0 0 \\"] {
            let p = problem(text).unwrap();
            assert!(
                p.problem.starts_with("line continuation"),
                "{text:?}: {p:?}"
            );
        }
        // A backslash inside a comment or a name is not a continuation.
        assert_eq!(problem("# C:\\models\\\no a\\b\n"), None);
    }

    #[test]
    fn vertex_colours_are_all_or_none() {
        assert_eq!(problem("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\n"), None);
        let p = problem("v 0 0 0\nv 1 0 0 0 1 0\n").unwrap();
        assert_eq!(p.line, 2);
        assert!(p.problem.contains("the `v` on line 1 has none"), "{p:?}");
    }

    #[test]
    fn huge_indices_and_invisible_characters_are_said_plainly() {
        let p = problem("v 0 0 0\nf 1 1 -99999999999999999999\n").unwrap();
        assert_eq!(p.problem, "index `-99999999999999999999` is too large");
        let p = problem("v 0 0 0\nf 1 1 1\u{200b}\n").unwrap();
        assert_eq!(p.problem, "`1\\u{200b}` is not an integer index");
        assert_eq!(shorten(&"é".repeat(50)), "é".repeat(40) + "…");
    }

    #[test]
    fn garbage_statements_are_rejected_but_comments_and_extensions_are_not() {
        assert_eq!(problem("#### header\n# c\ns off\nmtllib a.mtl\n"), None);
        assert_eq!(
            problem("v 0 0 0\nhello world\n"),
            None,
            "unknown keyword: ignored, counted"
        );
        assert_eq!(
            scan("v 0 0 0\nhello world\nxyz_1 2\n").unknown_statements,
            2
        );
        let p = problem("v 0 0 0\n@!%$ world\n").unwrap();
        assert_eq!(p.line, 2);
        assert!(p.problem.contains("`@!%$` is not an OBJ statement"));
    }
}
