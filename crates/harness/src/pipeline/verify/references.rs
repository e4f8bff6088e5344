//! What every structure of one scene is checked against: the workloads and `embree-medium`'s
//! answers (as `run` makes them), `embree-robust` on every query, and `bruteforce` on its
//! budgeted subsample.

use super::{VerifyOptions, brute_force_sample};
use crate::pipeline::measure::{Answers, point_pass};
use crate::pipeline::scenes::LoadedScene;
use crate::pipeline::workloads::{QueryCounts, SceneRun, reference_answers};
use crate::registry::{BuildContext, StructureEntry};
use anyhow::Result;
use raybench_accel::{Accel, PointHit};
use std::borrow::Cow;

/// What every structure of one scene is checked against.
pub(super) struct SceneReferences<'a> {
    /// The workloads and `embree-medium`'s answers.
    pub run: SceneRun<'a>,
    pub robust: Box<dyn Accel>,
    pub brute: Box<dyn Accel>,
    /// Parallel to `run.workloads`.
    pub workloads: Vec<WorkloadReferences>,
    /// Parallel to `run.point_workloads`.
    pub point_workloads: Vec<PointReferences>,
}

pub(super) struct PointReferences {
    /// `embree-robust` on every point.
    pub robust: Vec<Option<PointHit>>,
    /// The brute-force subsample (every point when affordable), and `bruteforce` on it.
    pub sample: Vec<usize>,
    pub brute: Vec<Option<PointHit>>,
}

pub(super) struct WorkloadReferences {
    /// `embree-robust` on every ray.
    pub robust: Answers,
    /// The brute-force subsample (every ray when affordable), and `bruteforce` on it.
    pub sample: Vec<usize>,
    pub brute: Answers,
}

impl<'a> SceneReferences<'a> {
    /// Builds the three references (`entries`, the structures named by [`super::REFERENCES`]) and
    /// answers every workload with each (brute force on its budgeted subsample only).
    pub(super) fn prepare(
        o: &VerifyOptions,
        entries: &[StructureEntry; 3],
        scene: &'a LoadedScene,
    ) -> Result<SceneReferences<'a>> {
        let ctx = BuildContext::new(o.threads);
        let [medium, robust, brute] = entries;
        let counts = QueryCounts {
            rays: o.rays,
            points: o.points,
        };
        let run = SceneRun::prepare(scene, &o.workloads, counts, o.seed, o.threads, medium)?;
        let mesh = &scene.scene.mesh;
        let robust = robust.build(mesh.clone(), &ctx)?.accel;
        let brute = brute.build(mesh.clone(), &ctx)?.accel;
        let mut workloads = Vec::new();
        for wl in &run.workloads {
            let any_hit = wl.workload.any_hit();
            let sample = brute_force_sample(wl.rays.len(), mesh.len(), o.brute_force_budget);
            let sampled_rays = gather(&wl.rays, &sample);
            workloads.push(WorkloadReferences {
                robust: reference_answers(robust.as_ref(), &wl.rays, any_hit, o.threads)?,
                brute: reference_answers(brute.as_ref(), &sampled_rays, any_hit, o.threads)?,
                sample,
            });
        }
        let point_workloads = run
            .point_workloads
            .iter()
            .map(|pw| {
                let sample = brute_force_sample(pw.points.len(), mesh.len(), o.brute_force_budget);
                PointReferences {
                    robust: answer_points(robust.as_ref(), &pw.points, pw.radius, o.threads),
                    brute: answer_points(
                        brute.as_ref(),
                        &gather(&pw.points, &sample),
                        pw.radius,
                        o.threads,
                    ),
                    sample,
                }
            })
            .collect();
        Ok(SceneReferences {
            run,
            robust,
            brute,
            workloads,
            point_workloads,
        })
    }
}

pub(super) fn gather<T: Copy>(items: &[T], indices: &[usize]) -> Vec<T> {
    indices.iter().map(|&i| items[i]).collect()
}

pub(super) fn maybe_gather<'a, T: Copy>(items: &'a [T], indices: Option<&[usize]>) -> Cow<'a, [T]> {
    match indices {
        Some(idx) => Cow::Owned(gather(items, idx)),
        None => Cow::Borrowed(items),
    }
}

/// A reference's closest points on its timed path (the thread count changes only the speed).
fn answer_points(
    reference: &dyn Accel,
    points: &[raybench_geom::Vec3],
    radius: f32,
    threads: usize,
) -> Vec<Option<PointHit>> {
    let mut answers = vec![None; points.len()];
    point_pass(reference, points, radius, threads, &mut answers);
    answers
}
