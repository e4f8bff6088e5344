//! One structure under test on one scene: built once, its timed and counted paths traced on
//! every workload and checked against each other and against every reference.

use super::references::{
    PointReferences, SceneReferences, WorkloadReferences, gather, maybe_gather,
};
use super::{REFERENCES, VerifyOptions};
use crate::pipeline::check::{
    PathDifferences, Sides, check_answers, check_points, counted_path_differences,
    counted_point_differences,
};
use crate::pipeline::dump::DumpDir;
use crate::pipeline::measure::{Answers, count_pass, count_point_pass, point_pass, trace_pass};
use crate::pipeline::workers::Progress;
use crate::pipeline::workloads::{PreparedPoints, PreparedWorkload, prepare_workload};
use crate::registry::{BuildContext, StructureEntry};
use crate::report::agreement::Agreement;
use crate::report::verify::VerifiedWorkload;
use anyhow::Result;
use raybench_accel::classify::Tolerance;
use raybench_accel::{Accel, PointHit};
use raybench_geom::{Ray, TriangleMesh};
use raybench_scenes::Workload;
use std::borrow::Cow;

/// Settings shared by every check of a run.
pub(super) struct Checker<'a> {
    pub opts: &'a VerifyOptions,
    /// The entries named by [`super::REFERENCES`], in that order.
    pub references: &'a [StructureEntry; 3],
    pub tol: Tolerance,
    pub progress: &'a Progress,
}

impl Checker<'_> {
    fn ctx(&self) -> BuildContext {
        BuildContext::new(self.opts.threads)
    }

    /// Builds one structure and checks it on every workload of the scene.
    pub(super) fn check_structure(
        &self,
        entry: &StructureEntry,
        refs: &SceneReferences<'_>,
        dump: Option<&mut DumpDir>,
    ) -> Result<Vec<VerifiedWorkload>> {
        let mesh = &refs.run.scene.scene.mesh;
        let built = entry.build(mesh.clone(), &self.ctx())?;
        let mut dump = dump;
        let mut out = Vec::new();
        for (wl, wr) in refs.run.workloads.iter().zip(&refs.workloads) {
            if wl.rays.is_empty() {
                continue;
            }
            let subject = Subject {
                name: entry.name,
                accel: built.accel.as_ref(),
                sampled: entry.is_exhaustive() && wr.sample.len() < wl.rays.len(),
            };
            let (result, traced) = self.check_ray_workload(&subject, refs, wl, wr)?;
            if let Some(d) = dump.as_deref_mut() {
                let indices = subject.sampled.then_some(&wr.sample[..]);
                let rays = maybe_gather(&wl.rays, indices);
                d.write(
                    &result.scene,
                    entry.name,
                    &result.workload,
                    &rays,
                    indices,
                    &traced,
                )?;
            }
            out.push(result);
        }
        for (pw, pr) in refs.run.point_workloads.iter().zip(&refs.point_workloads) {
            if !pw.points.is_empty() {
                let sampled = entry.is_exhaustive() && pr.sample.len() < pw.points.len();
                let subject = Subject {
                    name: entry.name,
                    accel: built.accel.as_ref(),
                    sampled,
                };
                out.push(self.check_point_workload(&subject, refs, pw, pr));
            }
        }
        Ok(out)
    }

    /// The subject's timed and counted closest points, compared with each other and with every
    /// reference (on the brute-force subsample where either side answered only that).
    fn check_point_workload(
        &self,
        subject: &Subject<'_>,
        refs: &SceneReferences<'_>,
        pw: &PreparedPoints,
        pr: &PointReferences,
    ) -> VerifiedWorkload {
        let own_indices = subject.sampled.then_some(&pr.sample[..]);
        let points = maybe_gather(&pw.points, own_indices);
        let mut timed = vec![None; points.len()];
        point_pass(
            subject.accel,
            &points,
            pw.radius,
            self.opts.threads,
            &mut timed,
        );
        let (counted, _) = count_point_pass(subject.accel, &points, pw.radius);
        let differs = counted_point_differences(&timed, &counted);
        let mesh = &refs.run.scene.scene.mesh;
        let classify_against = |name: &str, theirs: &[Option<PointHit>], theirs_on_sample: bool| {
            let on_sample = subject.sampled || theirs_on_sample;
            let narrow = |answers: &[Option<PointHit>], already: bool| {
                if on_sample && !already {
                    gather(answers, &pr.sample)
                } else {
                    answers.to_vec()
                }
            };
            let ours = narrow(&timed, subject.sampled);
            let theirs = narrow(theirs, theirs_on_sample);
            let queried = maybe_gather(&pw.points, on_sample.then_some(&pr.sample[..]));
            let mut v = check_points(mesh, &queried, pw.radius, &ours, &theirs, name);
            if on_sample {
                v.first_point_mismatches
                    .iter_mut()
                    .for_each(|d| d.index = pr.sample[d.index]);
            }
            v.counted_path_differs = differs;
            v
        };
        VerifiedWorkload {
            scene: refs.run.scene.scene.name.clone(),
            structure: subject.name.to_string(),
            workload: pw.workload.name().to_string(),
            any_hit: false,
            queries: points.len(),
            subsampled: subject.sampled,
            counted_path_differs: differs,
            counted_path_explained: 0,
            agreements: vec![
                classify_against(REFERENCES[0], &pw.reference, false),
                classify_against(REFERENCES[1], &pr.robust, false),
                classify_against(REFERENCES[2], &pr.brute, true),
            ],
        }
    }

    /// The subject's timed and counted answers, compared with each other and with every
    /// reference. Also returns the timed answers (for the dump).
    fn check_ray_workload(
        &self,
        subject: &Subject<'_>,
        refs: &SceneReferences<'_>,
        wl: &PreparedWorkload,
        wr: &WorkloadReferences,
    ) -> Result<(VerifiedWorkload, Answers)> {
        let any_hit = wl.workload.any_hit();
        let own_indices = subject.sampled.then_some(&wr.sample[..]);
        let rays = maybe_gather(&wl.rays, own_indices);
        let (timed, counted) = trace_both(
            subject.accel,
            wl.workload,
            &rays,
            any_hit,
            self.opts.threads,
        )?;
        let mesh = &refs.run.scene.scene.mesh;
        let paths =
            counted_path_differences(mesh, &rays, &timed, &counted, &self.tol, subject.accel);
        let differs = paths.differs;
        let classify_against =
            |reference: (&str, &dyn Accel), theirs: &Answers, on_sample: bool| {
                // `on_sample`: the reference answered the subsample only; the subject's answers
                // are narrowed to it unless they already are.
                let narrow = on_sample && !subject.sampled && wr.sample.len() < wl.rays.len();
                let indices = if narrow {
                    Some(&wr.sample[..])
                } else {
                    own_indices
                };
                let (rays, ours) = if narrow {
                    (
                        Cow::Owned(gather(&rays, &wr.sample)),
                        Cow::Owned(timed.gather(&wr.sample)),
                    )
                } else {
                    (Cow::Borrowed(&rays[..]), Cow::Borrowed(&timed))
                };
                let theirs = match (own_indices, on_sample) {
                    (Some(idx), false) => Cow::Owned(theirs.gather(idx)),
                    _ => Cow::Borrowed(theirs),
                };
                let sides = Sides {
                    ours: subject.accel,
                    reference: reference.1,
                    reference_name: reference.0,
                };
                check_against(
                    mesh, &rays, &ours, &theirs, &sides, &self.tol, indices, paths,
                )
            };
        let agreements = vec![
            classify_against(
                (REFERENCES[0], refs.run.reference.as_ref()),
                &wl.reference,
                false,
            ),
            classify_against((REFERENCES[1], refs.robust.as_ref()), &wr.robust, false),
            classify_against((REFERENCES[2], refs.brute.as_ref()), &wr.brute, true),
        ];
        let result = VerifiedWorkload {
            scene: refs.run.scene.scene.name.clone(),
            structure: subject.name.to_string(),
            workload: wl.workload.name().to_string(),
            any_hit,
            queries: rays.len(),
            subsampled: subject.sampled,
            counted_path_differs: differs,
            counted_path_explained: paths.explained,
            agreements,
        };
        Ok((result, timed))
    }
}

