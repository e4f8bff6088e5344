//! `raybench run`: load scenes, generate one ray set per workload from the reference, build and
//! time every structure, count, validate, and assemble the report.

use crate::env::Environment;
use crate::images::{PixelInput, PrimaryImage, shade};
use crate::measure::{Answers, count_pass, time_builds, time_traces};
use crate::registry::{self, BuildContext, StructureEntry};
use crate::report::*;
use crate::validate::{Sides, count_differences, validate};
use anyhow::{Context, Result, bail};
use raybench_accel::Accel;
use raybench_accel::compare::Tolerance;
use raybench_embree::{Device, EmbreeParams, fpu};
use raybench_geom::Ray;
use raybench_scenes::{Scene, SuiteScene, SurfaceHit, WhittedParams, Workload};
use std::path::{Path, PathBuf};
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
}

/// A scene to load: by spec, or a suite file entry (with its `optional` flag).
#[derive(Clone, Debug)]
pub enum SceneRequest {
    Spec(String),
    File { path: PathBuf, optional: bool },
}

impl SceneRequest {
    fn label(&self) -> String {
        match self {
            SceneRequest::Spec(s) => s.clone(),
            SceneRequest::File { path, .. } => path.display().to_string(),
        }
    }

    /// The name the report uses for this scene: the spec as written (`teapot-in-stadium:view=
    /// stadium`), or an OBJ file's name (`teapot.obj`), so a generated teapot and the teapot
    /// file, or two views of one generator, never share a name.
    fn report_name(&self) -> String {
        let file_name = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
        match self {
            SceneRequest::Spec(s) if s.to_ascii_lowercase().ends_with(".obj") => {
                file_name(Path::new(s)).unwrap_or_else(|| s.clone())
            }
            SceneRequest::Spec(s) => s.trim().to_string(),
            SceneRequest::File { path, .. } => file_name(path).unwrap_or_else(|| self.label()),
        }
    }
}

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

/// The scenes of a suite, resolved relative to the manifest's directory.
pub fn suite_requests(manifest: &Path, scenes: &[SuiteScene]) -> Vec<SceneRequest> {
    let base = manifest.parent().unwrap_or(Path::new("."));
    scenes
        .iter()
        .map(|s| match s {
            SuiteScene::Generated(spec) => SceneRequest::Spec(spec.clone()),
            SuiteScene::File { obj, optional } => SceneRequest::File {
                path: base.join(obj),
                optional: *optional,
            },
        })
        .collect()
}

