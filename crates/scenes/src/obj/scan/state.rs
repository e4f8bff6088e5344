//! The per-line pass: what each OBJ statement must look like, which indices it may use, and
//! what it adds to the [`Scan`] totals.

use super::parse::{
    Element, parse_corner, parse_floats, parse_position, resolve, rest_after_space, shorten,
};
use super::polygon::polygon_is_non_convex;
use super::{LineProblem, Scan, Totals};
use raybench_geom::DVec3;

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

pub(super) struct State {
    totals: Totals,
    /// The line being scanned (1-based).
    pub(super) line_number: usize,
    /// Positions seen so far (tobj resolves negative indices against these counts).
    positions: Vec<DVec3>,
    vt_so_far: usize,
    vn_so_far: usize,
    colours: Colours,
    /// An `f` or `l` since tobj last closed a model (an `o`/`g` closes one only then).
    model_has_faces: bool,
    /// Forward references of the open model, per [`Element`] (see `remember_forward`).
    forward: [Vec<ForwardRef>; 3],
    pub(super) scan: Scan,
}

impl State {
    pub(super) fn new(totals: Totals) -> State {
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

    pub(super) fn line(&mut self, line: &str) -> Result<(), LineProblem> {
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
    pub(super) fn close_model(&mut self, at_line: usize) -> Result<(), LineProblem> {
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
