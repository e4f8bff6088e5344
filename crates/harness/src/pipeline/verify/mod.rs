//! `raybench verify`: are the answers right? Every structure × scene × workload is checked
//! against three references — `embree-medium` (Embree's default, fast mode), `embree-robust`
//! (Embree's robust mode) and `bruteforce` (every triangle, Möller–Trumbore) — and every
//! disagreement goes through the f64 arbiter of `raybench_accel::classify`, which decides
//! between the explained classes (`tie`, `boundary`, `edge_ambiguous`) and `mismatch`.
//!
//! Nothing is timed. Each structure runs its timed path (the prepared batch path `run` times,
//! on the run's threads) and its counted path once each; the two must give identical answers.
//!
//! Brute force costs rays × triangles ray–triangle tests, so it is traced on a deterministic,
//! evenly spaced subsample of each workload: as many rays as [`BRUTE_FORCE_BUDGET`] tests allow
//! (every ray when that is affordable). This applies to the `bruteforce` reference and to
//! brute-force structures under test (`bruteforce`, `bruteforce-watertight`). The report
//! says how many rays were brute-force checked per scene and workload.
//!
//! The workloads are the ones `run` makes (secondary rays start at `embree-medium`'s hits).
//! Closest-point workloads (`points-near`, `points-volume`) are checked the same way, with the
//! point classes of `raybench_accel::classify_points` and the same brute-force budget (one
//! point–triangle test per triangle per query). `--dump-hits` covers ray workloads only.

mod references;
mod structure;

use super::dump::{DumpDir, points_not_dumped};
use super::scenes::{LoadedScene, for_each_scene};
use super::workers::{Log, Progress, Workers, catch_panic};
use crate::env::Environment;
use crate::output::agreement::agreement_sentence;
use crate::registry::{Registry, StructureEntry};
use crate::report::Header;
use crate::report::agreement::Agreement;
use crate::report::verify::{
    AgreementRow, SampledWorkload, VERIFY_SCHEMA_VERSION, VerifiedScene, VerifiedWorkload,
    VerifyReport, VerifySettings,
};
use anyhow::{Result, ensure};
use raybench_accel::classify::{Tolerance, VerdictCounts};
use raybench_scenes::{SceneRequest, Workload};
use references::SceneReferences;
use std::path::PathBuf;
use structure::Checker;

/// The references every structure is checked against, in the order tables list them.
pub const REFERENCES: [&str; 3] = ["embree-medium", "embree-robust", "bruteforce"];

/// Ray–triangle tests brute force may spend per scene × workload (per brute-force pass):
/// well under a tenth of a second of one core for `bruteforce` at the 2.8e8–3.8e8
/// Möller–Trumbore tests per second measured, a third of a second for `bruteforce-watertight`
/// at 6e7–9e7 (release build, `soup:triangles=10000` and `sphere:triangles=100000`, random
/// and camera rays, on the shared 2-core development machine, an AMD EPYC with AVX2). A scene
/// × workload costs five such passes (the reference, and the timed and counted paths of
/// `bruteforce` and `bruteforce-watertight`), so the adversarial suite verifies in about two
/// minutes on 2 cores, most of them the structures' own. At 5,000 rays every scene up to 4,000
/// triangles is checked on every ray; `--brute-force-budget 2e8` checks ten times as many.
pub const BRUTE_FORCE_BUDGET: u64 = 20_000_000;

/// Everything `raybench verify` needs; the CLI fills it from flags and the suite manifest.
#[derive(Clone, Debug)]
pub struct VerifyOptions {
    pub suite: Option<String>,
    /// Structures under test (each is checked against all of [`REFERENCES`]).
    pub structures: Vec<String>,
    pub workloads: Vec<Workload>,
    pub rays: usize,
    /// Query points per closest-point workload.
    pub points: usize,
    pub threads: usize,
    pub seed: u64,
    pub ftz_daz: bool,
    pub progress: bool,
    pub brute_force_budget: u64,
    pub dump_hits: Option<PathBuf>,
}

