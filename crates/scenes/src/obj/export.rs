//! Writing a mesh as a Wavefront OBJ file that [`load_obj`](crate::load_obj) reads back
//! bit for bit.
//!
//! * Coordinates use Rust's `Display` for `f32`, which prints the shortest decimal that parses
//!   back to the same `f32` (never an exponent, so every OBJ reader understands it); `-0` stays
//!   `-0`.
//! * Faces are `f a b c` with 1-based indices, in mesh order, so primitive `i` stays `i` and
//!   each triangle keeps its vertices, corner order and winding.
//! * Vertices are written in the order faces first use them, and vertices no face uses are left
//!   out ([`in_file_order`]). That is the order the loader returns whatever the file says: tobj
//!   (with per-attribute indices, as [`load_obj`](crate::load_obj) uses it) numbers positions by
//!   first use in the faces. Writing that order makes the round trip exact: the loaded mesh has
//!   the positions and indices of `in_file_order(mesh)`, which equal `mesh`'s own whenever its
//!   vertices are already in first-use order with none unused (soup's are; sphere's and
//!   plane's, numbered ring by ring or row by row, are not). Either way triangle `i` has the
//!   same three vertices, bit for bit, before and after.
//!   Non-finite vertices are only ever used by triangles [`TriangleMesh::new`] removed, so they
//!   are never written.
//! * The file appears atomically: it is written to a temporary file next to `out`, synced, then
//!   renamed over `out`. On any error the temporary file is removed and `out` is untouched.

