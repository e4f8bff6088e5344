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

use crate::agreement::{agreement_sentence, class_counts};
use crate::dump::DumpDir;
use crate::env::Environment;
use crate::measure::{Answers, count_pass, count_point_pass, point_pass, trace_pass};
use crate::registry::{self, BuildContext, StructureEntry};
use crate::report::{TriangleCounts, Validation, write_json_atomic};
use crate::run::{
    LoadedScene, Log, PreparedPoints, Progress, QueryCounts, SceneRequest, SceneRun, Workers,
    catch_panic, for_each_scene, points_not_dumped, reference_answers,
};
use crate::validate::{
    Sides, count_differences, count_point_differences, validate, validate_points,
};
use anyhow::{Context, Result, ensure};
use raybench_accel::classify::{Tolerance, VerdictCounts};
use raybench_accel::{Accel, PointHit};
use raybench_geom::{Ray, TriangleMesh};
use raybench_scenes::Workload;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The references every structure is checked against, in the order tables list them.
pub const REFERENCES: [&str; 3] = ["embree-medium", "embree-robust", "bruteforce"];

/// Ray–triangle tests brute force may spend per scene × workload (per brute-force pass):
/// about half a second of one core at the 3.8e7 Möller–Trumbore tests per second measured for
/// `bruteforce` (release build, `soup:triangles=10000`, 20,000 random rays, on the shared
/// 2-core development machine). A scene × workload costs five such passes (the reference, and
/// the timed and counted paths of `bruteforce` and `bruteforce-watertight`), so the
/// adversarial suite verifies in minutes. At 5,000 rays every scene up to 4,000 triangles is
/// checked on every ray; `--brute-force-budget 2e8` checks ten times as many.
pub const BRUTE_FORCE_BUDGET: u64 = 20_000_000;

/// Bumped whenever a field of `verify.json` changes meaning or disappears.
pub const VERIFY_SCHEMA_VERSION: u32 = 1;

/// Replay commands printed for the first mismatches.
pub const REPLAY_COMMANDS: usize = 5;

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

