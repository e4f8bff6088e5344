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

use raybench_geom::DVec3;
use std::num::IntErrorKind;

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

/// OBJ statements tobj ignores without carrying triangle geometry (Wavefront OBJ spec, plus `s`).
const HARMLESS_KEYWORDS: &[&str] = &[
    "o",
    "g",
    "s",
    "mg",
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
];
const IGNORED_GEOMETRY_KEYWORDS: &[&str] = &["p", "curv", "curv2", "surf"];

/// Totals needed to check positive (absolute) indices, which may refer forward.
#[derive(Default)]
struct Totals {
    v: usize,
    vt: usize,
    vn: usize,
}

/// The kinds of element a face corner refers to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Element {
    Position,
    TexCoord,
    Normal,
}

impl Element {
    fn noun(self) -> &'static str {
        match self {
            Element::Position => "vertex",
            Element::TexCoord => "texture-coordinate",
            Element::Normal => "normal",
        }
    }

    fn keyword(self) -> &'static str {
        match self {
            Element::Position => "v",
            Element::TexCoord => "vt",
            Element::Normal => "vn",
        }
    }
}

/// A positive index beyond the elements seen so far on its line: tobj resolves it when it
/// closes the model, so it must be satisfied by then.
#[derive(Clone, Copy, Debug)]
struct ForwardRef {
    line: usize,
    element: Element,
    /// 1-based, as written.
    index: usize,
}

/// Whether the `v` lines so far carry a colour, and where that was first seen.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Colours {
    Unknown,
    With { first_line: usize },
    Without { first_line: usize },
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

struct State {
    totals: Totals,
    /// The line being scanned (1-based).
    line_number: usize,
    /// Positions seen so far (tobj resolves negative indices against these counts).
    positions: Vec<DVec3>,
    vt_so_far: usize,
    vn_so_far: usize,
    colours: Colours,
    /// An `f` or `l` since tobj last closed a model (an `o`/`g` closes one only then).
    model_has_faces: bool,
    /// Forward references of the open model, per [`Element`] (see `remember_forward`).
    forward: [Vec<ForwardRef>; 3],
    scan: Scan,
}

impl State {
    fn new(totals: Totals) -> State {
        State {
            totals,
            line_number: 0,
            positions: Vec::new(),
            vt_so_far: 0,
            vn_so_far: 0,
            colours: Colours::Unknown,
            model_has_faces: false,
            forward: Default::default(),
            scan: Scan::default(),
        }
    }

    fn line(&mut self, line: &str) -> Result<(), LineProblem> {
        let at = self.line_number;
        if matches!(line.split_whitespace().next(), Some("o" | "g")) {
            self.close_model(at)?;
        }
        self.statement(line)
            .map_err(|problem| LineProblem { line: at, problem })
    }