use raybench_geom::TriangleMesh;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `mesh` to `out` as OBJ, every line of `header` first as a `# ` comment. Loading the
/// file gives [`in_file_order`]`(mesh)` exactly (see the module documentation).
///
/// Errors name the path (`out`, or the temporary file next to it).
pub fn write_obj(mesh: &TriangleMesh, header: &str, out: &Path) -> io::Result<()> {
    let tmp = temp_path(out);
    let result = write_to(&tmp, &in_file_order(mesh), header)
        .map_err(|e| {
            with_path(
                e,
                &format!(
                    "{}: cannot write the temporary file {}",
                    out.display(),
                    tmp.display()
                ),
            )
        })
        .and_then(|()| {
            std::fs::rename(&tmp, out).map_err(|e| {
                with_path(
                    e,
                    &format!(
                        "{}: cannot rename the temporary file {} over it",
                        out.display(),
                        tmp.display()
                    ),
                )
            })
        });
    if result.is_err() {
        // Best effort: the file may never have been created.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `mesh` with its vertices renumbered in order of first use by the triangles (corners in
/// order), unused vertices dropped, triangles unchanged in order and corner order: the mesh
/// [`load_obj`](crate::load_obj) returns for the file [`write_obj`] writes. Triangle `i` has
/// bit-identical vertices in both meshes.
pub fn in_file_order(mesh: &TriangleMesh) -> TriangleMesh {
    const UNUSED: u32 = u32::MAX;
    let mut new_index = vec![UNUSED; mesh.positions().len()];
    let mut positions = Vec::new();
    let indices: Vec<[u32; 3]> = mesh
        .indices()
        .iter()
        .map(|tri| {
            tri.map(|old| {
                let slot = &mut new_index[old as usize];
                if *slot == UNUSED {
                    // At most as many vertices as the mesh has, which fit u32 (TriangleMesh::new).
                    *slot = positions.len() as u32;
                    positions.push(mesh.positions()[old as usize]);
                }
                *slot
            })
        })
        .collect();
    // A subset of a valid mesh's vertices and all its triangles: within every limit, and every
    // vertex finite and in range, so nothing is removed.
    TriangleMesh::new(positions, indices)
        .expect("a renumbering of a valid mesh is valid")
        .0
}

/// `DIR/.NAME.tmp-PID`: same directory (so the rename is atomic), hidden, unique per process.
fn temp_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "export.obj".to_owned());
    out.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

fn write_to(tmp: &Path, mesh: &TriangleMesh, header: &str) -> io::Result<()> {
    let mut w = BufWriter::with_capacity(1 << 20, File::create(tmp)?);
    for line in header.lines() {
        if line.is_empty() {
            writeln!(w, "#")?;
        } else {
            writeln!(w, "# {line}")?;
        }
    }
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.positions().len(),
        mesh.len()
    )?;
    for p in mesh.positions() {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for [a, b, c] in mesh.indices() {
        // In u64: index u32::MAX + 1 would overflow u32.
        writeln!(
            w,
            "f {} {} {}",
            u64::from(*a) + 1,
            u64::from(*b) + 1,
            u64::from(*c) + 1
        )?;
    }
    w.into_inner().map_err(|e| e.into_error())?.sync_all()
}

fn with_path(e: io::Error, what: &str) -> io::Error {
    io::Error::new(e.kind(), format!("{what}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load_obj;
    use raybench_geom::Vec3;

    fn temp_dir(tag: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("raybench-export-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn bits(m: &TriangleMesh) -> Vec<[u32; 3]> {
        m.positions()
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    }

    /// Awkward values: negative zero, subnormals, values with long shortest representations,
    /// the largest coordinate Embree accepts.
    #[test]
    fn awkward_values_round_trip_bit_exactly() {
        let positions = vec![
            Vec3::new(-0.0, 0.1, 1.0 / 3.0),
            Vec3::new(f32::MIN_POSITIVE / 8.0, -1.0e-30, 16_777_217.0),
            Vec3::new(1.8e18, -1.8e18, std::f32::consts::PI),
            Vec3::new(0.3, 0.7, -2.5e-7),
        ];
        let (mesh, _) = TriangleMesh::new(positions, vec![[0, 1, 2], [2, 1, 3]]).unwrap();
        assert_eq!(in_file_order(&mesh), mesh, "already in first-use order");
        let dir = temp_dir("awkward");
        let out = dir.join("a.obj");
        write_obj(&mesh, "test\n\nsecond line", &out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.starts_with("# test\n#\n# second line\n"), "{text}");
        let back = load_obj(&out).unwrap();
        assert_eq!(bits(&back.mesh), bits(&mesh));
        assert_eq!(back.mesh.indices(), mesh.indices());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Vertices out of first-use order, unused (one of them NaN, used only by a triangle the
    /// mesh removed), and shared: the file holds the first-use order, which is what loads back,
    /// and every triangle keeps its exact vertices.
    #[test]
    fn any_vertex_order_loads_back_as_in_file_order() {
        let positions = vec![
            Vec3::new(5.0, 5.0, 5.0), // unused
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(f32::NAN, 0.0, 0.0), // used only by a removed triangle
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(1.0, 1.0, -0.0),
        ];
        let indices = vec![[3, 1, 4], [2, 1, 3], [5, 1, 3], [4, 4, 5]];
        let (mesh, removed) = TriangleMesh::new(positions, indices).unwrap();
        assert_eq!((mesh.len(), removed.non_finite), (3, 1));
        let canonical = in_file_order(&mesh);
        assert_eq!(canonical.indices(), &[[0, 1, 2], [3, 1, 0], [2, 2, 3]]);
        assert_eq!(canonical.positions().len(), 4);
        let dir = temp_dir("order");
        let out = dir.join("o.obj");
        write_obj(&mesh, "", &out).unwrap();
        let back = load_obj(&out).unwrap();
        assert_eq!(bits(&back.mesh), bits(&canonical));
        assert_eq!(back.mesh.indices(), canonical.indices());
        for i in 0..mesh.len() {
            let t = |m: &TriangleMesh| {
                let t = m.triangle(i);
                [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits))
            };
            assert_eq!(t(&back.mesh), t(&mesh), "triangle {i}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_leaves_nothing_behind() {
        let dir = temp_dir("fail");
        let (mesh, _) =
            TriangleMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        // The target is a directory: the rename fails after the data was written.
        let target = dir.join("is-a-dir.obj");
        std::fs::create_dir(&target).unwrap();
        let err = write_obj(&mesh, "", &target).unwrap_err().to_string();
        assert!(err.contains("is-a-dir.obj"), "{err}");
        // A missing directory: the temporary file cannot be created.
        let missing = dir.join("no/such/dir/x.obj");
        let err = write_obj(&mesh, "", &missing).unwrap_err().to_string();
        assert!(err.contains("no/such/dir"), "{err}");
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("is-a-dir.obj")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
