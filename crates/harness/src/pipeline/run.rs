//! `raybench run`: load scenes, generate one ray set (or query point set) per workload from the
//! reference, build and time every structure, count, check every answer, and assemble the report.
//!
//! Ray workloads and closest-point workloads share the pipeline (build once, warm-up + median
//! of timed passes, an untimed counted pass, every answer checked against the reference) but
//! not the code that handles rays: `SceneRun` keeps the two kinds in separate lists.

use super::check::{
    Sides, check_answers, check_points, counted_path_differences, counted_point_differences,
};
use super::dump::{DumpDir, points_not_dumped};
use super::images::{PixelInput, PrimaryImage, shade};
use super::measure::{Answers, count_pass, count_point_pass, warm_up_points, warm_up_trace};
use super::picture::{self, ScenePicturePass};
use super::rounds::{self, Job, Pending};
use super::scenes::for_each_scene;
use super::workers::{Log, Progress, Workers, catch_panic};
use super::workloads::{PreparedPoints, QueryCounts, SceneRun, prepare_workload, triangle_counts};
use crate::interrupt;
use crate::registry::{BuildContext, Registry, StructureEntry};
use crate::report::Header;
use crate::report::interval::{Interval, median_with_interval, paired_ratios};
use crate::report::run::*;
use anyhow::Result;
use raybench_accel::Accel;
use raybench_accel::classify::Tolerance;
use raybench_scenes::{SceneRequest, WhittedParams, Workload};
use std::path::PathBuf;
use std::time::Instant;

/// Everything `raybench run` needs; the CLI fills it from flags and the suite manifest.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub suite: Option<String>,
    pub structures: Vec<String>,
    /// Skip a structure on scenes above its suite triangle limit (brute force): when the
    /// structures come from a suite's list or the default of every structure, not when the
    /// user named them.
    pub suite_limits: bool,
    pub workloads: Vec<Workload>,
    pub rays: usize,
    /// Query points per closest-point workload.
    pub points: usize,
    pub threads: usize,
    pub reference: String,
    pub seed: u64,
    pub build_runs: usize,
    pub trace_runs: usize,
    /// Extra timing rounds per scene while a structure's ratios are imprecise, up to this
    /// much of its passes' time (see `rounds.rs`); `None` for the fixed rounds only.
    pub time_budget: Option<std::time::Duration>,
    pub ftz_daz: bool,
    pub progress: bool,
    /// Keep per-pixel pictures of the primary workload in the report (see `images`); off for
    /// baselines, which are compared, not looked at.
    pub images: bool,
    /// Write every structure's answers to every workload here (see [`super::dump`]).
    pub dump_hits: Option<PathBuf>,
    /// The run's output directory: with `images`, full-resolution pictures of the primary view
    /// go to its `images/` (see [`super::picture`]). `None` keeps only the small planes.
    pub picture_dir: Option<PathBuf>,
    /// Width of those pictures in pixels ([`picture::MIN_WIDTH`] to [`picture::MAX_WIDTH`]);
    /// the height is three quarters of it.
    pub picture_width: u32,
}

impl RunOptions {
    /// Where the full-resolution pictures go, if they are drawn: pictures on, a directory
    /// given, and the primary workload among the workloads (the pictures show its view).
    fn picture_dir(&self) -> Option<&std::path::Path> {
        let primary = self.workloads.contains(&Workload::Primary);
        self.picture_dir
            .as_deref()
            .filter(|_| self.images && primary)
    }
}

/// [`run_with`] the built-in structures.
pub fn run(opts: &RunOptions, scenes: &[SceneRequest]) -> Result<Report> {
    run_with(&Registry::builtin(), opts, scenes)
}

