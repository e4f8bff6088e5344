//! `raybench run`: load scenes, generate one ray set (or query point set) per workload from the
//! reference, build and time every structure, count, validate, and assemble the report.
//!
//! Ray workloads and closest-point workloads share the pipeline (build once, warm-up + median
//! of timed passes, an untimed counted pass, validation against the reference) but not the code
//! that handles rays: [`SceneRun`] keeps the two kinds in separate lists.

use crate::dump::DumpDir;
use crate::env::Environment;
use crate::images::{PixelInput, PrimaryImage, shade};
use crate::measure::{
    Answers, count_pass, count_point_pass, point_pass, time_builds, time_point_queries, time_traces,
};
use crate::registry::{self, BuildContext, StructureEntry};
use crate::report::*;
use crate::validate::{
    Sides, count_differences, count_point_differences, validate, validate_points,
};
use anyhow::{Context, Result, bail};
use raybench_accel::classify::Tolerance;
use raybench_accel::{Accel, PointHit, PreparedRays};
use raybench_embree::{Device, EmbreeParams, fpu};
use raybench_geom::{Ray, Vec3};
use raybench_scenes::{RayRecipe, Scene, SurfaceHit, WhittedParams, Workload};
use std::path::PathBuf;
use std::time::Instant;

/// Everything `raybench run` needs; the CLI fills it from flags and the suite manifest.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub suite: Option<String>,
    /// Scene specs (`sphere`, `soup:triangles=5000`) or `.obj` paths.
    pub scenes: Vec<String>,
    pub structures: Vec<String>,
    pub workloads: Vec<Workload>,
    pub rays: usize,
    /// Query points per closest-point workload.
    pub points: usize,
    pub threads: usize,
    pub reference: String,
    pub seed: u64,
    pub build_runs: usize,
    pub trace_runs: usize,
    pub ftz_daz: bool,
    pub progress: bool,
    /// Keep per-pixel pictures of the primary workload in the report (see `images`); off for
    /// baselines, which are compared, not looked at.
    pub images: bool,
    /// Write every structure's answers to every workload here (see [`crate::dump`]).
    pub dump_hits: Option<PathBuf>,
}

pub use raybench_scenes::SceneRequest;

/// `name`, or `name #2`, `name #3`, … if the run already has a scene of that name.
fn unique_name(name: String, used: &mut std::collections::HashSet<String>) -> String {
    let unique = (1..)
        .map(|i| {
            if i == 1 {
                name.clone()
            } else {
                format!("{name} #{i}")
            }
        })
        .find(|n| !used.contains(n))
        .expect("some suffix is free");
    used.insert(unique.clone());
    unique
}

/// Live progress on a terminal; one plain line per step on stderr otherwise (CI logs).
pub(crate) struct Progress {
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    pub(crate) fn new(enabled: bool, steps: u64) -> Progress {
        let bar = enabled.then(|| {
            let pb = indicatif::ProgressBar::new(steps);
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed} {msg}")
            {
                pb.set_style(style);
            }
            pb
        });
        Progress { bar }
    }

    /// Called between measurements only, never inside a timed region.
    pub(crate) fn step(&self, msg: String) {
        match &self.bar {
            Some(pb) => {
                pb.set_message(msg);
                pb.inc(1);
            }
            None => eprintln!("raybench: {msg}"),
        }
    }

    pub(crate) fn note(&self, msg: String) {
        match &self.bar {
            Some(pb) => pb.println(msg),
            None => eprintln!("raybench: {msg}"),
        }
    }

    pub(crate) fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}

/// The worker pool every build and trace runs in, with the run's FPU state on every worker, and
/// the environment fingerprint read on one of its workers (shared by `run` and `verify`).
pub(crate) struct Workers {
    pub pool: rayon::ThreadPool,
    pub environment: Environment,
}

impl Workers {
    pub(crate) fn start(threads: usize, ftz: bool) -> Result<Workers> {
        anyhow::ensure!(threads >= 1, "--threads must be at least 1 (got {threads})");
        fpu::set_ftz_daz(ftz);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("raybench-worker-{i}"))
            .start_handler(move |_| fpu::set_ftz_daz(ftz))
            .build()
            .context("creating the thread pool")?;
        let config = EmbreeParams {
            threads,
            ..EmbreeParams::medium()
        }
        .config_string();
        let device = Device::shared(&config)
            .map_err(|e| anyhow::anyhow!("creating the Embree device ({config}): {e}"))?;
        let mxcsr = pool.install(fpu::mxcsr);
        let environment = Environment::capture(threads, mxcsr, device.info());
        Ok(Workers { pool, environment })
    }
}

