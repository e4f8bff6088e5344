//! The one recipe that turns a scene into the rays of its ray workloads, used by every caller
//! that traces workloads (the harness's `run`, `verify` and timing probes), so all of them
//! trace identical rays.
//!
//! Primary and random rays come from the view and the bounds alone. The secondary workloads
//! start at the surfaces the primary rays hit, so the recipe traces the primary rays once with
//! a reference (`trace`: its closest hit) and builds shadow, diffuse and Whitted rays from
//! those hits; Whitted's recursion asks the reference again at each generation. Every
//! structure then traces the same set, whatever it would have hit itself.

use crate::{
    Scene, SurfaceHit, WhittedParams, Workload, diffuse_rays, primary_rays, random_rays,
    shadow_rays, whitted_children,
};
use raybench_geom::Ray;

/// A reference's closest hit, as secondary workloads need it.
pub type TraceFn<'a> = &'a (dyn Fn(&Ray) -> Option<SurfaceHit> + Sync);

/// A scene's primary rays and the reference's hits on them, ready to make any ray workload.
pub struct RayRecipe<'a> {
    scene: &'a Scene,
    trace: TraceFn<'a>,
    ray_count: usize,
    seed: u64,
    primary: Vec<Ray>,
    /// Width × height of the primary image.
    size: (u32, u32),
    hits: Vec<Option<SurfaceHit>>,
}

impl std::fmt::Debug for RayRecipe<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RayRecipe")
            .field("scene", &self.scene.name)
            .field("ray_count", &self.ray_count)
            .field("seed", &self.seed)
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

impl<'a> RayRecipe<'a> {
    /// Traces the primary rays of `scene` (about `ray_count` pixels at 4:3) with `trace`.
    pub fn new(scene: &'a Scene, ray_count: usize, seed: u64, trace: TraceFn<'a>) -> RayRecipe<'a> {
        let bounds = scene.mesh.bounds();
        let (primary, w, h) = primary_rays(&scene.view, &bounds, ray_count);
        let hits = primary.iter().map(trace).collect();
        RayRecipe {
            scene,
            trace,
            ray_count,
            seed,
            primary,
            size: (w, h),
            hits,
        }
    }

    /// The primary image's width and height.
    pub fn image_size(&self) -> (u32, u32) {
        self.size
    }

    /// The rays of `workload`; `None` for a closest-point workload.
    pub fn rays(&self, workload: Workload) -> Option<Vec<Ray>> {
        let s = self.scene;
        Some(match workload {
            Workload::Primary => self.primary.clone(),
            Workload::Random => random_rays(&s.mesh.bounds(), self.ray_count, self.seed),
            Workload::Shadow => shadow_rays(&s.mesh, s.view.light, &self.primary, &self.hits),
            Workload::Diffuse => diffuse_rays(&s.mesh, &self.primary, &self.hits, self.seed),
            Workload::Whitted => self.whitted(),
            Workload::PointsNear | Workload::PointsVolume => return None,
        })
    }

    /// Every generation of Whitted's recursion below the primary rays, each traced with the
    /// reference to start the next.
    fn whitted(&self) -> Vec<Ray> {
        let params = WhittedParams::default();
        let mut all = Vec::new();
        let mut parents = self.primary.clone();
        let mut weights = vec![1.0; parents.len()];
        let mut hits = self.hits.clone();
        for depth in 1..=params.max_depth {
            let (children, child_weights) =
                whitted_children(self.scene, &parents, &weights, &hits, &params);
            all.extend_from_slice(&children);
            if depth == params.max_depth || children.is_empty() {
                break;
            }
            hits = children.iter().map(self.trace).collect();
            (parents, weights) = (children, child_weights);
        }
        all
    }
}