/// Live progress on a terminal; one plain line per step on stderr otherwise (CI logs).
struct Progress {
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    fn new(enabled: bool, steps: u64) -> Progress {
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
    fn step(&self, msg: String) {
        match &self.bar {
            Some(pb) => {
                pb.set_message(msg);
                pb.inc(1);
            }
            None => eprintln!("raybench: {msg}"),
        }
    }

    fn note(&self, msg: String) {
        match &self.bar {
            Some(pb) => pb.println(msg),
            None => eprintln!("raybench: {msg}"),
        }
    }

    fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}

/// Runs everything and returns the report (not yet written).
pub fn run(opts: &RunOptions, scenes: &[SceneRequest]) -> Result<Report> {
    anyhow::ensure!(opts.threads >= 1, "--threads must be at least 1");
    anyhow::ensure!(opts.rays >= 1, "--rays must be at least 1");
    let mut structures = registry::select(&opts.structures)?;
    let reference_entry = registry::find(&opts.reference)?;
    let mut notes = Vec::new();
    if !structures.iter().any(|e| e.name == reference_entry.name) {
        notes.push(format!(
            "reference {} added to the measured structures so ratios can be computed",
            opts.reference
        ));
        structures.insert(0, registry::find(&opts.reference)?);
    }
    let ftz = opts.ftz_daz;
    fpu::set_ftz_daz(ftz);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .thread_name(|i| format!("raybench-worker-{i}"))
        .start_handler(move |_| fpu::set_ftz_daz(ftz))
        .build()
        .context("creating the thread pool")?;
    let config = EmbreeParams {
        threads: opts.threads,
        ..EmbreeParams::medium()
    }
    .config_string();
    let device = Device::shared(&config)
        .map_err(|e| anyhow::anyhow!("creating the Embree device ({config}): {e}"))?;
    let mxcsr = pool.install(fpu::mxcsr);
    let environment = Environment::capture(opts.threads, mxcsr, device.info());

    let tol = Tolerance::default();
    let progress = Progress::new(
        opts.progress,
        (scenes.len() * (structures.len() + 1)) as u64,
    );
    let mut report = Report {
        schema_version: SCHEMA_VERSION,
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        environment,
        run: RunSettings {
            suite: opts.suite.clone(),
            seed: opts.seed,
            rays: opts.rays,
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
        notes,
        errors: Vec::new(),
    };
    let explicit = opts.suite.is_none();
    let mut used_names = std::collections::HashSet::new();
    pool.install(|| {
        for request in scenes {
            let mut scene = match load(request, opts.seed) {
                Ok(Some(s)) => s,
                Ok(None) => {
                    let note = format!("skipped {}: optional scene file is absent", request.label());
                    progress.note(note.clone());
                    report.notes.push(note);
                    continue;
                }
                Err(e) => {
                    let err = format!("scene {}: {e:#}", request.label());
                    progress.note(err.clone());
                    report.errors.push(err);
                    continue;
                }
            };
            scene.scene.name = unique_name(request.report_name(), &mut used_names);
            progress.step(format!("{}: generating workloads with {}", scene.scene.name, reference_entry.name));
            match SceneRun::prepare(&scene, opts, &reference_entry) {
                Ok(sr) => {
                    report.scenes.push(sr.record(&scene));
                    for entry in &structures {
                        if let Some(limit) = entry.suite_triangle_limit.filter(|&l| !explicit && scene.scene.mesh.len() > l) {
                            report.notes.push(format!(
                                "{} skipped on {} ({} triangles > its suite limit {limit}); name it with --structures to run it",
                                entry.name,
                                scene.scene.name,
                                scene.scene.mesh.len()
                            ));
                            progress.step(format!("{}: {} skipped", scene.scene.name, entry.name));
                            continue;
                        }
                        progress.step(format!("{}: {}", scene.scene.name, entry.name));
                        match sr.measure(entry, opts, &tol) {
                            Ok(r) => report.results.push(r),
                            Err(e) => report.errors.push(format!("{} on {}: {e:#}", entry.name, scene.scene.name)),
                        }
                    }
                }
                Err(e) => report.errors.push(format!("scene {}: {e:#}", scene.scene.name)),
            }
        }
    });
    progress.finish();
    fill_ratios(&mut report);
    Ok(report)
}

struct LoadedScene {
    scene: Scene,
    load_ms: f64,
}

fn load(request: &SceneRequest, seed: u64) -> Result<Option<LoadedScene>> {
    let start = Instant::now();
    let scene = match request {
        SceneRequest::Spec(spec) => raybench_scenes::resolve(spec, seed)?,
        SceneRequest::File { path, optional } => {
            if *optional && !path.exists() {
                return Ok(None);
            }
            raybench_scenes::load_obj(path)?
        }
    };
    Ok(Some(LoadedScene {
        scene,
        load_ms: start.elapsed().as_secs_f64() * 1e3,
    }))
}

/// One workload's rays (the same for every structure) and the reference's answers to them.
struct PreparedWorkload {
    workload: Workload,
    rays: Vec<Ray>,
    reference: Answers,
    size: Option<(u32, u32)>,
}

/// A scene with its workloads generated and the reference built.
struct SceneRun<'a> {
    scene: &'a LoadedScene,
    reference: Box<dyn Accel>,
    reference_name: String,
    workloads: Vec<PreparedWorkload>,
}

impl<'a> SceneRun<'a> {
    fn prepare(
        scene: &'a LoadedScene,
        opts: &RunOptions,
        reference_entry: &StructureEntry,
    ) -> Result<SceneRun<'a>> {
        let s = &scene.scene;
        let ctx = BuildContext {
            threads: opts.threads,
        };
        let reference = reference_entry.build(s.mesh.clone(), &ctx)?.accel;
        let bounds = s.mesh.bounds();
        let (primary, w, h) = raybench_scenes::primary_rays(&s.view, &bounds, opts.rays);
        let surface: Vec<Option<SurfaceHit>> = primary
            .iter()
            .map(|r| {
                reference.intersect(r).map(|h| SurfaceHit {
                    prim: h.prim,
                    u: h.u,
                    v: h.v,
                })
            })
            .collect();
        let mut workloads = Vec::new();
        for &wl in &opts.workloads {
            let seed = opts.seed;
            let (rays, size) = match wl {
                Workload::Primary => (primary.clone(), Some((w, h))),
                Workload::Random => (raybench_scenes::random_rays(&bounds, opts.rays, seed), None),
                Workload::Shadow => (
                    raybench_scenes::shadow_rays(&s.mesh, s.view.light, &primary, &surface),
                    None,
                ),
                Workload::Diffuse => (
                    raybench_scenes::diffuse_rays(&s.mesh, &primary, &surface, seed),
                    None,
                ),
                Workload::Whitted => (
                    whitted_rays(s, reference.as_ref(), &primary, &surface),
                    None,
                ),
            };
            check_rays(wl, &rays)?;
            let reference_answers = reference_answers(reference.as_ref(), &rays, wl.any_hit())?;
            workloads.push(PreparedWorkload {
                workload: wl,
                rays,
                reference: reference_answers,
                size,
            });
        }
        Ok(SceneRun {
            scene,
            reference,
            reference_name: reference_entry.name.to_string(),
            workloads,
        })
    }