/// Evenly spaced ray indices, as many as `budget` ray–triangle tests allow over `triangles`
/// triangles (at least one; every ray when affordable). Spread over the whole list, so a
/// primary workload is sampled over the whole image, and deterministic.
pub fn brute_force_sample(rays: usize, triangles: usize, budget: u64) -> Vec<usize> {
    // No triangles, no tests: every ray is affordable.
    let affordable = budget
        .checked_div(triangles as u64)
        .unwrap_or(u64::MAX)
        .max(1);
    let k = (rays as u64).min(affordable) as usize;
    (0..k)
        .map(|i| (i as u128 * rays as u128 / k as u128) as usize)
        .collect()
}

/// [`verify_with`] the built-in structures.
pub fn verify(opts: &VerifyOptions, requests: &[SceneRequest]) -> Result<VerifyReport> {
    verify_with(&Registry::builtin(), opts, requests)
}

/// Checks every structure on every scene, looking names (the subjects' and the references')
/// up in `registry`; the report is not yet written.
pub fn verify_with(
    registry: &Registry,
    opts: &VerifyOptions,
    requests: &[SceneRequest],
) -> Result<VerifyReport> {
    ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    ensure!(
        opts.brute_force_budget >= 1,
        "the brute-force budget must be at least 1"
    );
    let subjects = registry.select(&opts.structures)?;
    let references = [
        registry.find(REFERENCES[0])?,
        registry.find(REFERENCES[1])?,
        registry.find(REFERENCES[2])?,
    ];
    let mut dump = opts.dump_hits.as_deref().map(DumpDir::create).transpose()?;
    let workers = Workers::start(opts.threads, opts.ftz_daz)?;
    let progress = Progress::new(
        opts.progress,
        (requests.len() * (subjects.len() + 1)) as u64,
    );
    let checker = Checker {
        opts,
        references: &references,
        tol: Tolerance::default(),
        progress: &progress,
    };
    let mut report = empty_report(opts, &subjects, workers.environment.clone(), checker.tol);
    let mut log = Log::default();
    log.notes
        .extend(points_not_dumped(dump.is_some(), &opts.workloads));
    workers.pool.install(|| {
        for_each_scene(
            requests,
            opts.seed,
            &progress,
            &mut log,
            |request, scene, log| {
                verify_scene(
                    &checker,
                    &subjects,
                    request,
                    scene,
                    log,
                    &mut report,
                    dump.as_mut(),
                );
            },
        );
    });
    progress.finish();
    report.notes.append(&mut log.notes);
    report.errors.append(&mut log.errors);
    report.totals = totals(&report.results);
    report.notes.extend(explained_path_notes(&report.results));
    if let Some(dump) = dump {
        dump.finish()?;
    }
    Ok(report)
}

fn empty_report(
    opts: &VerifyOptions,
    subjects: &[StructureEntry],
    environment: Environment,
    tolerance: Tolerance,
) -> VerifyReport {
    VerifyReport {
        header: Header::new(VERIFY_SCHEMA_VERSION, environment),
        settings: VerifySettings {
            suite: opts.suite.clone(),
            seed: opts.seed,
            rays: opts.rays,
            points: opts.points,
            threads: opts.threads,
            structures: subjects.iter().map(|e| e.name.to_string()).collect(),
            workloads: opts
                .workloads
                .iter()
                .map(|w| w.name().to_string())
                .collect(),
            references: REFERENCES.map(String::from).to_vec(),
            brute_force_budget: opts.brute_force_budget,
            tolerance,
        },
        scenes: Vec::new(),
        results: Vec::new(),
        totals: Vec::new(),
        notes: Vec::new(),
        errors: Vec::new(),
    }
}

fn verify_scene(
    checker: &Checker<'_>,
    subjects: &[StructureEntry],
    request: &SceneRequest,
    scene: &LoadedScene,
    log: &mut Log,
    report: &mut VerifyReport,
    mut dump: Option<&mut DumpDir>,
) {
    let name = &scene.scene.name;
    checker
        .progress
        .step(format!("{name}: workloads and reference answers"));
    let refs =
        match catch_panic(|| SceneReferences::prepare(checker.opts, checker.references, scene)) {
            Ok(r) => r,
            Err(e) => return log.errors.push(format!("scene {name}: {e:#}")),
        };
    report.scenes.push(VerifiedScene {
        name: name.clone(),
        spec: request.label(),
        triangles: refs.run.record(scene).triangles,
        workloads: refs
            .run
            .workloads
            .iter()
            .zip(&refs.workloads)
            .map(|(wl, wr)| SampledWorkload {
                workload: wl.workload.name().to_string(),
                queries: wl.rays.len(),
                brute_force_queries: wr.sample.len(),
            })
            .chain(point_samples(&refs))
            .collect(),
    });
    for entry in subjects {
        checker.progress.step(format!("{name}: {}", entry.name));
        match catch_panic(|| checker.check_structure(entry, &refs, dump.as_deref_mut())) {
            Ok(results) => report.results.extend(results),
            Err(e) => log.errors.push(format!("{} on {name}: {e:#}", entry.name)),
        }
    }
}

