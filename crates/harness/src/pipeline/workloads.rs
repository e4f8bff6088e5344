//! The workloads of one scene, made once and shared by every structure: rays from the one
//! workload recipe ([`RayRecipe`]: secondary rays start at the reference's primary hits) or
//! seeded query points, each with the reference's answers on its timed path.

use super::measure::{Answers, point_pass, trace_pass};
use super::scenes::LoadedScene;
use crate::registry::{BuildContext, StructureEntry};
use crate::report::run::{SceneRecord, TriangleCounts, WorkloadRecord};
use anyhow::{Context, Result, bail};
use raybench_accel::{Accel, PointHit, PreparedRays};
use raybench_geom::{Ray, Vec3};
use raybench_scenes::{RayRecipe, Scene, SurfaceHit, Workload};

/// One workload's rays (the same for every structure) and the reference's answers to them.
pub(crate) struct PreparedWorkload {
    pub workload: Workload,
    pub rays: Vec<Ray>,
    /// The reference's answers, traced on the timed path.
    pub reference: Answers,
    /// The primary image's size, for the primary workload.
    pub size: Option<(u32, u32)>,
}

/// One closest-point workload's query points (the same for every structure) and the
/// reference's answers to them.
pub(crate) struct PreparedPoints {
    pub workload: Workload,
    pub points: Vec<Vec3>,
    /// The search radius every structure is asked with (the workload's: infinite).
    pub radius: f32,
    /// The reference's answers, on its timed path.
    pub reference: Vec<Option<PointHit>>,
}

/// How many queries each kind of workload asks.
#[derive(Clone, Copy, Debug)]
pub(crate) struct QueryCounts {
    /// Rays per ray workload (primary: about this many pixels).
    pub rays: usize,
    /// Query points per closest-point workload.
    pub points: usize,
}

/// A scene with its workloads generated and the reference built.
pub(crate) struct SceneRun<'a> {
    pub scene: &'a LoadedScene,
    pub reference: Box<dyn Accel>,
    pub reference_name: String,
    /// The ray workloads, in the order asked.
    pub workloads: Vec<PreparedWorkload>,
    /// The closest-point workloads, in the order asked.
    pub point_workloads: Vec<PreparedPoints>,
}

impl<'a> SceneRun<'a> {
    /// Builds the reference and generates every workload's rays with it (secondary rays start
    /// at its primary hits) or its query points, and its answers to them.
    pub(crate) fn prepare(
        scene: &'a LoadedScene,
        workloads: &[Workload],
        counts: QueryCounts,
        seed: u64,
        threads: usize,
        reference_entry: &StructureEntry,
    ) -> Result<SceneRun<'a>> {
        let s = &scene.scene;
        let ctx = BuildContext::new(threads);
        let reference = reference_entry.build(s.mesh.clone(), &ctx)?.accel;
        let (points, rays): (Vec<Workload>, Vec<Workload>) =
            workloads.iter().partition(|w| w.is_point_query());
        let prepared = if rays.is_empty() {
            Vec::new()
        } else {
            ray_workloads(s, reference.as_ref(), &rays, counts.rays, seed, threads)?
        };
        let point_workloads = points
            .iter()
            .map(|&wl| point_workload(s, reference.as_ref(), wl, counts.points, seed, threads))
            .collect::<Result<_>>()?;
        Ok(SceneRun {
            scene,
            reference,
            reference_name: reference_entry.name.to_string(),
            workloads: prepared,
            point_workloads,
        })
    }

    pub(crate) fn record(&self, loaded: &LoadedScene) -> SceneRecord {
        let s = &loaded.scene;
        SceneRecord {
            name: s.name.clone(),
            source: serde_json::to_value(&s.source).unwrap_or_default(),
            triangles: triangle_counts(s),
            load_ms: loaded.load_ms,
            loader_notes: s.loader_notes.clone(),
            view: serde_json::to_value(s.view).unwrap_or_default(),
            workloads: self
                .workloads
                .iter()
                .map(|w| WorkloadRecord {
                    workload: w.workload.name().to_string(),
                    queries: w.rays.len(),
                    any_hit: w.workload.any_hit(),
                    point_query: false,
                    width: w.size.map(|s| s.0),
                    height: w.size.map(|s| s.1),
                })
                .chain(self.point_workloads.iter().map(|w| WorkloadRecord {
                    workload: w.workload.name().to_string(),
                    queries: w.points.len(),
                    any_hit: false,
                    point_query: true,
                    width: None,
                    height: None,
                }))
                .collect(),
        }
    }
}