/// Notes and errors collected while a run goes on (both end up in its report).
#[derive(Debug, Default)]
pub(crate) struct Log {
    pub notes: Vec<String>,
    pub errors: Vec<String>,
}

/// Loads every requested scene in turn, names it uniquely and hands it to `visit`. An absent
/// optional file becomes a note and a load failure an error; the run goes on either way.
pub(crate) fn for_each_scene(
    requests: &[SceneRequest],
    seed: u64,
    progress: &Progress,
    log: &mut Log,
    mut visit: impl FnMut(&SceneRequest, &LoadedScene, &mut Log),
) {
    let mut used_names = std::collections::HashSet::new();
    for request in requests {
        let mut scene = match catch_panic(|| load(request, seed)) {
            Ok(Some(s)) => s,
            Ok(None) => {
                let note = format!("skipped {}: optional scene file is absent", request.label());
                progress.note(note.clone());
                log.notes.push(note);
                continue;
            }
            Err(e) => {
                let err = format!("scene {}: {e:#}", request.label());
                progress.note(err.clone());
                log.errors.push(err);
                continue;
            }
        };
        scene.scene.name = unique_name(request.report_name(), &mut used_names);
        visit(request, &scene, log);
    }
}

/// Runs `work`, turning a panic (a bug in a structure or generator) into an error, so one bad
/// structure costs its own result, not the whole run and its report.
pub(crate) fn catch_panic<T>(work: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
        .unwrap_or_else(|payload| Err(anyhow::anyhow!("panicked: {}", panic_message(&*payload))))
}

/// The message a panic was raised with (`panic!("…")` carries a `&str` or a `String`).
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// Checks what can be checked before any work: generator specs (names, parameters), and that
/// OBJ files that are not optional exist. A bad scene then fails the command at once, before
/// a report or dump is written, instead of after the scenes listed before it were measured.
pub fn check_requests(requests: &[SceneRequest]) -> Result<()> {
    for request in requests {
        request.check().with_context(|| match request {
            SceneRequest::Spec(spec) if !spec.to_ascii_lowercase().ends_with(".obj") => {
                format!("scene '{spec}'")
            }
            _ => "scene file".to_string(),
        })?;
    }
    Ok(())
}

/// Runs everything and returns the report (not yet written). With `dump_hits`, every
/// structure's answers are written there as they are measured (see [`crate::dump`]).
pub fn run(opts: &RunOptions, scenes: &[SceneRequest]) -> Result<Report> {
    anyhow::ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    anyhow::ensure!(opts.points >= 1, "--points must be at least 1 (got 0)");
    let mut structures = registry::select(&opts.structures)?;
    let reference_entry = registry::find(&opts.reference)?;
    let mut log = Log::default();
    if !structures.iter().any(|e| e.name == reference_entry.name) {
        log.notes.push(format!(
            "reference {} added to the measured structures so ratios can be computed",
            opts.reference
        ));
        structures.insert(0, registry::find(&opts.reference)?);
    }
    let mut dump = opts.dump_hits.as_deref().map(DumpDir::create).transpose()?;
    log.notes
        .extend(points_not_dumped(dump.is_some(), &opts.workloads));
    let workers = Workers::start(opts.threads, opts.ftz_daz)?;
    let tol = Tolerance::default();
    let progress = Progress::new(
        opts.progress,
        (scenes.len() * (structures.len() + 1)) as u64,
    );
    let mut report = Report {
        schema_version: SCHEMA_VERSION,
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        environment: workers.environment.clone(),
        run: RunSettings {
            suite: opts.suite.clone(),
            seed: opts.seed,
            rays: opts.rays,
            points: opts.points,
            threads: opts.threads,
            reference: opts.reference.clone(),
            build_runs: opts.build_runs,
            trace_runs: opts.trace_runs,
            tolerance: tol,
            structures: structures.iter().map(|e| e.name.to_string()).collect(),
            workloads: opts
                .workloads
                .iter()
                .map(|w| w.name().to_string())
                .collect(),
            whitted: whitted_params(),
        },
        scenes: Vec::new(),
        results: Vec::new(),
        notes: Vec::new(),
        errors: Vec::new(),
    };
    let explicit = opts.suite.is_none();
    workers.pool.install(|| {
        for_each_scene(scenes, opts.seed, &progress, &mut log, |_, scene, log| {
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
            for entry in &structures {
                if let Some(limit) = entry.suite_triangle_limit.filter(|&l| !explicit && scene.scene.mesh.len() > l) {
                    log.notes.push(format!(
                        "{} skipped on {name} ({} triangles > its suite limit {limit}); name it with --structures to run it",
                        entry.name,
                        scene.scene.mesh.len()
                    ));
                    progress.step(format!("{name}: {} skipped", entry.name));
                    continue;
                }
                progress.step(format!("{name}: {}", entry.name));
                match catch_panic(|| sr.measure(entry, opts, &tol, dump.as_mut())) {
                    Ok(r) => report.results.push(r),
                    Err(e) => log.errors.push(format!("{} on {name}: {e:#}", entry.name)),
                }
            }
        });
    });
    progress.finish();
    report.notes.append(&mut log.notes);
    report.errors.append(&mut log.errors);
    if let Some(dump) = dump {
        dump.finish()?;
    }
    fill_ratios(&mut report);
    Ok(report)
}