/// Runs everything, looking structure names up in `registry`, and returns the report (not yet
/// written). With `dump_hits`, every structure's answers are written there as they are
/// measured (see [`super::dump`]).
pub fn run_with(registry: &Registry, opts: &RunOptions, scenes: &[SceneRequest]) -> Result<Report> {
    anyhow::ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    anyhow::ensure!(opts.points >= 1, "--points must be at least 1 (got 0)");
    anyhow::ensure!(
        (picture::MIN_WIDTH..=picture::MAX_WIDTH).contains(&opts.picture_width),
        "--picture-width must be {} to {} pixels (got {})",
        picture::MIN_WIDTH,
        picture::MAX_WIDTH,
        opts.picture_width
    );
    let mut structures = registry.select(&opts.structures)?;
    let reference_entry = registry.find(&opts.reference)?;
    let mut log = Log::default();
    if !structures.iter().any(|e| e.name == reference_entry.name) {
        log.notes.push(format!(
            "reference {} added to the measured structures so ratios can be computed",
            opts.reference
        ));
        structures.insert(0, reference_entry.clone());
    }
    let mut dump = opts.dump_hits.as_deref().map(DumpDir::create).transpose()?;
    log.notes
        .extend(points_not_dumped(dump.is_some(), &opts.workloads));
    let workers = Workers::start(opts.threads, opts.ftz_daz)?;
    let tol = Tolerance::default();
    let progress = Progress::new(
        opts.progress,
        (scenes.len() * (structures.len() + 2)) as u64,
    );
    let mut report = Report {
        header: Header::new(SCHEMA_VERSION, workers.environment.clone()),
        run: RunSettings {
            suite: opts.suite.clone(),
            seed: opts.seed,
            rays: opts.rays,
            points: opts.points,
            threads: opts.threads,
            reference: opts.reference.clone(),
            build_runs: opts.build_runs,
            trace_runs: opts.trace_runs,
            time_budget_s: opts.time_budget.map(|d| d.as_secs_f64()),
            tolerance: tol,
            structures: structures.iter().map(|e| e.name.to_string()).collect(),
            workloads: opts
                .workloads
                .iter()
                .map(|w| w.name().to_string())
                .collect(),
            whitted: WhittedParams::default(),
            images: opts.images,
            suite_limits: opts.suite_limits,
            ftz_daz: opts.ftz_daz,
            picture_width: opts.picture_width,
        },
        scenes: Vec::new(),
        results: Vec::new(),
        notes: Vec::new(),
        errors: Vec::new(),
        claims: Vec::new(),
        pictures: Vec::new(),
        incomplete: None,
    };
    // The request being measured (or next) when a graceful stop was asked for.
    let mut stopped_at: Option<usize> = None;
    let mut picture_names = std::collections::HashSet::new();
    let picture_pool = opts
        .picture_dir()
        .map(|_| picture::pool(opts.ftz_daz))
        .transpose()?;

    workers.pool.install(|| {
        for_each_scene(scenes, opts.seed, &progress, &mut log, |request, scene, log| {
            let index = scenes.iter().position(|r| std::ptr::eq(r, request)).unwrap_or(0);
            if stopped_at.is_some() {
                return;
            }
            if interrupt::requested() {
                stopped_at = Some(index);
                return;
            }
            let name = &scene.scene.name;
            progress.step(format!("{name}: generating workloads with {}", reference_entry.name));
            let prepared = catch_panic(|| {
                let counts = QueryCounts { rays: opts.rays, points: opts.points };
                SceneRun::prepare(scene, &opts.workloads, counts, opts.seed, opts.threads, &reference_entry)
            });
            let sr = match prepared {
                Ok(sr) => sr,
                Err(e) => return log.errors.push(format!("scene {name}: {e:#}")),
            };
            report.scenes.push(sr.record(scene));
            let mut pictures = opts.picture_dir().zip(picture_pool.as_ref()).and_then(|(dir, pool)| {
                let base = unique_base(&mut picture_names, name);
                let started = catch_panic(|| pool.install(|| {
                    let threads = pool.current_num_threads();
                    ScenePicturePass::start(dir, base, opts.picture_width, &scene.scene, sr.reference.as_ref(), &sr.reference_name, threads)
                }));
                started.map(|pass| (pass, pool)).map_err(|e| log.errors.push(format!("pictures of {name}: {e:#}"))).ok()
            });
            let mut pending = Vec::new();
            for entry in &structures {
                if interrupt::requested() {
                    break;
                }
                if let Some(limit) = entry.suite_triangle_limit.filter(|&l| opts.suite_limits && scene.scene.mesh.len() > l) {
                    log.notes.push(format!(
                        "{} skipped on {name} ({} triangles > its suite limit {limit}); name it with --structures to run it",
                        entry.name,
                        scene.scene.mesh.len()
                    ));
                    progress.step(format!("{name}: {} skipped", entry.name));
                    continue;
                }
                progress.step(format!("{name}: {}", entry.name));
                let p = match catch_panic(|| sr.prepare_entry(entry, opts, &tol, dump.as_mut())) {
                    Ok(p) => p,
                    Err(e) => {
                        log.errors.push(format!("{} on {name}: {e:#}", entry.name));
                        continue;
                    }
                };
                if let (Some((pics, pool)), Some(accel)) = (pictures.as_mut(), p.warm_up()) {
                    let mesh = &scene.scene.mesh;
                    let added = catch_panic(|| pool.install(|| pics.add(entry.name, accel, mesh, sr.reference.as_ref(), &tol)));
                    if let Err(e) = added {
                        log.errors.push(format!("pictures of {} on {name}: {e:#}", entry.name));
                    }
                }
                pending.push(p);
            }
            progress.step(format!("{name}: timing {} structures in {} interleaved rounds", pending.len(), rounds::rounds(opts)));
            // Stopped before every structure was timed: the scene is left out whole (a resumed
            // run measures it again), so no result of it mixes finished and unfinished work.
            let timed = (!interrupt::requested()).then(|| rounds::time_in_rounds(pending, &sr, opts)).flatten();
            let Some(timed) = timed else {
                stopped_at = Some(index);
                report.scenes.pop();
                log.notes.push(format!("{name}: interrupted while measured; left for --resume"));
                return;
            };
            for (structure, timed) in timed {
                match timed {
                    Ok((r, note)) => {
                        report.results.push(r);
                        log.notes.extend(note);
                    }
                    Err(e) => log.errors.push(format!("{structure} on {name}: {e:#}")),
                }
            }
            if let Some((p, pool)) = pictures {
                match catch_panic(|| pool.install(|| p.finish())) {
                    Ok(set) => report.pictures.push(set),
                    Err(e) => log.errors.push(format!("pictures of {name}: {e:#}")),
                }
            }
        });
    });
    progress.finish();
    if let Some(i) = stopped_at {
        report.incomplete = Some(Incomplete {
            reason: "interrupted (SIGINT or SIGTERM)".into(),
            remaining: scenes[i..].iter().map(RequestRecord::from).collect(),
        });
    }
    report.notes.append(&mut log.notes);
    report.errors.append(&mut log.errors);
    if let Some(dump) = dump {
        dump.finish()?;
    }
    fill_ratios(&mut report);
    report.claims = crate::report::claims::evaluate(&report)
        .into_iter()
        .map(|e| e.claim)
        .collect();
    Ok(report)
}