/// `verify.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifyReport {
    pub schema_version: u32,
    pub tool_version: String,
    pub environment: Environment,
    pub settings: VerifySettings,
    pub scenes: Vec<VerifiedScene>,
    /// One entry per scene × structure × workload, with one validation per reference.
    pub results: Vec<VerifiedWorkload>,
    /// Per structure × reference, summed over scenes and workloads (what the table prints).
    pub totals: Vec<AgreementRow>,
    pub notes: Vec<String>,
    pub errors: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifySettings {
    pub suite: Option<String>,
    pub seed: u64,
    pub rays: usize,
    /// Query points per closest-point workload (0 in files older than point workloads).
    #[serde(default)]
    pub points: usize,
    pub threads: usize,
    pub structures: Vec<String>,
    pub workloads: Vec<String>,
    pub references: Vec<String>,
    /// Ray–triangle tests brute force may spend per scene × workload.
    pub brute_force_budget: u64,
    pub tolerance: Tolerance,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifiedScene {
    /// The name results use (unique within the run).
    pub name: String,
    /// What `raybench replay --scene` takes to rebuild it (a spec or an OBJ path).
    pub spec: String,
    pub triangles: TriangleCounts,
    pub workloads: Vec<SampledWorkload>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SampledWorkload {
    pub workload: String,
    pub rays: usize,
    /// Rays the `bruteforce` reference checked (evenly spaced; all when affordable).
    pub brute_force_rays: usize,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VerifiedWorkload {
    pub scene: String,
    pub structure: String,
    pub workload: String,
    pub any_hit: bool,
    /// Rays this structure traced: every ray, or the brute-force subsample for brute force.
    pub rays: usize,
    pub subsampled: bool,
    /// Rays where the counted path answered differently from the timed path (a bug).
    pub counted_path_differs: u64,
    /// One per reference, in [`REFERENCES`] order. Disputed rays carry their index in the
    /// workload's full ray list.
    pub validations: Vec<Validation>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AgreementRow {
    pub structure: String,
    pub reference: String,
    pub rays: u64,
    #[serde(flatten)]
    pub counts: VerdictCounts,
    pub counted_path_differs: u64,
    pub mismatch_rate_upper95: f64,
    /// "0 mismatches in n rays (95% upper bound 3/n = …)" or "k mismatches in n rays".
    pub agreement: String,
}

impl VerifyReport {
    /// Mismatches against any reference plus counted-path differences: anything non-zero is a
    /// bug somewhere (exit status 2).
    pub fn mismatches(&self) -> u64 {
        self.results
            .iter()
            .map(|r| {
                r.counted_path_differs
                    + r.validations.iter().map(|v| v.counts.mismatch).sum::<u64>()
            })
            .sum()
    }

    /// Writes `dir/verify.json` atomically.
    pub fn write_atomic(&self, dir: &Path) -> Result<PathBuf> {
        write_json_atomic(dir, "verify.json", self)
    }

    pub fn read(path: &Path) -> Result<VerifyReport> {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let report: VerifyReport = serde_json::from_slice(&bytes)
            .with_context(|| format!("parsing {}", path.display()))?;
        ensure!(
            report.schema_version == VERIFY_SCHEMA_VERSION,
            "{}: schema_version {} is not the supported {VERIFY_SCHEMA_VERSION}",
            path.display(),
            report.schema_version
        );
        Ok(report)
    }

    /// A `raybench replay` command line for each of the first `n` mismatches.
    pub fn replay_commands(&self, n: usize) -> Vec<String> {
        let mut out = Vec::new();
        for r in &self.results {
            let Some(scene) = self.scenes.iter().find(|s| s.name == r.scene) else {
                continue;
            };
            for v in &r.validations {
                for d in &v.first_point_mismatches {
                    out.push(format!(
                        "# {} / {} point {}: {} vs {}: {} (point bits {}; `raybench replay` takes rays only)",
                        r.scene,
                        r.workload,
                        d.index,
                        r.structure,
                        v.reference,
                        d.verdict,
                        d.point_bits.join(",")
                    ));
                    if out.len() == n {
                        return out;
                    }
                }
                for d in &v.first_mismatches {
                    let structures = [r.structure.as_str(), v.reference.as_str()];
                    out.push(format!(
                        "# {} / {} ray {}: {} vs {}: {}\n{}",
                        r.scene,
                        r.workload,
                        d.index,
                        r.structure,
                        v.reference,
                        d.verdict,
                        replay_command(&scene.spec, self.settings.seed, &structures, &d.ray_bits)
                    ));
                    if out.len() == n {
                        return out;
                    }
                }
            }
        }
        out
    }
}

/// A ready-to-paste `raybench replay` command line.
pub fn replay_command(
    scene_spec: &str,
    seed: u64,
    structures: &[&str],
    ray_bits: &[String],
) -> String {
    let mut names: Vec<&str> = Vec::new();
    for s in structures {
        if !names.contains(s) {
            names.push(s);
        }
    }
    format!(
        "raybench replay --scene {} --seed {seed} --structure {} --ray {}",
        shell_quote(scene_spec),
        names.join(","),
        ray_bits.join(",")
    )
}

/// Quotes `s` for a POSIX shell unless it is made of characters that need none.
fn shell_quote(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./:=,+@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
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

/// What every structure of one scene is checked against.
struct SceneReferences<'a> {
    /// The workloads and `embree-medium`'s answers.
    run: SceneRun<'a>,
    robust: Box<dyn Accel>,
    brute: Box<dyn Accel>,
    /// Parallel to `run.workloads`.
    workloads: Vec<WorkloadReferences>,
    /// Parallel to `run.point_workloads`.
    point_workloads: Vec<PointReferences>,
}

struct PointReferences {
    /// `embree-robust` on every point.
    robust: Vec<Option<PointHit>>,
    /// The brute-force subsample (every point when affordable), and `bruteforce` on it.
    sample: Vec<usize>,
    brute: Vec<Option<PointHit>>,
}

struct WorkloadReferences {
    /// `embree-robust` on every ray.
    robust: Answers,
    /// The brute-force subsample (every ray when affordable), and `bruteforce` on it.
    sample: Vec<usize>,
    brute: Answers,
}

/// Settings shared by every check of a run.
struct Checker<'a> {
    opts: &'a VerifyOptions,
    tol: Tolerance,
    progress: &'a Progress,
}

impl Checker<'_> {
    fn ctx(&self) -> BuildContext {
        BuildContext {
            threads: self.opts.threads,
        }
    }

    fn prepare<'s>(&self, scene: &'s LoadedScene) -> Result<SceneReferences<'s>> {
        let o = self.opts;
        let medium = registry::find(REFERENCES[0])?;
        let counts = QueryCounts {
            rays: o.rays,
            points: o.points,
        };
        let run = SceneRun::prepare(scene, &o.workloads, counts, o.seed, o.threads, &medium)?;
        let mesh = &scene.scene.mesh;
        let robust = registry::find(REFERENCES[1])?
            .build(mesh.clone(), &self.ctx())?
            .accel;
        let brute = registry::find(REFERENCES[2])?
            .build(mesh.clone(), &self.ctx())?
            .accel;
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

    /// Builds one structure and checks it on every workload of the scene.
    fn check_structure(
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
            let (result, traced) = self.check_workload(&subject, refs, wl, wr)?;
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
                out.push(self.check_points(&subject, refs, pw, pr));
            }
        }
        Ok(out)
    }

    /// The subject's timed and counted closest points, compared with each other and with every
    /// reference (on the brute-force subsample where either side answered only that).
    fn check_points(
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
        let differs = count_point_differences(&timed, &counted);
        let mesh = &refs.run.scene.scene.mesh;
        let compare = |name: &str, theirs: &[Option<PointHit>], theirs_on_sample: bool| {
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
            let mut v = validate_points(mesh, &queried, pw.radius, &ours, &theirs, name);
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
            rays: points.len(),
            subsampled: subject.sampled,
            counted_path_differs: differs,
            validations: vec![
                compare(REFERENCES[0], &pw.reference, false),
                compare(REFERENCES[1], &pr.robust, false),
                compare(REFERENCES[2], &pr.brute, true),
            ],
        }
    }

    /// The subject's timed and counted answers, compared with each other and with every
    /// reference. Also returns the timed answers (for the dump).
    fn check_workload(
        &self,
        subject: &Subject<'_>,
        refs: &SceneReferences<'_>,
        wl: &crate::run::PreparedWorkload,
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
        let paths = count_differences(mesh, &rays, &timed, &counted, &self.tol);
        let differs = paths.differs;
        let compare = |reference: (&str, &dyn Accel), theirs: &Answers, on_sample: bool| {
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
            comparison(
                mesh, &rays, &ours, &theirs, &sides, &self.tol, indices, differs,
            )
        };
        let validations = vec![
            compare(
                (REFERENCES[0], refs.run.reference.as_ref()),
                &wl.reference,
                false,
            ),
            compare((REFERENCES[1], refs.robust.as_ref()), &wr.robust, false),
            compare((REFERENCES[2], refs.brute.as_ref()), &wr.brute, true),
        ];
        let result = VerifiedWorkload {
            scene: refs.run.scene.scene.name.clone(),
            structure: subject.name.to_string(),
            workload: wl.workload.name().to_string(),
            any_hit,
            rays: rays.len(),
            subsampled: subject.sampled,
            counted_path_differs: differs,
            validations,
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

/// Validates `ours` against `theirs` on `rays`; disputed rays get their index in the full
/// workload (`indices[k]` for the k-th of a subsample).
#[allow(clippy::too_many_arguments)]
fn comparison(
    mesh: &TriangleMesh,
    rays: &[Ray],
    ours: &Answers,
    theirs: &Answers,
    sides: &Sides<'_>,
    tol: &Tolerance,
    indices: Option<&[usize]>,
    counted_path_differs: u64,
) -> Validation {
    let (mut v, _levels) = validate(mesh, rays, ours, theirs, sides, tol);
    if let Some(idx) = indices {
        for d in v.first_mismatches.iter_mut().chain(&mut v.first_ambiguous) {
            d.index = idx[d.index];
        }
    }
    v.counted_path_differs = counted_path_differs;
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
    let prepared = crate::run::prepare_workload(accel, workload, rays)
        .map_err(|e| anyhow::anyhow!("{} rejected a ray: {e}", accel.name()))?;
    let mut timed = Answers::new(any_hit, rays.len());
    trace_pass(accel, rays, &prepared, threads, &mut timed);
    let (counted, _, _) = count_pass(accel, rays, any_hit);
    Ok((timed, counted))
}

fn gather<T: Copy>(items: &[T], indices: &[usize]) -> Vec<T> {
    indices.iter().map(|&i| items[i]).collect()
}

fn maybe_gather<'a, T: Copy>(items: &'a [T], indices: Option<&[usize]>) -> Cow<'a, [T]> {
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

/// Checks every structure on every scene; the report is not yet written.
pub fn verify(opts: &VerifyOptions, requests: &[SceneRequest]) -> Result<VerifyReport> {
    ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    ensure!(
        opts.brute_force_budget >= 1,
        "the brute-force budget must be at least 1"
    );
    let subjects = registry::select(&opts.structures)?;
    let mut dump = opts.dump_hits.as_deref().map(DumpDir::create).transpose()?;
    let workers = Workers::start(opts.threads, opts.ftz_daz)?;
    let progress = Progress::new(
        opts.progress,
        (requests.len() * (subjects.len() + 1)) as u64,
    );
    let checker = Checker {
        opts,
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
        schema_version: VERIFY_SCHEMA_VERSION,
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        environment,
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
    let refs = match catch_panic(|| checker.prepare(scene)) {
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
                rays: wl.rays.len(),
                brute_force_rays: wr.sample.len(),
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
            rays: pw.points.len(),
            brute_force_rays: pr.sample.len(),
        })
}

/// Sums every structure × reference over scenes and workloads, in subject order.
fn totals(results: &[VerifiedWorkload]) -> Vec<AgreementRow> {
    let mut rows: Vec<AgreementRow> = Vec::new();
    for r in results {
        for v in &r.validations {
            let i = match rows
                .iter()
                .position(|x| x.structure == r.structure && x.reference == v.reference)
            {
                Some(i) => i,
                None => {
                    rows.push(AgreementRow {
                        structure: r.structure.clone(),
                        reference: v.reference.clone(),
                        rays: 0,
                        counts: VerdictCounts::default(),
                        counted_path_differs: 0,
                        mismatch_rate_upper95: 0.0,
                        agreement: String::new(),
                    });
                    rows.len() - 1
                }
            };
            rows[i].counts += v.counts;
            rows[i].counted_path_differs += v.counted_path_differs;
        }
    }
    for row in &mut rows {
        let v = Validation::new(&row.reference, row.counts);
        row.rays = row.counts.total();
        row.mismatch_rate_upper95 = v.mismatch_rate_upper95;
        row.agreement = agreement_sentence(&row.counts);
    }
    rows
}

/// The table `raybench verify` prints: per structure and reference, every class and the
/// agreement sentence; how much brute force checked; replay commands for the first mismatches.
pub fn verify_table(report: &VerifyReport) -> String {
    let mut out = String::new();
    let s = &report.settings;
    let _ = writeln!(
        out,
        "Verified {} structures on {} scenes ({} workloads, seed {}, {} threads) against {}.",
        s.structures.len(),
        report.scenes.len(),
        s.workloads.len(),
        s.seed,
        s.threads,
        s.references.join(", ")
    );
    let _ = writeln!(out, "{}", brute_force_coverage(report));
    let _ = writeln!(
        out,
        "\n{:<22} {:<14} {:>9} {:>9} {:>9} {:>10} {:>6} {:>8} {:>8} {:>8} {:>8}  agreement",
        "structure",
        "reference",
        "rays",
        "both_miss",
        "exact",
        "within_tol",
        "tie",
        "boundary",
        "edge_amb",
        "mismatch",
        "cnt≠timed"
    );
    for row in &report.totals {
        let c = &row.counts;
        let _ = writeln!(
            out,
            "{:<22} {:<14} {:>9} {:>9} {:>9} {:>10} {:>6} {:>8} {:>8} {:>8} {:>8}  {}",
            row.structure,
            row.reference,
            row.rays,
            c.both_miss,
            c.exact,
            c.within_tolerance,
            c.tie,
            c.boundary,
            c.edge_ambiguous,
            c.mismatch,
            row.counted_path_differs,
            row.agreement
        );
    }
    let mut all = VerdictCounts::default();
    report.totals.iter().for_each(|r| all += r.counts);
    // The same ray appears once per structure × reference here, so these comparisons are not
    // independent and no bound is given for their sum; each row's bound stands on its own.
    let _ = writeln!(
        out,
        "\nAll rows: {} mismatches in {} comparisons ({}).",
        all.mismatch,
        all.total(),
        class_counts(&all)
    );
    write_mismatch_replays(&mut out, report);
    for n in &report.notes {
        let _ = writeln!(out, "note: {n}");
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}

fn write_mismatch_replays(out: &mut String, report: &VerifyReport) {
    let commands = report.replay_commands(REPLAY_COMMANDS);
    if commands.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\n{} mismatches (and counted-path differences); replay the first {} with:",
        report.mismatches(),
        commands.len()
    );
    for c in commands {
        let _ = writeln!(out, "{c}");
    }
}

/// "bruteforce checked 54,000 of 60,000 rays; subsampled: bunny (2,879 of 5,000 per workload)".
fn brute_force_coverage(report: &VerifyReport) -> String {
    let (mut checked, mut total) = (0, 0);
    let mut subsampled = Vec::new();
    for scene in &report.scenes {
        let c: usize = scene.workloads.iter().map(|w| w.brute_force_rays).sum();
        let t: usize = scene.workloads.iter().map(|w| w.rays).sum();
        checked += c;
        total += t;
        if c < t {
            subsampled.push(format!("{} ({c} of {t})", scene.name));
        }
    }
    let budget = report.settings.brute_force_budget;
    let mut line = format!(
        "Brute force checked {checked} of {total} rays (budget {budget:.1e} ray–triangle tests per scene × workload)"
    );
    if subsampled.is_empty() {
        line.push_str(": every ray.");
    } else {
        let _ = write!(
            line,
            "; evenly spaced subsamples on {}.",
            subsampled.join(", ")
        );
    }
    line
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

    #[test]
    fn replay_commands_quote_what_the_shell_would_split() {
        let bits = ["0x3f800000".to_string(), "0x00000000".to_string()];
        assert_eq!(
            replay_command(
                "sphere:triangles=800,radius=2",
                7,
                &["grid", "bruteforce"],
                &bits
            ),
            "raybench replay --scene sphere:triangles=800,radius=2 --seed 7 \
             --structure grid,bruteforce --ray 0x3f800000,0x00000000"
        );
        assert_eq!(
            replay_command("my scenes/it's.obj", 1, &["grid", "grid"], &bits),
            "raybench replay --scene 'my scenes/it'\\''s.obj' --seed 1 --structure grid \
             --ray 0x3f800000,0x00000000"
        );
    }
}
