//! `peer-obvhs`: the `obvhs` crate (0.4, MIT OR Apache-2.0): a PLOC binary BVH (Meister and
//! Bittner 2018) with parallel reinsertion, collapsed to a compressed 8-wide CWBVH (Ylitie et
//! al. 2017, 80-byte nodes) and walked by the crate's CPU traversal, four child boxes at a
//! time. The traversal calls back for each primitive in a reached leaf; that callback is
//! raybench's two-sided Möller–Trumbore, because the crate's `Triangle::intersect` returns a
//! distance without barycentrics. The crate accepts a hit only strictly below its `tmax`, so it
//! is handed `next_up(t_max)` and the wrapper keeps the best hit itself (inclusive `t_max`, the
//! lower index on equal `t`). Caveats: the build runs on the calling rayon pool; the crate
//! offers no closest-point query.

use super::moller_triangles;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::{CwBvh, builder::build_cwbvh_from_tris};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory};
use raybench_geom::{MollerTriangle, Ray, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;
use std::time::Duration;

/// The crate's build presets (`BvhBuildParams::*_build`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObvhsPreset {
    Fast,
    /// The preset the crate's own example uses.
    #[default]
    Medium,
    Slow,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct ObvhsParams {
    pub preset: ObvhsPreset,
}

#[derive(Debug)]
pub struct Obvhs {
    name: String,
    tris: Vec<MollerTriangle>,
    /// `None` for an empty mesh (nothing to build).
    bvh: Option<CwBvh>,
}

fn v3a(v: Vec3) -> Vec3A {
    Vec3A::new(v.x, v.y, v.z)
}

impl Obvhs {
    /// The crate's ray, or `None` for one its constructor refuses (non-finite origin or
    /// direction: it asserts in debug builds); such rays hit nothing, as for every structure.
    fn crate_ray(ray: &Ray) -> Option<obvhs::ray::Ray> {
        if !(ray.origin().is_finite() && ray.dir().is_finite()) {
            return None;
        }
        Some(obvhs::ray::Ray::new(
            v3a(ray.origin()),
            v3a(ray.dir()),
            ray.t_min(),
            ray.t_max().next_up(),
        ))
    }
}

impl Accel for Obvhs {
    type Params = ObvhsParams;

    fn build(mesh: Arc<TriangleMesh>, params: &ObvhsParams) -> Result<Self, BuildError> {
        let tris: Vec<obvhs::triangle::Triangle> = mesh
            .triangles()
            .map(|t| obvhs::triangle::Triangle {
                v0: v3a(t.v0),
                v1: v3a(t.v1),
                v2: v3a(t.v2),
            })
            .collect();
        let config = match params.preset {
            ObvhsPreset::Fast => BvhBuildParams::fast_build(),
            ObvhsPreset::Medium => BvhBuildParams::medium_build(),
            ObvhsPreset::Slow => BvhBuildParams::slow_build(),
        };
        let bvh = (!tris.is_empty())
            .then(|| build_cwbvh_from_tris(&tris, config, &mut Duration::default()));
        let name = match params.preset {
            ObvhsPreset::Medium => "peer-obvhs".to_string(),
            p => format!(
                "peer-obvhs-{}",
                serde_json::to_value(p)
                    .unwrap_or_default()
                    .as_str()
                    .unwrap_or("?")
            ),
        };
        Ok(Obvhs {
            name,
            tris: moller_triangles(&mesh),
            bvh,
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::uncounted_queries!();

    raybench_accel::no_closest_point!();

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut best: Option<Hit> = None;
        let mut r = *ray;
        let mut hit = obvhs::ray::RayHit::none();
        bvh.ray_traverse(Self::crate_ray(ray)?, &mut hit, |_, id| {
            let prim = bvh.primitive_indices[id] as usize;
            let Some(h) = self.tris[prim].intersect(&r) else {
                return f32::INFINITY;
            };
            if !best.is_some_and(|b| h.t > b.t || (h.t == b.t && prim as u32 > b.prim)) {
                best = Some(Hit::from_tri_hit(prim as u32, h));
                r = r.with_t_max(h.t);
            }
            h.t
        });
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let (Some(bvh), Some(r)) = (self.bvh.as_ref(), Self::crate_ray(ray)) else {
            return false;
        };
        !bvh.ray_traverse_miss(r, |_, id| {
            let prim = bvh.primitive_indices[id] as usize;
            self.tris[prim]
                .intersect(ray)
                .map_or(f32::INFINITY, |h| h.t)
        })
    }

    fn build_stats(&self) -> BuildStats {
        let Some(bvh) = &self.bvh else {
            return BuildStats::default();
        };
        BuildStats {
            nodes: bvh.nodes.len() as u64,
            refs: bvh.primitive_indices.len() as u64,
            ..BuildStats::default()
        }
    }

    /// From the crate's own vectors: nodes and primitive indices, plus the triangle copies the
    /// wrapper's Möller–Trumbore reads.
    fn memory(&self) -> Memory {
        let (nodes, indices) = self.bvh.as_ref().map_or((0, 0), |b| {
            (
                b.nodes.len() * size_of::<CwBvhNode>(),
                b.primitive_indices.len() * 4,
            )
        });
        Memory {
            nodes: nodes as u64,
            indices: indices as u64,
            primitives: (self.tris.len() * size_of::<MollerTriangle>()) as u64,
        }
    }
}
