//! The tokens of a statement: face corners, indices, positions and numbers, parsed with
//! tobj's rules, and how a token is quoted in a message.

use raybench_geom::DVec3;
use std::num::IntErrorKind;

/// The kinds of element a face corner refers to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Element {
    Position,
    TexCoord,
    Normal,
}

impl Element {
    pub(super) fn noun(self) -> &'static str {
        match self {
            Element::Position => "vertex",
            Element::TexCoord => "texture-coordinate",
            Element::Normal => "normal",
        }
    }

    pub(super) fn keyword(self) -> &'static str {
        match self {
            Element::Position => "v",
            Element::TexCoord => "vt",
            Element::Normal => "vn",
        }
    }
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn`: up to three optional signed integers.
pub(super) fn parse_corner(token: &str) -> Result<[Option<i64>; 3], String> {
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
///
/// [`State::close_model`]: super::State::close_model
pub(super) fn resolve(
    index: i64,
    so_far: usize,
    total: usize,
    element: Element,
) -> Result<usize, String> {
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
pub(super) fn parse_position(args: &[&str]) -> Result<DVec3, String> {
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
pub(super) fn parse_floats(args: &[&str], n: usize, need: &str) -> Result<Vec<f64>, String> {
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

pub(super) fn rest_after_space(line: &str) -> &str {
    line.split_once(' ').map_or("", |(_, rest)| rest.trim())
}

/// At most 40 characters of a token, so a huge garbage line does not flood the message, with
/// invisible characters (zero-width spaces, controls) escaped so the reader sees them.
pub(super) fn shorten(s: &str) -> String {
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