    fn statement(&mut self, line: &str) -> Result<(), String> {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        if keyword.starts_with('#') {
            return Ok(());
        }
        let args: Vec<&str> = words.collect();
        if line.trim_end().ends_with('\\') {
            return Err(
                "line continuation (`\\` at the end of the line) is not supported: join the lines"
                    .into(),
            );
        }
        match keyword {
            "v" => self.vertex(&args)?,
            "vt" => {
                parse_floats(&args, 2, "`vt` needs 2 numbers")?;
                self.vt_so_far += 1;
            }
            "vn" => {
                parse_floats(&args, 3, "`vn` needs 3 numbers")?;
                self.vn_so_far += 1;
            }
            "f" => self.face(&args)?,
            "l" => self.polyline(&args)?,
            "mtllib" => self.scan.mtllib_lines += 1,
            // tobj takes the name after the first space; `usemtl` alone is its MaterialParseError.
            "usemtl" if rest_after_space(line).is_empty() => {
                return Err("`usemtl` without a material name".into());
            }
            "usemtl" => {}
            k if IGNORED_GEOMETRY_KEYWORDS.contains(&k) => self.scan.ignored_geometry += 1,
            k if HARMLESS_KEYWORDS.contains(&k) => {}
            // A word keyword tobj would ignore (an exporter's extension) is counted, not fatal;
            // anything else at the start of a line is garbage or a cut-off file.
            k if k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
                self.scan.unknown_statements += 1
            }
            other => {
                return Err(format!(
                    "`{}` is not an OBJ statement (garbage or a truncated file?)",
                    shorten(other)
                ));
            }
        }
        Ok(())
    }

    fn vertex(&mut self, args: &[&str]) -> Result<(), String> {
        let p = parse_position(args)?;
        self.check_colour_consistency(args.len() == 6)?;
        self.positions.push(p);
        self.scan.vertices += 1;
        Ok(())
    }

    /// tobj keeps one colour list for all `v` lines and fails, without a line number, when a
    /// face uses a vertex past its end: all `v` lines carry a colour or none does.
    fn check_colour_consistency(&mut self, coloured: bool) -> Result<(), String> {
        match (self.colours, coloured) {
            (Colours::Unknown, true) => {
                self.colours = Colours::With {
                    first_line: self.line_number,
                }
            }
            (Colours::Unknown, false) => {
                self.colours = Colours::Without {
                    first_line: self.line_number,
                }
            }
            (Colours::With { first_line }, false) => {
                return Err(format!(
                    "`v` without a colour, but the `v` on line {first_line} has one (r g b): \
                     give every `v` a colour or none"
                ));
            }
            (Colours::Without { first_line }, true) => {
                return Err(format!(
                    "`v` with a colour (r g b), but the `v` on line {first_line} has none: \
                     give every `v` a colour or none"
                ));
            }
            _ => {}
        }
        Ok(())
    }

    /// tobj closes the open model here if it has faces: every forward reference made in it
    /// must now be satisfied. `Err` carries the line of the first unsatisfied face.
    fn close_model(&mut self, at_line: usize) -> Result<(), LineProblem> {
        if !self.model_has_faces {
            return Ok(());
        }
        self.model_has_faces = false;
        let refs = std::mem::take(&mut self.forward);
        let first_unsatisfied = refs
            .iter()
            .filter_map(|list| list.iter().find(|r| !self.satisfied(r)))
            .min_by_key(|r| r.line);
        match first_unsatisfied {
            None => Ok(()),
            Some(r) => Err(LineProblem {
                line: r.line,
                problem: format!(
                    "{} index {} refers forward, but only {} `{}` lines come before its object \
                     ends at line {at_line} (tobj resolves indices per object)",
                    r.element.noun(),
                    r.index,
                    self.count(r.element),
                    r.element.keyword()
                ),
            }),
        }
    }

    fn count(&self, element: Element) -> usize {
        match element {
            Element::Position => self.positions.len(),
            Element::TexCoord => self.vt_so_far,
            Element::Normal => self.vn_so_far,
        }
    }

    /// tobj ignores texture-coordinate and normal indices when a model closes before any
    /// `vt`/`vn` exists.
    fn satisfied(&self, r: &ForwardRef) -> bool {
        let have = self.count(r.element);
        r.index <= have || (r.element != Element::Position && have == 0)
    }

    fn face(&mut self, args: &[&str]) -> Result<(), String> {
        let corners = self.corners(args)?;
        match corners.len() {
            0 => return Err("`f` without vertices".into()),
            1 | 2 => self.scan.points_and_lines += 1,
            3 => self.scan.faces += 1,
            _ => {
                self.scan.faces += 1;
                self.scan.polygons += 1;
                if self.is_non_convex(&corners) {
                    self.scan.non_convex_polygons += 1;
                }
            }
        }
        self.model_has_faces = true;
        Ok(())
    }

    fn polyline(&mut self, args: &[&str]) -> Result<(), String> {
        let corners = self.corners(args)?;
        match corners.len() {
            0 => return Err("`l` without vertices".into()),
            1 | 2 => self.scan.points_and_lines += 1,
            _ => {
                self.scan.faces += 1;
                self.scan.polylines_as_polygons += 1;
            }
        }
        self.model_has_faces = true;
        Ok(())
    }

    /// The position index (0-based) of every corner of an `f` or `l` statement, checked the way
    /// tobj checks `v`, `vt` and `vn` indices.
    fn corners(&mut self, args: &[&str]) -> Result<Vec<usize>, String> {
        args.iter().map(|token| self.corner(token)).collect()
    }

    fn corner(&mut self, token: &str) -> Result<usize, String> {
        let [v, vt, vn] = parse_corner(token)?;
        let v = v.ok_or_else(|| format!("`{}` has no vertex index", shorten(token)))?;
        let position = self.resolve(v, Element::Position)?;
        // tobj reads `vt`/`vn` indices only when the file has any `vt`/`vn`, and treats 0 as absent.
        if let Some(vt) = vt.filter(|&i| i != 0 && self.totals.vt > 0) {
            self.resolve(vt, Element::TexCoord)?;
        }
        if let Some(vn) = vn.filter(|&i| i != 0 && self.totals.vn > 0) {
            self.resolve(vn, Element::Normal)?;
        }
        Ok(position)
    }

    /// Resolves an index against the whole file, and remembers a forward reference so it can
    /// be checked when tobj closes the model.
    fn resolve(&mut self, index: i64, element: Element) -> Result<usize, String> {
        let total = match element {
            Element::Position => self.totals.v,
            Element::TexCoord => self.totals.vt,
            Element::Normal => self.totals.vn,
        };
        let zero_based = resolve(index, self.count(element), total, element)?;
        if zero_based >= self.count(element) {
            self.remember_forward(element, zero_based + 1);
        }
        Ok(zero_based)
    }

    /// Keeps only forward references larger than every earlier one of their kind: when a
    /// smaller later one fails, an earlier one has failed first, so only these can be the first
    /// failure (and a file made of forward references keeps a short list).
    fn remember_forward(&mut self, element: Element, index: usize) {
        let list = &mut self.forward[element as usize];
        if list.last().is_none_or(|r| index > r.index) {
            list.push(ForwardRef {
                line: self.line_number,
                element,
                index,
            });
        }
    }

    fn is_non_convex(&self, corners: &[usize]) -> bool {
        let points: Option<Vec<DVec3>> = corners
            .iter()
            .map(|&i| self.positions.get(i).copied())
            .collect();
        // Forward references (a `v` after the face) are rare; such polygons are not checked.
        points.is_some_and(|p| polygon_is_non_convex(&p))
    }
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn`: up to three optional signed integers.
fn parse_corner(token: &str) -> Result<[Option<i64>; 3], String> {
    let parts: Vec<&str> = token.split('/').collect();
    if parts.len() > 3 {
        return Err(format!(
            "`{}` has more than 3 slash-separated parts",
            shorten(token)
        ));
    }
    let mut numbers = [None; 3];
    for (slot, part) in numbers.iter_mut().zip(&parts) {
        if part.is_empty() {
            continue;
        }
        let whole = if parts.len() > 1 {
            format!(" in `{}`", shorten(token))
        } else {
            String::new()
        };
        *slot = Some(part.parse::<i64>().map_err(|e| match e.kind() {
            IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => {
                format!("index `{}`{whole} is too large", shorten(part))
            }
            _ => format!("`{}`{whole} is not an integer index", shorten(part)),
        })?);
    }
    Ok(numbers)
}

/// Resolves a 1-based or negative (relative) OBJ index to a 0-based one, as tobj does: negative
/// indices count back from the elements seen so far, positive ones may refer forward (checked
/// here against the whole file, and by [`State::close_model`] against its object).
fn resolve(index: i64, so_far: usize, total: usize, element: Element) -> Result<usize, String> {
    let (what, keyword) = (element.noun(), element.keyword());
    if index == 0 {
        return Err(format!("{what} index 0 (OBJ indices start at 1)"));
    }
    if index < 0 {
        let back = index.unsigned_abs();
        return so_far
            .checked_sub(usize::try_from(back).unwrap_or(usize::MAX))
            .ok_or_else(|| {
                format!("relative {what} index {index} reaches before the first `{keyword}` ({so_far} defined so far)")
            });
    }
    let zero_based = usize::try_from(index - 1).unwrap_or(usize::MAX);
    if zero_based >= total {
        return Err(format!(
            "{what} index {index} is out of range (the file has {total} `{keyword}` lines)"
        ));
    }
    Ok(zero_based)
}

/// `v x y z [w | r g b]`, with tobj's rules: three numbers, then nothing, a non-zero `w`
/// (which divides x, y, z), or three colour values.
fn parse_position(args: &[&str]) -> Result<DVec3, String> {
    let xyz = parse_floats(args, 3, "`v` needs 3 numbers")?;
    let p = DVec3::new(xyz[0], xyz[1], xyz[2]);
    match args.len() {
        3 => Ok(p),
        6 => {
            parse_floats(&args[3..], 3, "`v` colour needs 3 numbers (r g b)")?;
            Ok(p)
        }
        4 => match args[3].parse::<f32>() {
            Ok(0.0) => Err("`v` with w = 0".into()),
            Ok(w) => Ok(p / f64::from(w)),
            Err(_) => Err(format!("`v`: w = `{}` is not a number", shorten(args[3]))),
        },
        n => Err(format!(
            "`v` with {n} values (expected 3, 4 with w, or 6 with a colour)"
        )),
    }
}

/// The first `n` arguments as numbers; parsed as f32 exactly like tobj (so `1e39` is inf, which
/// the mesh then drops and counts, and `nan` is accepted here too).
fn parse_floats(args: &[&str], n: usize, need: &str) -> Result<Vec<f64>, String> {
    if args.len() < n {
        return Err(format!("{need}, found {}", args.len()));
    }
    args[..n]
        .iter()
        .map(|a| {
            a.parse::<f32>()
                .map(f64::from)
                .map_err(|_| format!("{need}: `{}` is not a number", shorten(a)))
        })
        .collect()
}

fn rest_after_space(line: &str) -> &str {
    line.split_once(' ').map_or("", |(_, rest)| rest.trim())
}

/// At most 40 characters of a token, so a huge garbage line does not flood the message, with
/// invisible characters (zero-width spaces, controls) escaped so the reader sees them.
fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    let mut out: String = s.chars().take(MAX).map(visible).collect();
    if s.chars().nth(MAX).is_some() {
        out.push('…');
    }
    out
}

/// A character as the reader should see it in a message: printable ASCII and other printable
/// characters as they are, anything invisible as a `\u{…}` escape.
fn visible(c: char) -> String {
    if c.is_ascii_graphic() || (!c.is_ascii() && c.escape_debug().count() == 1) {
        c.to_string()
    } else {
        c.escape_unicode().to_string()
    }
}

/// True when some corner turns the other way from the polygon's overall orientation (Newell
/// normal). Collinear corners are allowed; degenerate or non-finite polygons are not judged.
pub(super) fn polygon_is_non_convex(points: &[DVec3]) -> bool {
    let n = points.len();
    let normal = newell_normal(points);
    if !normal.is_finite() || normal.length_squared() == 0.0 {
        return false;
    }
    // The corners were rounded to f32: each is only known to a few f32 ulps of the largest
    // coordinate. A dent smaller than that is rounding, not shape (a finely tessellated disc,
    // 100k corners on a circle, has such dents everywhere and is convex).
    let scale = points
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let position_slack = 4.0 * f64::from(f32::EPSILON) * scale;
    (0..n).any(|i| {
        let a = points[i];
        let b = points[(i + 1) % n];
        let c = points[(i + 2) % n];
        let (e1, e2) = (b - a, c - b);
        let turn = e1.cross(e2).dot(normal);
        // Moving a corner by `position_slack` changes the cross product by about
        // slack × (|e1| + |e2|); the relative 1e-9 covers f64 rounding in the product itself.
        let slack =
            (position_slack * (e1.length() + e2.length())).max(1e-9 * e1.length() * e2.length());
        turn < -slack * normal.length()
    })
}

fn newell_normal(points: &[DVec3]) -> DVec3 {
    let n = points.len();
    (0..n).fold(DVec3::ZERO, |acc, i| {
        let (p, q) = (points[i], points[(i + 1) % n]);
        acc + DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        )
    })
}

#[cfg(test)]
mod tests {
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
    fn detects_non_convex_polygons() {
        let square = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)];
        let arrow = [(0., 0.), (2., 0.), (1., 0.5), (2., 2.), (0., 2.)];
        let to3 = |p: &[(f64, f64)]| {
            p.iter()
                .map(|&(x, y)| DVec3::new(x, y, 0.0))
                .collect::<Vec<_>>()
        };
        assert!(!polygon_is_non_convex(&to3(&square)));
        assert!(polygon_is_non_convex(&to3(&arrow)));
        // Orientation does not matter.
        let mut reversed = to3(&arrow);
        reversed.reverse();
        assert!(polygon_is_non_convex(&reversed));
        // A 100k-corner disc rounded to f32 has dents of rounding size only: convex.
        let n = 100_000;
        let disc: Vec<DVec3> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                DVec3::new(f64::from(a.cos() as f32), f64::from(a.sin() as f32), 0.0)
            })
            .collect();
        assert!(!polygon_is_non_convex(&disc));
        // A real dent in a fine polygon is still found: one corner pulled in by 1 %.
        let mut dented = disc;
        dented[500] *= 0.99;
        assert!(polygon_is_non_convex(&dented));
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