impl SceneRun<'_> {
    /// Builds `entry` once (the warm-up build, which also creates shared state such as
    /// Embree's device) and runs everything but the timing: a warm-up pass per workload whose
    /// answers are checked and dumped, and the counted pass. The timed builds and passes
    /// follow in rounds (`rounds.rs`).
    fn prepare_entry<'e>(
        &self,
        entry: &'e StructureEntry,
        opts: &RunOptions,
        tol: &Tolerance,
        mut dump: Option<&mut DumpDir>,
    ) -> Result<Pending<'e>> {
        let s = &self.scene.scene;
        let ctx = BuildContext::new(opts.threads);
        let start = Instant::now();
        let built = entry.build(s.mesh.clone(), &ctx)?;
        let warm_up_ms = start.elapsed().as_secs_f64() * 1e3;
        let accel = built.accel.as_ref();
        let mut jobs = Vec::new();
        let mut workloads = Vec::new();
        let mut primary_image = None;
        for (wi, wl) in self
            .workloads
            .iter()
            .enumerate()
            .filter(|(_, w)| !w.rays.is_empty())
        {
            let any_hit = wl.workload.any_hit();
            let prepared = prepare_workload(accel, wl.workload, &wl.rays).map_err(|e| {
                anyhow::anyhow!(
                    "{} rays rejected by {}: {e}",
                    wl.workload.name(),
                    entry.name
                )
            })?;
            let (answers, warm_up) =
                warm_up_trace(accel, &wl.rays, &prepared, any_hit, opts.threads);
            let (counted, counters, work) = count_pass(accel, &wl.rays, any_hit);
            let sides = Sides {
                ours: accel,
                reference: self.reference.as_ref(),
                reference_name: &self.reference_name,
            };
            let (mut agreement, levels) =
                check_answers(&s.mesh, &wl.rays, &answers, &wl.reference, &sides, tol);
            let paths = counted_path_differences(&s.mesh, &wl.rays, &answers, &counted, tol, accel);
            agreement.counted_path_differs = paths.differs;
            agreement.counted_path_explained = paths.explained;
            if let Some(d) = dump.as_deref_mut() {
                d.write(
                    &s.name,
                    entry.name,
                    wl.workload.name(),
                    &wl.rays,
                    None,
                    &answers,
                )?;
            }
            let has_counters = accel.has_counters();
            if let (true, Some((w, h)), Answers::Closest(hits)) = (opts.images, wl.size, &answers) {
                let pixels: Vec<PixelInput> = (0..wl.rays.len())
                    .map(|i| PixelInput {
                        cost: has_counters.then_some(work[i]),
                        shade: shade(&s.mesh, &wl.rays[i], hits[i].as_ref()),
                        disagree: levels[i],
                    })
                    .collect();
                primary_image = Some(PrimaryImage::new(w, h, &pixels));
            }
            let scratch = Answers::new(any_hit, wl.rays.len());
            jobs.push(Job::rays(
                workloads.len(),
                wi,
                prepared,
                scratch,
                warm_up,
                opts.trace_runs,
            ));
            workloads.push(WorkloadResult {
                workload: wl.workload.name().to_string(),
                queries: wl.rays.len(),
                any_hit,
                point_query: false,
                mqueries_per_s: Throughput::from_samples(Vec::new()),
                speedup_vs_reference: None,
                speedup_interval: None,
                counters_per_query: has_counters
                    .then(|| CountersPerQuery::from_total(&counters, wl.rays.len())),
                counters_total: has_counters.then_some(counters),
                agreement,
            });
        }
        let mut not_offered = Vec::new();
        for (wi, pw) in self
            .point_workloads
            .iter()
            .enumerate()
            .filter(|(_, w)| !w.points.is_empty())
        {
            if accel.offers_closest_point() {
                let (result, warm_up) = self.check_points(accel, pw, opts);
                let queries = pw.points.len();
                jobs.push(Job::points(
                    workloads.len(),
                    wi,
                    queries,
                    warm_up,
                    opts.trace_runs,
                ));
                workloads.push(result);
            } else {
                not_offered.push(pw.workload.name().to_string());
            }
        }
        let memory = accel.memory();
        let entry_of = entry;
        let result = ResultEntry {
            scene: s.name.clone(),
            triangles: triangle_counts(s),
            structure: entry.name.to_string(),
            params: built.params.clone(),
            build: Timing::from_samples(Vec::new()),
            build_ratio_to_reference: None,
            build_ratio_interval: None,
            memory_bytes: memory.total(),
            memory,
            build_stats: accel.build_stats(),
            workloads,
            not_offered,
            primary_image,
        };
        let mut pending = Pending::new(entry_of, built, warm_up_ms, result);
        pending.jobs = jobs;
        Ok(pending)
    }

    /// One structure on one closest-point workload, like rays: the warm-up pass on the run's
    /// threads (returned with how long it took), then the counted pass, then the check against
    /// the reference. Not dumped: `--dump-hits` covers ray workloads only.
    fn check_points(
        &self,
        accel: &dyn Accel,
        pw: &PreparedPoints,
        opts: &RunOptions,
    ) -> (WorkloadResult, std::time::Duration) {
        let (answers, warm_up) = warm_up_points(accel, &pw.points, pw.radius, opts.threads);
        let (counted, counters) = count_point_pass(accel, &pw.points, pw.radius);
        let mesh = &self.scene.scene.mesh;
        let mut agreement = check_points(
            mesh,
            &pw.points,
            pw.radius,
            &answers,
            &pw.reference,
            &self.reference_name,
        );
        agreement.counted_path_differs = counted_point_differences(&answers, &counted);
        let has_counters = accel.has_counters();
        let result = WorkloadResult {
            workload: pw.workload.name().to_string(),
            queries: pw.points.len(),
            any_hit: false,
            point_query: true,
            mqueries_per_s: Throughput::from_samples(Vec::new()),
            speedup_vs_reference: None,
            speedup_interval: None,
            counters_per_query: has_counters
                .then(|| CountersPerQuery::from_total(&counters, pw.points.len())),
            counters_total: has_counters.then_some(counters),
            agreement,
        };
        (result, warm_up)
    }
}

