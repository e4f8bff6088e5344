//! Our own line-by-line pass over an OBJ text, run before tobj.
//!
//! tobj reports only the kind of an error ("face vertex index out of bounds"), never the line,
//! and panics on one input (a relative `vt` index reaching too far back, in debug builds). This
//! scan mirrors tobj's rules for the statements it parses, so it finds the first offending line
//! and rejects it before tobj sees it. It also counts what tobj drops or changes silently (point
//! and line elements, `l` polylines turned into polygons, non-convex polygons that the fan
//! triangulation gets wrong, ignored free-form geometry) so the loader can say so in its notes.
//!
//! One rule is ours, not tobj's: a line whose first word is not an OBJ statement is rejected
//! (tobj ignores it). Such a line means a corrupt or truncated file more often than an exotic
//! exporter.

use raybench_geom::DVec3;

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

/// Scans the whole text; stops collecting at the first problem.
pub(super) fn scan(text: &str) -> Scan {
    let totals = count_elements(text);
    let mut state = State {
        totals,
        positions: Vec::new(),
        vt_so_far: 0,
        vn_so_far: 0,
        scan: Scan::default(),
    };
    for (i, line) in text.lines().enumerate() {
        if let Err(problem) = state.line(line) {
            state.scan.first_problem = Some(LineProblem {
                line: i + 1,
                problem,
            });
            break;
        }
    }
    state.scan
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
    /// Positions seen so far (tobj resolves negative indices against these counts).
    positions: Vec<DVec3>,
    vt_so_far: usize,
    vn_so_far: usize,
    scan: Scan,
}

impl State {
    fn line(&mut self, line: &str) -> Result<(), String> {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            k if k.starts_with('#') => {}
            "v" => {
                let p = parse_position(&args)?;
                self.positions.push(p);
                self.scan.vertices += 1;
            }
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
        Ok(())
    }

    /// The position index (0-based) of every corner of an `f` or `l` statement, checked the way
    /// tobj checks `v`, `vt` and `vn` indices.
    fn corners(&self, args: &[&str]) -> Result<Vec<usize>, String> {
        args.iter().map(|token| self.corner(token)).collect()
    }

    fn corner(&self, token: &str) -> Result<usize, String> {
        let parts: Vec<&str> = token.split('/').collect();
        if parts.len() > 3 {
            return Err(format!(
                "`{}` has more than 3 slash-separated parts",
                shorten(token)
            ));
        }
        let mut numbers = [None; 3];
        for (slot, part) in numbers.iter_mut().zip(&parts) {
            if !part.is_empty() {
                let n = part.parse::<i64>().map_err(|_| {
                    let whole = if parts.len() > 1 {
                        format!(" in `{}`", shorten(token))
                    } else {
                        String::new()
                    };
                    format!("`{}`{whole} is not an integer index", shorten(part))
                })?;
                *slot = Some(n);
            }
        }
        let [v, vt, vn] = numbers;
        let v = v.ok_or_else(|| format!("`{}` has no vertex index", shorten(token)))?;
        let position = resolve(v, self.positions.len(), self.totals.v, "vertex", "v")?;
        // tobj reads `vt`/`vn` indices only when the file has any `vt`/`vn`, and treats 0 as absent.
        if let Some(vt) = vt.filter(|&i| i != 0 && self.totals.vt > 0) {
            resolve(
                vt,
                self.vt_so_far,
                self.totals.vt,
                "texture-coordinate",
                "vt",
            )?;
        }
        if let Some(vn) = vn.filter(|&i| i != 0 && self.totals.vn > 0) {
            resolve(vn, self.vn_so_far, self.totals.vn, "normal", "vn")?;
        }
        Ok(position)
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

/// Resolves a 1-based or negative (relative) OBJ index to a 0-based one, as tobj does: negative
/// indices count back from the elements seen so far, positive ones may refer forward.
fn resolve(
    index: i64,
    so_far: usize,
    total: usize,
    what: &str,
    keyword: &str,
) -> Result<usize, String> {
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
        3 | 6 => Ok(p),
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

/// At most 40 characters of a token, so a huge garbage line does not flood the message.
fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    if s.chars().count() <= MAX {
        s.to_owned()
    } else {
        s.chars().take(MAX).collect::<String>() + "…"
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
    (0..n).any(|i| {
        let a = points[i];
        let b = points[(i + 1) % n];
        let c = points[(i + 2) % n];
        let (e1, e2) = (b - a, c - b);
        let turn = e1.cross(e2).dot(normal);
        // Relative tolerance: rounding in the cross product, not geometry, below 1e-9.
        turn < -1e-9 * e1.length() * e2.length() * normal.length()
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
