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
//! * [`write_obj`] writes to any `Write`: the harness streams it into its atomic file writer,
//!   so the file appears whole or not at all.

use raybench_geom::TriangleMesh;
use std::io::{self, Write};

/// Writes `mesh` as OBJ text to `w`, every line of `header` first as a `# ` comment. Loading
/// the text gives [`in_file_order`]`(mesh)` exactly (see the module documentation).
pub fn write_obj(mesh: &TriangleMesh, header: &str, w: &mut dyn Write) -> io::Result<()> {
    let mesh = in_file_order(mesh);
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
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load_obj_bytes;
    use raybench_geom::Vec3;
    use std::path::Path;

    fn exported(mesh: &TriangleMesh, header: &str) -> Vec<u8> {
        let mut bytes = Vec::new();
        write_obj(mesh, header, &mut bytes).unwrap();
        bytes
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
        let bytes = exported(&mesh, "test\n\nsecond line");
        let text = String::from_utf8(bytes.clone()).unwrap();
        assert!(text.starts_with("# test\n#\n# second line\n"), "{text}");
        let back = load_obj_bytes(Path::new("a.obj"), &bytes).unwrap();
        assert_eq!(bits(&back.mesh), bits(&mesh));
        assert_eq!(back.mesh.indices(), mesh.indices());
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
        let back = load_obj_bytes(Path::new("o.obj"), &exported(&mesh, "")).unwrap();
        assert_eq!(bits(&back.mesh), bits(&canonical));
        assert_eq!(back.mesh.indices(), canonical.indices());
        for i in 0..mesh.len() {
            let t = |m: &TriangleMesh| {
                let t = m.triangle(i);
                [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits))
            };
            assert_eq!(t(&back.mesh), t(&mesh), "triangle {i}");
        }
    }
}