/// A structure under test on one scene.
struct Subject<'a> {
    name: &'a str,
    accel: &'a dyn Accel,
    /// Traced on the brute-force subsample only.
    sampled: bool,
}

/// Checks `ours` against `theirs` on `rays`; disputed rays get their index in the full
/// workload (`indices[k]` for the k-th of a subsample).
#[allow(clippy::too_many_arguments)]
fn check_against(
    mesh: &TriangleMesh,
    rays: &[Ray],
    ours: &Answers,
    theirs: &Answers,
    sides: &Sides<'_>,
    tol: &Tolerance,
    indices: Option<&[usize]>,
    paths: PathDifferences,
) -> Agreement {
    let (mut v, _levels) = check_answers(mesh, rays, ours, theirs, sides, tol);
    if let Some(idx) = indices {
        for d in v.first_mismatches.iter_mut().chain(&mut v.first_ambiguous) {
            d.index = idx[d.index];
        }
    }
    v.counted_path_differs = paths.differs;
    v.counted_path_explained = paths.explained;
    v
}

/// The timed path (prepared batch, the run's threads) and the counted path, once each.
fn trace_both(
    accel: &dyn Accel,
    workload: Workload,
    rays: &[Ray],
    any_hit: bool,
    threads: usize,
) -> Result<(Answers, Answers)> {
    let prepared = prepare_workload(accel, workload, rays)
        .map_err(|e| anyhow::anyhow!("{} rejected a ray: {e}", accel.name()))?;
    let mut timed = Answers::new(any_hit, rays.len());
    trace_pass(accel, rays, &prepared, threads, &mut timed);
    let (counted, _, _) = count_pass(accel, rays, any_hit);
    Ok((timed, counted))
}
