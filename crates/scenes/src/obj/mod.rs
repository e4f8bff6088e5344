//! Wavefront OBJ loading: positions and faces only, through tobj, treating the file as untrusted.
//!
//! Order of checks, each with its own clear error:
//! 1. read the bytes ourselves (missing file, directory, unreadable: the path is in the message);
//! 2. UTF-8 (with the line and column of the first bad byte; tobj would only say "read error");
//! 3. our line scan ([`scan`]), which rejects what tobj rejects, and garbage, with a line number,
//!    before tobj can panic on it;
//! 4. tobj itself inside `catch_unwind`, with a material loader that never opens a file (tobj
//!    panics on some MTL lines, and `mtllib` paths come from the file);
//! 5. [`TriangleMesh::new`], which drops and counts triangles Embree would ignore, then "no
//!    triangles" if nothing is left.

pub mod export;
mod scan;

use crate::{Scene, SceneError, SceneSource, View};
use raybench_geom::{EMBREE_LARGE, RemovedTriangles, TriangleMesh, Vec3};
use scan::{LineProblem, Scan};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::sync::Arc;

/// Beyond this magnitude the f32 spacing is ≥ 1 (from 2^23 ≈ 8.4e6 up): "far from the origin"
/// precision, worth a note (docs/validation.md, Loader).
const FAR_COORDINATE: f32 = 1e7;

/// Loads an OBJ file as a scene named after the file stem, with a default view from its bounds.
pub fn load_obj(path: &Path) -> Result<Scene, SceneError> {
    let bytes = read_bytes(path)?;
    load_obj_bytes(path, &bytes)
}

/// Loads OBJ text already in memory, exactly as [`load_obj`] loads a file (which reads the file
/// and calls this): `path` is never opened, it names the input in errors and names the scene.
/// Any byte string gives a scene or a [`SceneError`], never a panic (the fuzz target in
/// `fuzz/` feeds it arbitrary bytes).
pub fn load_obj_bytes(path: &Path, bytes: &[u8]) -> Result<Scene, SceneError> {
    let text = std::str::from_utf8(bytes).map_err(|e| not_utf8(path, bytes, e))?;
    // tobj would read a byte-order mark as part of the first keyword and skip that line.
    let (text, had_bom) = match text.strip_prefix('\u{feff}') {
        Some(rest) => (rest, true),
        None => (text, false),
    };
    let scan = scan::scan(text);
    if let Some(problem) = scan.first_problem.clone() {
        return Err(line_error(path, problem));
    }
    let models = run_tobj(path, text)?;
    let (positions, indices) = merge_models(path, &models)?;
    let (mesh, removed) =
        TriangleMesh::new(positions, indices).map_err(|source| SceneError::Mesh {
            path: path.to_owned(),
            source,
        })?;
    if mesh.is_empty() {
        return Err(SceneError::NoTriangles {
            path: path.to_owned(),
            detail: why_empty(&scan, &removed),
        });
    }
    let mut loader_notes = scan_notes(&scan);
    if had_bom {
        loader_notes.push("UTF-8 byte-order mark skipped".to_owned());
    }
    loader_notes.extend(far_coordinate_note(&mesh));
    let view = View::of_mesh(&mesh);
    Ok(Scene {
        name: scene_name(path),
        source: SceneSource::Obj {
            path: path.to_owned(),
            sha256: crate::sha256::sha256_hex(bytes),
        },
        view,
        views: vec![crate::NamedView {
            name: "default".into(),
            view,
        }],
        materials: vec![crate::Material::DEFAULT],
        triangle_materials: Vec::new(),
        mesh: Arc::new(mesh),
        removed,
        loader_notes,
    })
}

fn scene_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, SceneError> {
    Ok(crate::input::read_input(path)?)
}

fn not_utf8(path: &Path, bytes: &[u8], error: std::str::Utf8Error) -> SceneError {
    let good = &bytes[..error.valid_up_to()];
    let line_start = good.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    SceneError::NotUtf8 {
        path: path.to_owned(),
        line: good.iter().filter(|&&b| b == b'\n').count() + 1,
        column: good.len() - line_start + 1,
        hint: not_utf8_hint(bytes),
    }
}

