//! `peer-parry3d`: the `parry3d` crate (0.31, Apache-2.0), Dimforge's collision library, whose
//! `TriMesh` keeps a binary BVH over its triangles (built by `TriMesh::new`, no flags: no
//! vertex merging or topology). Closest hit is the crate's own ray cast
//! (`CompositeShapeRef::cast_local_ray`, its own ray–triangle test) returning the triangle and
//! the time of impact; barycentrics are computed here from the hit point. parry's rays start at
//! `t = 0`, so a query with `t_min > 0` is cast from `origin + t_min·dir` over
//! `t_max - t_min` and its `t` shifted back: one more rounding than the other structures take.
//! Any hit is the same full closest-hit cast (the crate's `intersects_local_ray` is one too).
//! Closest point is the crate's `project_local_point_and_get_feature`, the nearest point then
//! recomputed with raybench's exact point–triangle distance so the radius rule is shared.

use super::point_answer;
use parry3d::math::Vector;
use parry3d::query::Ray as PRay;
use parry3d::shape::{CompositeShapeRef, TriMesh};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory, PointHit};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// No knobs: `TriMesh::new` with no flags.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ParryParams {}

#[derive(Debug)]
pub struct Parry {
    mesh: Arc<TriangleMesh>,
    /// `None` for an empty mesh (the crate refuses one).
    trimesh: Option<TriMesh>,
}

fn pv(v: Vec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

impl Parry {
    /// The query as parry casts it: the segment `[t_min, t_max]` moved to start at 0.
    fn crate_ray(ray: &Ray) -> (PRay, f32) {
        let (o, d) = (ray.origin(), ray.dir());
        let start = if ray.t_min() > 0.0 {
            o + ray.t_min() * d
        } else {
            o
        };
        let span = ray.t_max() - ray.t_min().max(0.0);
        (PRay::new(pv(start), pv(d)), span)
    }

    /// Barycentric weights `(u, v)` of `p` on triangle `prim` (of `v1` and `v2`).
    fn barycentric(&self, prim: usize, p: Vec3) -> (f32, f32) {
        let t = self.mesh.triangle(prim);
        let (e1, e2, q) = (t.v1 - t.v0, t.v2 - t.v0, p - t.v0);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (q1, q2) = (q.dot(e1), q.dot(e2));
        let den = d11 * d22 - d12 * d12;
        if den == 0.0 {
            return (0.0, 0.0);
        }
        ((d22 * q1 - d12 * q2) / den, (d11 * q2 - d12 * q1) / den)
    }
}

impl Accel for Parry {
    type Params = ParryParams;

    fn build(mesh: Arc<TriangleMesh>, _params: &ParryParams) -> Result<Self, BuildError> {
        let trimesh = if mesh.is_empty() {
            None
        } else {
            let vertices = mesh.positions().iter().map(|&v| pv(v)).collect();
            let indices = mesh.indices().to_vec();
            Some(TriMesh::new(vertices, indices).map_err(|e| BuildError::Backend(e.to_string()))?)
        };
        Ok(Parry { mesh, trimesh })
    }

    fn name(&self) -> &str {
        "peer-parry3d"
    }

    raybench_accel::uncounted_queries!();

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let tm = self.trimesh.as_ref()?;
        let (r, span) = Self::crate_ray(ray);
        let (prim, toi) = CompositeShapeRef(tm).cast_local_ray(&r, span, false)?;
        let t = toi + ray.t_min().max(0.0);
        if !(t > ray.t_min() && t <= ray.t_max()) {
            return None;
        }
        let (u, v) = self.barycentric(prim as usize, ray.at(t));
        Some(Hit { t, prim, u, v })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        // The crate's `intersects_local_ray` is this same full cast; going through
        // `intersect` applies the one strict-`t_min` check to both queries.
        self.intersect(ray).is_some()
    }

    fn closest_point(&self, p: Vec3, max_radius: f32) -> Option<PointHit> {
        let tm = self.trimesh.as_ref()?;
        let radius = if max_radius.is_finite() {
            max_radius
        } else {
            f32::MAX
        };
        let found = CompositeShapeRef(tm)
            .project_local_point_and_get_feature(pv(p), radius)
            .map(|(prim, _, _)| prim as usize);
        point_answer(&self.mesh, p, max_radius, found)
    }

    fn build_stats(&self) -> BuildStats {
        let Some(tm) = &self.trimesh else {
            return BuildStats::default();
        };
        BuildStats {
            leaves: u64::from(tm.bvh().leaf_count()),
            refs: u64::from(tm.bvh().leaf_count()),
            ..BuildStats::default()
        }
    }

    /// What the crate reports: `TriMesh::total_memory_size` (vertices, indices and its BVH),
    /// all counted as nodes since the crate does not split it.
    fn memory(&self) -> Memory {
        Memory {
            nodes: self
                .trimesh
                .as_ref()
                .map_or(0, |t| t.total_memory_size() as u64),
            ..Memory::default()
        }
    }
}