/// A file-name base for a scene's pictures, unique in the run (`a:b` and `a-b` share a slug).
fn unique_base(used: &mut std::collections::HashSet<String>, scene: &str) -> String {
    let base = crate::output::render::names::slug(scene);
    let mut candidate = base.clone();
    let mut k = 2;
    while !used.insert(candidate.clone()) {
        candidate = format!("{base}-{k}");
        k += 1;
    }
    candidate
}

/// Ratios to the reference measured in the same run: build time and throughput per workload,
/// each the median of the per-round ratios with its interval (see `report/interval.rs`).
fn fill_ratios(report: &mut Report) {
    let reference = report.run.reference.clone();
    let refs: Vec<ResultEntry> = report
        .results
        .iter()
        .filter(|r| r.structure == reference)
        .cloned()
        .collect();
    for r in &mut report.results {
        let Some(base) = refs.iter().find(|b| b.scene == r.scene) else {
            continue;
        };
        (r.build_ratio_to_reference, r.build_ratio_interval) = ratio(
            (r.build.median_ms, &r.build.samples_ms),
            (base.build.median_ms, &base.build.samples_ms),
        );
        for w in &mut r.workloads {
            let Some(b) = base.workloads.iter().find(|b| b.workload == w.workload) else {
                continue;
            };
            let (ours, theirs) = (&w.mqueries_per_s, &b.mqueries_per_s);
            (w.speedup_vs_reference, w.speedup_interval) = ratio(
                (ours.median, &ours.samples),
                (theirs.median, &theirs.samples),
            );
        }
    }
}

/// `a / b` as the median of the per-round ratios with its interval when both sides have two
/// samples or more, else the ratio of the medians; `None` when `b` is not positive.
fn ratio(
    (a, a_samples): (f64, &[f64]),
    (b, b_samples): (f64, &[f64]),
) -> (Option<f64>, Option<Interval>) {
    if b <= 0.0 {
        return (None, None);
    }
    let paired = paired_ratios(a_samples, b_samples);
    if a_samples.len() < 2 || b_samples.len() < 2 {
        return (Some(a / b), None);
    }
    match median_with_interval(&paired) {
        Some((median, interval)) => (Some(median), interval),
        None => (Some(a / b), None),
    }
}