/// The likely cause of bytes that are not UTF-8, from their first bytes.
fn not_utf8_hint(bytes: &[u8]) -> &'static str {
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        "; it starts with a UTF-16 byte-order mark: save it as UTF-8"
    } else if bytes.iter().take(512).any(|&b| b == 0) {
        "; it contains NUL bytes: binary data, not an OBJ file"
    } else {
        ""
    }
}

fn line_error(path: &Path, p: LineProblem) -> SceneError {
    SceneError::Obj {
        path: path.to_owned(),
        line: Some(p.line),
        problem: p.problem,
    }
}

/// The options the project mandates: triangles only, points and lines dropped, indices per
/// attribute (we only use positions, so no vertex duplication).
// `..Default::default()` is needed when another crate enables tobj's `merging`/`reordering`
// features (Cargo unifies features), which add fields.
#[allow(clippy::needless_update)]
fn load_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    }
}

/// Runs tobj on text that already passed our scan. A tobj error or panic here means the scan
/// missed a rule; the error names tobj's error kind in words, without a line.
fn run_tobj(path: &Path, text: &str) -> Result<Vec<tobj::Model>, SceneError> {
    let error = |problem: String| SceneError::Obj {
        path: path.to_owned(),
        line: None,
        problem,
    };
    // Materials are never read: the closure ignores the `mtllib` path and opens nothing.
    let never_read_materials = |_: &Path| Err(tobj::LoadError::GenericFailure);
    let result = catch_unwind(AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &load_options(), never_read_materials)
    }));
    match result {
        Ok(Ok((models, _materials))) => Ok(models),
        Ok(Err(e)) => Err(error(format!("tobj rejected the file: {}", describe(&e)))),
        Err(panic) => Err(error(format!(
            "tobj panicked on this file ({}); this is a tobj bug reachable from the file's bytes",
            panic_message(panic.as_ref())
        ))),
    }
}

/// tobj's error kind in plain words, with the likely cause.
fn describe(e: &tobj::LoadError) -> String {
    use tobj::LoadError as E;
    let hint = match e {
        E::FaceColorOutOfBounds => " (some `v` lines carry a colour and others do not)",
        E::FaceVertexOutOfBounds => " (an `f` refers to a vertex that does not exist)",
        E::InvalidObjectName => " (an `o` or `g` without a name)",
        _ => "",
    };
    format!("{e}{hint}")
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_owned())
}

/// Concatenates tobj's models (one per `o`/`g`/material change) into one vertex and index list,
/// offsetting each model's indices by the vertices before it.
fn merge_models(
    path: &Path,
    models: &[tobj::Model],
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), SceneError> {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for model in models {
        let base = positions.len();
        positions.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        for tri in model.mesh.indices.chunks_exact(3) {
            indices.push(offset_triangle(path, tri, base)?);
        }
    }
    Ok((positions, indices))
}

fn offset_triangle(path: &Path, tri: &[u32], base: usize) -> Result<[u32; 3], SceneError> {
    let too_many = || SceneError::Mesh {
        path: path.to_owned(),
        source: raybench_geom::MeshError::TooManyVertices(base),
    };
    let mut out = [0u32; 3];
    for (o, &i) in out.iter_mut().zip(tri) {
        *o = u32::try_from(base + i as usize).map_err(|_| too_many())?;
    }
    Ok(out)
}

/// Why a file that parsed has no triangle left.
fn why_empty(scan: &Scan, removed: &RemovedTriangles) -> String {
    if removed.total() > 0 {
        return format!(
            "all {} triangles were removed: {} with a NaN or infinite vertex, {} with a coordinate beyond {EMBREE_LARGE:e}, {} with a bad index",
            removed.total(),
            removed.non_finite,
            removed.too_large,
            removed.bad_index
        );
    }
    match (scan.vertices, scan.faces, scan.points_and_lines) {
        (0, 0, 0) => "no vertices and no faces: empty, or comments only".to_owned(),
        (v, 0, 0) => format!("{v} vertices but no faces"),
        (_, 0, pl) => format!("only {pl} point/line elements, which are not surfaces"),
        (_, f, _) => format!("{f} faces produced no triangles"),
    }
}