pub(crate) struct LoadedScene {
    pub scene: Scene,
    pub load_ms: f64,
}

fn load(request: &SceneRequest, seed: u64) -> Result<Option<LoadedScene>> {
    let start = Instant::now();
    Ok(request.load(seed)?.map(|scene| LoadedScene {
        scene,
        load_ms: start.elapsed().as_secs_f64() * 1e3,
    }))
}

/// One workload's rays (the same for every structure) and the reference's answers to them.
pub(crate) struct PreparedWorkload {
    pub workload: Workload,
    pub rays: Vec<Ray>,
    /// The reference's answers, traced on the timed path.
    pub reference: Answers,
    size: Option<(u32, u32)>,
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
        let ctx = BuildContext { threads };
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
                    rays: w.rays.len(),
                    any_hit: w.workload.any_hit(),
                    point_query: false,
                    width: w.size.map(|s| s.0),
                    height: w.size.map(|s| s.1),
                })
                .chain(self.point_workloads.iter().map(|w| WorkloadRecord {
                    workload: w.workload.name().to_string(),
                    rays: w.points.len(),
                    any_hit: false,
                    point_query: true,
                    width: None,
                    height: None,
                }))
                .collect(),
        }
    }

    fn measure(
        &self,
        entry: &StructureEntry,
        opts: &RunOptions,
        tol: &Tolerance,
        mut dump: Option<&mut DumpDir>,
    ) -> Result<ResultEntry> {
        let s = &self.scene.scene;
        let ctx = BuildContext {
            threads: opts.threads,
        };
        let (built, build) = time_builds(entry, &s.mesh, &ctx, opts.build_runs)?;
        let accel = built.accel.as_ref();
        let mut workloads = Vec::new();
        let mut primary_image = None;
        for wl in self.workloads.iter().filter(|w| !w.rays.is_empty()) {
            let any_hit = wl.workload.any_hit();
            let prepared = prepare_workload(accel, wl.workload, &wl.rays).map_err(|e| {
                anyhow::anyhow!(
                    "{} rays rejected by {}: {e}",
                    wl.workload.name(),
                    entry.name
                )
            })?;
            let (answers, mrays) = time_traces(
                accel,
                &wl.rays,
                &prepared,
                any_hit,
                opts.threads,
                opts.trace_runs,
            );
            let (counted, counters, work) = count_pass(accel, &wl.rays, any_hit);
            let sides = Sides {
                ours: accel,
                reference: self.reference.as_ref(),
                reference_name: &self.reference_name,
            };
            let (mut validation, levels) =
                validate(&s.mesh, &wl.rays, &answers, &wl.reference, &sides, tol);
            let paths = count_differences(&s.mesh, &wl.rays, &answers, &counted, tol);
            validation.counted_path_differs = paths.differs;
            validation.counted_path_ties = paths.ties;
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
            workloads.push(WorkloadResult {
                workload: wl.workload.name().to_string(),
                rays: wl.rays.len(),
                any_hit,
                point_query: false,
                mrays_per_s: mrays,
                speedup_vs_reference: None,
                counters_per_ray: has_counters
                    .then(|| CountersPerRay::from_total(&counters, wl.rays.len())),
                counters_total: has_counters.then_some(counters),
                validation,
            });
        }
        for pw in self.point_workloads.iter().filter(|w| !w.points.is_empty()) {
            workloads.push(self.measure_points(accel, pw, opts));
        }
        let memory = accel.memory();
        Ok(ResultEntry {
            scene: s.name.clone(),
            triangles: triangle_counts(s),
            structure: entry.name.to_string(),
            params: built.params.clone(),
            build,
            build_ratio_to_reference: None,
            memory_bytes: memory.total(),
            memory,
            build_stats: accel.build_stats(),
            workloads,
            primary_image,
        })
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
        check_rays(wl, &rays)?;
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
    check_points(workload, &points, radius)?;
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
fn check_points(wl: Workload, points: &[Vec3], radius: f32) -> Result<()> {
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

impl SceneRun<'_> {
    /// One structure on one closest-point workload: timed like rays (warm-up, median of
    /// `trace_runs` passes on the run's threads), then the counted pass, then validation
    /// against the reference. Not dumped: `--dump-hits` covers ray workloads only.
    fn measure_points(
        &self,
        accel: &dyn Accel,
        pw: &PreparedPoints,
        opts: &RunOptions,
    ) -> WorkloadResult {
        let (answers, throughput) =
            time_point_queries(accel, &pw.points, pw.radius, opts.threads, opts.trace_runs);
        let (counted, counters) = count_point_pass(accel, &pw.points, pw.radius);
        let mesh = &self.scene.scene.mesh;
        let mut validation = validate_points(
            mesh,
            &pw.points,
            pw.radius,
            &answers,
            &pw.reference,
            &self.reference_name,
        );
        validation.counted_path_differs = count_point_differences(&answers, &counted);
        let has_counters = accel.has_counters();
        WorkloadResult {
            workload: pw.workload.name().to_string(),
            rays: pw.points.len(),
            any_hit: false,
            point_query: true,
            mrays_per_s: throughput,
            speedup_vs_reference: None,
            counters_per_ray: has_counters
                .then(|| CountersPerRay::from_total(&counters, pw.points.len())),
            counters_total: has_counters.then_some(counters),
            validation,
        }
    }
}

/// The note a run or verify with `--dump-hits` and closest-point workloads carries.
pub(crate) fn points_not_dumped(dumping: bool, workloads: &[Workload]) -> Option<String> {
    let points: Vec<&str> = workloads
        .iter()
        .filter(|w| w.is_point_query())
        .map(Workload::name)
        .collect();
    (dumping && !points.is_empty()).then(|| {
        format!(
            "--dump-hits covers ray workloads only: {} not dumped",
            points.join(", ")
        )
    })
}

/// Knobs of the recursive `whitted` workload, written into the report's run settings.
pub fn whitted_params() -> WhittedParams {
    WhittedParams::default()
}

fn surface_hit(accel: &dyn Accel, ray: &Ray) -> Option<SurfaceHit> {
    accel.intersect(ray).map(|h| SurfaceHit {
        prim: h.prim,
        u: h.u,
        v: h.v,
    })
}

fn triangle_counts(s: &Scene) -> TriangleCounts {
    let traced = s.mesh.len() as u64;
    TriangleCounts {
        loaded: traced + s.removed.total(),
        removed: s.removed.total(),
        removed_by_reason: s.removed,
        traced,
    }
}

/// Every generated ray must be traceable by Embree; a bad one is a generator bug, named here.
fn check_rays(wl: Workload, rays: &[Ray]) -> Result<()> {
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
    crate::measure::trace_pass(reference, rays, &prepared, threads, &mut answers);
    Ok(answers)
}

/// Ratios to the reference measured in the same run: build time and throughput per workload.
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
        r.build_ratio_to_reference =
            (base.build.median_ms > 0.0).then(|| r.build.median_ms / base.build.median_ms);
        for w in &mut r.workloads {
            let base_w = base.workloads.iter().find(|b| b.workload == w.workload);
            w.speedup_vs_reference = base_w
                .filter(|b| b.mrays_per_s.median > 0.0)
                .map(|b| w.mrays_per_s.median / b.mrays_per_s.median);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_naming_its_message() {
        let err = catch_panic::<()>(|| panic!("bad node {}", 7)).unwrap_err();
        assert_eq!(err.to_string(), "panicked: bad node 7");
        assert_eq!(catch_panic(|| Ok(5)).unwrap(), 5);
    }

    #[test]
    fn bad_specs_and_missing_files_are_found_before_any_work() {
        let ok = SceneRequest::Spec("sphere:triangles=100".into());
        let optional = SceneRequest::File {
            path: "/nonexistent/optional.obj".into(),
            optional: true,
        };
        assert!(check_requests(&[ok.clone(), optional]).is_ok());
        let bad = SceneRequest::Spec("sphere:triangles=-5".into());
        let err = format!("{:#}", check_requests(&[ok.clone(), bad]).unwrap_err());
        assert!(err.contains("sphere:triangles=-5"), "{err}");
        let missing = SceneRequest::Spec("/nonexistent/scene.OBJ".into());
        let err = format!("{:#}", check_requests(&[ok, missing]).unwrap_err());
        assert!(err.contains("/nonexistent/scene.OBJ"), "{err}");
    }
}