    fn record(&self, loaded: &LoadedScene) -> SceneRecord {
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
                    width: w.size.map(|s| s.0),
                    height: w.size.map(|s| s.1),
                })
                .collect(),
        }
    }

    fn measure(
        &self,
        entry: &StructureEntry,
        opts: &RunOptions,
        tol: &Tolerance,
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
            let prepared = accel.prepare_rays(&wl.rays).map_err(|e| {
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
            validation.counted_path_differs = count_differences(&answers, &counted);
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
                mrays_per_s: mrays,
                speedup_vs_reference: None,
                counters_per_ray: has_counters
                    .then(|| CountersPerRay::from_total(&counters, wl.rays.len())),
                counters_total: has_counters.then_some(counters),
                validation,
            });
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

/// Knobs of the recursive `whitted` workload, written into the report's run settings.
pub fn whitted_params() -> WhittedParams {
    WhittedParams::default()
}

/// Every generation of Whitted's recursion below the primary rays, traced with the reference so
/// each structure later traces the identical set.
fn whitted_rays(
    scene: &Scene,
    reference: &dyn Accel,
    primary: &[Ray],
    primary_hits: &[Option<SurfaceHit>],
) -> Vec<Ray> {
    let params = whitted_params();
    let mut all = Vec::new();
    let mut parents = primary.to_vec();
    let mut weights = vec![1.0; primary.len()];
    let mut hits = primary_hits.to_vec();
    for depth in 1..=params.max_depth {
        let (children, child_weights) =
            raybench_scenes::whitted_children(scene, &parents, &weights, &hits, &params);
        all.extend_from_slice(&children);
        if depth == params.max_depth || children.is_empty() {
            break;
        }
        hits = children.iter().map(|r| surface_hit(reference, r)).collect();
        (parents, weights) = (children, child_weights);
    }
    all
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

fn reference_answers(reference: &dyn Accel, rays: &[Ray], any_hit: bool) -> Result<Answers> {
    let prepared = reference
        .prepare_rays(rays)
        .map_err(|e| anyhow::anyhow!("reference rejected a ray: {e}"))?;
    let mut answers = Answers::new(any_hit, rays.len());
    crate::measure::trace_pass(reference, rays, &prepared, 1, &mut answers);
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