/// How much brute force checked of each closest-point workload.
fn point_samples<'r>(refs: &'r SceneReferences<'_>) -> impl Iterator<Item = SampledWorkload> + 'r {
    let prepared = refs.run.point_workloads.iter();
    prepared
        .zip(&refs.point_workloads)
        .map(|(pw, pr)| SampledWorkload {
            workload: pw.workload.name().to_string(),
            queries: pw.points.len(),
            brute_force_queries: pr.sample.len(),
        })
}

/// Sums every structure × reference over scenes and workloads, in subject order.
/// One note per structure whose timed and counted paths differ only in explained ways: said,
/// not failed. Embree's entries run two of Embree's own entry points (a batch call timed, a
/// single-ray call counted), so their differences are Embree disagreeing with itself.
fn explained_path_notes(results: &[VerifiedWorkload]) -> Vec<String> {
    let mut per_structure: Vec<(&str, u64)> = Vec::new();
    for r in results.iter().filter(|r| r.counted_path_explained > 0) {
        match per_structure.iter_mut().find(|(s, _)| *s == r.structure) {
            Some((_, n)) => *n += r.counted_path_explained,
            None => per_structure.push((&r.structure, r.counted_path_explained)),
        }
    }
    per_structure
        .into_iter()
        .map(|(structure, n)| {
            let whose = if structure.starts_with("embree") {
                "; both paths are Embree's own entry points (a batch call timed, a single-ray \
                 call counted), so this is Embree disagreeing with itself, not a fault of \
                 raybench's"
            } else {
                ""
            };
            format!(
                "{structure}: its timed and counted paths answer {n} rays differently, each one \
                 explained in f64 as for any reference (a tie, an edge-ambiguous ray, a \
                 boundary hit or t within tolerance){whose}"
            )
        })
        .collect()
}

fn totals(results: &[VerifiedWorkload]) -> Vec<AgreementRow> {
    let mut rows: Vec<AgreementRow> = Vec::new();
    for r in results {
        for v in &r.agreements {
            let i = match rows
                .iter()
                .position(|x| x.structure == r.structure && x.reference == v.reference)
            {
                Some(i) => i,
                None => {
                    rows.push(AgreementRow {
                        structure: r.structure.clone(),
                        reference: v.reference.clone(),
                        queries: 0,
                        counts: VerdictCounts::default(),
                        counted_path_differs: 0,
                        counted_path_explained: 0,
                        mismatch_rate_upper95: 0.0,
                        agreement: String::new(),
                    });
                    rows.len() - 1
                }
            };
            rows[i].counts += v.counts;
            rows[i].counted_path_differs += v.counted_path_differs;
            rows[i].counted_path_explained += v.counted_path_explained;
        }
    }
    for row in &mut rows {
        let v = Agreement::new(&row.reference, row.counts);
        row.queries = row.counts.total();
        row.mismatch_rate_upper95 = v.mismatch_rate_upper95;
        row.agreement = agreement_sentence(&row.counts);
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_subsample_fits_the_budget_and_spans_the_list() {
        assert_eq!(
            brute_force_sample(10, 5, 1_000),
            (0..10).collect::<Vec<_>>()
        );
        let s = brute_force_sample(1_000, 100, 10_000);
        assert_eq!(s.len(), 100);
        assert_eq!((s[0], s[1], s[99]), (0, 10, 990));
        assert_eq!(
            brute_force_sample(7, 1_000_000, 10),
            [0],
            "at least one ray"
        );
        assert_eq!(brute_force_sample(0, 10, 10), Vec::<usize>::new());
        assert_eq!(
            brute_force_sample(4, 0, 1).len(),
            4,
            "an empty scene costs nothing"
        );
    }
}