/// The ray workloads of a scene: rays made by the one recipe ([`RayRecipe`]: secondary rays
/// start at the reference's primary hits) and the reference's answers.
fn ray_workloads(
    s: &Scene,
    reference: &dyn Accel,
    workloads: &[Workload],
    ray_count: usize,
    seed: u64,
    threads: usize,
) -> Result<Vec<PreparedWorkload>> {
    let trace = |r: &Ray| surface_hit(reference, r);
    let recipe = RayRecipe::new(s, ray_count, seed, &trace);
    let mut prepared = Vec::new();
    for &wl in workloads {
        let Some(rays) = recipe.rays(wl) else {
            bail!("{wl} is a closest-point workload, not a ray workload")
        };
        let size = (wl == Workload::Primary).then(|| recipe.image_size());
        ensure_traceable(wl, &rays)?;
        let reference_answers = reference_answers(reference, &rays, wl.any_hit(), threads)?;
        prepared.push(PreparedWorkload {
            workload: wl,
            rays,
            reference: reference_answers,
            size,
        });
    }
    Ok(prepared)
}

/// A closest-point workload of a scene: its query points (a function of the mesh, the count
/// and the seed only, so every thread count and run sees the same) and the reference's answers.
fn point_workload(
    s: &Scene,
    reference: &dyn Accel,
    workload: Workload,
    count: usize,
    seed: u64,
    threads: usize,
) -> Result<PreparedPoints> {
    let kind = workload
        .point_workload()
        .context("a ray workload among the point workloads")?;
    let points = kind.generate(&s.mesh, count, seed);
    let radius = kind.default_radius();
    ensure_queryable(workload, &points, radius)?;
    let mut answers = vec![None; points.len()];
    point_pass(reference, &points, radius, threads, &mut answers);
    Ok(PreparedPoints {
        workload,
        points,
        radius,
        reference: answers,
    })
}

/// Every generated query must be one Embree can take; a bad one is a generator bug, named here.
fn ensure_queryable(wl: Workload, points: &[Vec3], radius: f32) -> Result<()> {
    for (i, &p) in points.iter().enumerate() {
        if raybench_geom::query_radius_squared(p, radius).is_none() {
            bail!(
                "workload {} point {i} is not a valid query (bits {:08x?})",
                wl.name(),
                p.to_array().map(f32::to_bits)
            );
        }
    }
    Ok(())
}

fn surface_hit(accel: &dyn Accel, ray: &Ray) -> Option<SurfaceHit> {
    accel.intersect(ray).map(|h| SurfaceHit {
        prim: h.prim,
        u: h.u,
        v: h.v,
    })
}

pub(crate) fn triangle_counts(s: &Scene) -> TriangleCounts {
    let traced = s.mesh.len() as u64;
    TriangleCounts {
        loaded: traced + s.removed.total(),
        removed: s.removed.total(),
        removed_by_reason: s.removed,
        traced,
    }
}

/// Every generated ray must be traceable by Embree; a bad one is a generator bug, named here.
fn ensure_traceable(wl: Workload, rays: &[Ray]) -> Result<()> {
    for (i, r) in rays.iter().enumerate() {
        if let Err(e) = r.check() {
            bail!(
                "workload {} ray {i} is invalid: {e} (bits {:08x?})",
                wl.name(),
                r.to_bits()
            );
        }
    }
    Ok(())
}

/// A workload's rays prepared for `accel`'s timed path, as coherent when the workload's are.
pub(crate) fn prepare_workload(
    accel: &dyn Accel,
    workload: Workload,
    rays: &[Ray],
) -> Result<PreparedRays, raybench_geom::RayError> {
    if workload.coherent() {
        accel.prepare_coherent_rays(rays)
    } else {
        accel.prepare_rays(rays)
    }
}

/// A reference's answers on its timed path (the thread count changes only the speed).
pub(crate) fn reference_answers(
    reference: &dyn Accel,
    rays: &[Ray],
    any_hit: bool,
    threads: usize,
) -> Result<Answers> {
    let prepared = reference
        .prepare_rays(rays)
        .map_err(|e| anyhow::anyhow!("{} rejected a ray: {e}", reference.name()))?;
    let mut answers = Answers::new(any_hit, rays.len());
    trace_pass(reference, rays, &prepared, threads, &mut answers);
    Ok(answers)
}
