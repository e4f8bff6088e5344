//! `peer-kdtree-ray`: the `kdtree-ray` crate (1.2, MIT), the one SAH k-d tree on crates.io
//! (Wald–Havran 2006 O(N log N) build, over triangle boxes: no perfect splits against the
//! triangles themselves). Its query returns a freshly allocated list of every primitive in
//! every leaf whose cell the ray's line crosses (unordered, repeats across leaves, no early
//! exit, the `[t_min, t_max]` segment ignored); the crate has no primitive test, so each
//! candidate is finished with raybench's two-sided Möller–Trumbore. Caveats: the allocation
//! per query is the crate's API and is timed, as a user would pay it; the crate builds in a
//! rayon pool of its own sized to the machine, not the run's `--threads`; it panics on an
//! empty shape list, so an empty mesh keeps no tree; it offers no closest-point query.

use super::{any_among, closest_among, moller_triangles};
use cgmath::Vector3;
use kdtree_ray::{AABB, Bounded, KDTree};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory};
use raybench_geom::{MollerTriangle, Ray, Triangle, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// No knobs: the crate's default builder configuration (`KDTree::build`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct KdtreeRayParams {}

struct Boxed(Triangle);

fn v3(v: Vec3) -> Vector3<f32> {
    Vector3::new(v.x, v.y, v.z)
}

impl Bounded for Boxed {
    fn bound(&self) -> AABB {
        let t = &self.0;
        AABB::new(v3(t.v0.min(t.v1).min(t.v2)), v3(t.v0.max(t.v1).max(t.v2)))
    }
}

#[derive(Debug)]
pub struct KdtreeRay {
    tris: Vec<MollerTriangle>,
    tree: Option<KDTree>,
}

impl KdtreeRay {
    fn candidates(&self, ray: &Ray) -> Vec<usize> {
        match &self.tree {
            Some(t) => t.intersect(&v3(ray.origin()), &v3(ray.dir())),
            None => Vec::new(),
        }
    }
}

impl Accel for KdtreeRay {
    type Params = KdtreeRayParams;

    fn build(mesh: Arc<TriangleMesh>, _params: &KdtreeRayParams) -> Result<Self, BuildError> {
        let shapes: Vec<Boxed> = mesh.triangles().map(Boxed).collect();
        let tree = (!shapes.is_empty()).then(|| KDTree::build(&shapes));
        Ok(KdtreeRay {
            tris: moller_triangles(&mesh),
            tree,
        })
    }

    fn name(&self) -> &str {
        "peer-kdtree-ray"
    }

    raybench_accel::uncounted_queries!();

    raybench_accel::no_closest_point!();

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        closest_among(&self.tris, ray, self.candidates(ray).into_iter())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        any_among(&self.tris, ray, self.candidates(ray).into_iter())
    }

    /// The crate keeps its nodes private: no shape figures.
    fn build_stats(&self) -> BuildStats {
        BuildStats::default()
    }

    /// The crate reports no size and keeps its nodes private: only the triangle copies this
    /// wrapper holds for its Möller–Trumbore are counted; the tree itself is missing.
    fn memory(&self) -> Memory {
        Memory {
            primitives: (self.tris.len() * size_of::<MollerTriangle>()) as u64,
            ..Memory::default()
        }
    }
}