fn scan_notes(scan: &Scan) -> Vec<String> {
    let mut notes = Vec::new();
    let mut note = |count: u64, text: &str| {
        if count > 0 {
            notes.push(format!("{count} {text}"));
        }
    };
    note(scan.points_and_lines, "point/line elements skipped");
    note(
        scan.polylines_as_polygons,
        "`l` polylines with 3+ vertices became polygons (tobj reads `l` like `f`)",
    );
    note(scan.polygons, "polygons with 4+ vertices fan-triangulated");
    note(
        scan.non_convex_polygons,
        "of them non-convex: the fan may cover the wrong area",
    );
    note(
        scan.ignored_geometry,
        "`p`/`curv`/`curv2`/`surf` statements ignored",
    );
    note(
        scan.mtllib_lines,
        "`mtllib` statements ignored (materials are never read)",
    );
    note(
        scan.unknown_statements,
        "statements with unknown keywords ignored (as tobj does)",
    );
    notes
}

/// Counts the vertices of kept triangles (those of removed ones are not traced) that lie far
/// from the origin.
fn far_coordinate_note(mesh: &TriangleMesh) -> Option<String> {
    let mut used = vec![false; mesh.positions().len()];
    mesh.indices()
        .iter()
        .flatten()
        .for_each(|&i| used[i as usize] = true);
    let far = mesh
        .positions()
        .iter()
        .zip(&used)
        .filter(|&(p, &used)| used && p.abs().max_element() > FAR_COORDINATE)
        .count();
    (far > 0).then(|| {
        format!(
            "{far} vertices have a coordinate beyond {FAR_COORDINATE:e}, where f32 spacing is ≥ 1"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scan rejects this text before tobj runs; here tobj is called directly to prove the
    /// `catch_unwind` contains its debug-build overflow panic (or its release-build error).
    #[test]
    fn tobj_panic_on_relative_texcoord_is_contained() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-5 2/-5 3/-5\n";
        let err = run_tobj(Path::new("vt.obj"), text).unwrap_err().to_string();
        assert!(err.starts_with("vt.obj: tobj "), "{err}");
        // Overflow checks follow debug assertions: there the panic path itself was exercised.
        if cfg!(debug_assertions) {
            assert!(err.contains("tobj panicked"), "{err}");
        }
    }

    /// The scan's per-object forward-reference and colour rules mirror real tobj failures:
    /// tobj rejects these texts, but without a line; the scan names it.
    #[test]
    fn tobj_fails_without_a_line_where_the_scan_names_one() {
        let cases = [
            ("o a\nv 0 0 0\nf 1 2 3\no b\nv 1 0 0\nv 0 1 0\n", 3),
            ("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 2),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//2 2//2 3//2\ng\nvn 0 1 0\n",
                5,
            ),
        ];
        for (text, line) in cases {
            let tobj = run_tobj(Path::new("t.obj"), text).unwrap_err().to_string();
            assert!(tobj.starts_with("t.obj: tobj rejected the file"), "{tobj}");
            assert_eq!(
                scan::scan(text).first_problem.map(|p| p.line),
                Some(line),
                "{text:?}"
            );
        }
    }

    #[test]
    fn not_utf8_reports_line_and_column() {
        let bytes = b"v 0 0 0\nv 1 \xff 0\n";
        let e = String::from_utf8(bytes.to_vec()).unwrap_err();
        let err = not_utf8(Path::new("x.obj"), bytes, e.utf8_error()).to_string();
        assert_eq!(
            err,
            "x.obj: line 2: not UTF-8 text (invalid byte at column 5)"
        );
    }
}
