use crate::{Aabb, EMBREE_LARGE, Triangle};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// An indexed triangle mesh that every structure and Embree can trace as it is.
///
/// The only way to make one is [`TriangleMesh::new`], which removes the triangles Embree would
/// silently ignore (an index out of range, a NaN or infinite vertex, a coordinate beyond
/// 1.844e18) and counts them, so our structures and Embree always see the same primitives and
/// primitive `i` means the same triangle everywhere. Zero-area triangles are kept (Embree keeps
/// them too and never hits them) and counted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

/// Triangles removed by [`TriangleMesh::new`], by reason, plus kept zero-area triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RemovedTriangles {
    /// An index `>=` the number of vertices.
    pub bad_index: u64,
    /// A vertex with a NaN or infinite coordinate.
    pub non_finite: u64,
    /// A vertex with a finite coordinate beyond Embree's 1.844e18.
    pub too_large: u64,
    /// Kept: zero area (collinear or repeated vertices); never hit by Embree or by us.
    pub degenerate_kept: u64,
}

impl RemovedTriangles {
    /// Triangles actually removed (degenerate ones are kept and not counted here).
    pub fn total(&self) -> u64 {
        self.bad_index + self.non_finite + self.too_large
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshError {
    /// More vertices than 32-bit indices (Embree's `RTC_FORMAT_UINT3`) can address.
    TooManyVertices(usize),
    TooManyTriangles(usize),
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshError::TooManyVertices(n) => {
                write!(f, "{n} vertices do not fit 32-bit indices (Embree's limit)")
            }
            MeshError::TooManyTriangles(n) => {
                write!(f, "{n} triangles do not fit 32-bit primitive ids")
            }
        }
    }
}

impl std::error::Error for MeshError {}

fn vertex_problem(p: Vec3) -> Option<fn(&mut RemovedTriangles)> {
    if !p.is_finite() {
        Some(|r| r.non_finite += 1)
    } else if p.abs().max_element() > EMBREE_LARGE {
        Some(|r| r.too_large += 1)
    } else {
        None
    }
}

impl TriangleMesh {
    /// Builds a mesh, dropping and counting the triangles Embree would ignore.
    pub fn new(
        positions: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
    ) -> Result<(TriangleMesh, RemovedTriangles), MeshError> {
        if u32::try_from(positions.len()).is_err() {
            return Err(MeshError::TooManyVertices(positions.len()));
        }
        if u32::try_from(indices.len()).is_err() {
            return Err(MeshError::TooManyTriangles(indices.len()));
        }
        let mut removed = RemovedTriangles::default();
        let mut kept = Vec::with_capacity(indices.len());
        for tri in indices {
            if tri.iter().any(|&i| i as usize >= positions.len()) {
                removed.bad_index += 1;
                continue;
            }
            let verts = tri.map(|i| positions[i as usize]);
            if let Some(count) = verts.iter().find_map(|&p| vertex_problem(p)) {
                count(&mut removed);
                continue;
            }
            if Triangle::new(verts[0], verts[1], verts[2]).area() == 0.0 {
                removed.degenerate_kept += 1;
            }
            kept.push(tri);
        }
        Ok((
            TriangleMesh {
                positions,
                indices: kept,
            },
            removed,
        ))
    }

    /// A mesh of separate triangles (three vertices each).
    pub fn from_triangles(
        tris: &[Triangle],
    ) -> Result<(TriangleMesh, RemovedTriangles), MeshError> {
        let positions = tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).collect();
        let indices = (0..tris.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        TriangleMesh::new(positions, indices)
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    #[inline(always)]
    pub fn triangle(&self, prim: usize) -> Triangle {
        let [a, b, c] = self.indices[prim];
        Triangle::new(
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        )
    }

    pub fn triangles(&self) -> impl ExactSizeIterator<Item = Triangle> + '_ {
        (0..self.len()).map(|i| self.triangle(i))
    }

    /// Bounds of the referenced vertices (unreferenced ones do not count).
    pub fn bounds(&self) -> Aabb {
        self.triangles()
            .fold(Aabb::EMPTY, |b, t| b.union(&t.bounds()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removes_what_embree_ignores_and_counts_it() {
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::new(0.0, f32::INFINITY, 0.0),
            Vec3::new(0.0, 0.0, 2e18),
            Vec3::new(0.0, 0.0, 1e18),
        ];
        let indices = vec![
            [0, 1, 2], // kept
            [0, 1, 7], // bad index
            [0, 1, 3], // NaN
            [0, 4, 2], // inf
            [5, 1, 2], // 2e18
            [6, 1, 2], // 1e18: below the limit, kept
            [0, 0, 1], // degenerate, kept
        ];
        let (mesh, removed) = TriangleMesh::new(positions, indices).unwrap();
        assert_eq!(mesh.len(), 3);
        assert_eq!(mesh.indices(), &[[0, 1, 2], [6, 1, 2], [0, 0, 1]]);
        assert_eq!(
            removed,
            RemovedTriangles {
                bad_index: 1,
                non_finite: 2,
                too_large: 1,
                degenerate_kept: 1
            }
        );
        assert_eq!(removed.total(), 4);
    }

    #[test]
    fn empty_mesh_is_allowed() {
        let (mesh, removed) = TriangleMesh::new(vec![], vec![]).unwrap();
        assert!(mesh.is_empty());
        assert!(mesh.bounds().is_empty());
        assert_eq!(removed.total(), 0);
    }

    #[test]
    fn bounds_ignore_unreferenced_vertices() {
        let (mesh, _) = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::splat(100.0)],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_eq!(
            mesh.bounds(),
            Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))
        );
    }
}
