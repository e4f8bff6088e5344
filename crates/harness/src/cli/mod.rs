//! The subcommands of `raybench`, one module each (its clap arguments and its handler), and
//! what several of them share: which scenes, structures, workloads and rays (the [`Selection`]
//! flags and their resolution), checks of every value and output directory before any work
//! starts, and the exit status. Every bad value is one error line naming it, exit status 1.

pub mod bounds;
pub mod compare;
mod entry;
pub mod history;
pub mod list;
pub mod replay;
pub mod report;
pub mod results;
pub mod run;
pub mod scene;
pub mod verify;
pub mod watertight;

pub use entry::main_with;

use crate::outdir::{self, OutDir, Output};
use crate::pipeline::scenes::check_requests;
use crate::registry::Registry;
use anyhow::{Context, Result};
use clap::Args;
use raybench_scenes::{SceneRequest, Workload};
use std::path::Path;
use std::process::ExitCode;

/// Query points per closest-point workload when neither `--points` nor the suite say: a point
/// query costs about a hundred rays (bvh on the bunny: ~0.5 Mqueries/s near the surface against
/// tens of Mrays/s), so 10,000 points take about as long as a 100,000-ray workload.
pub const DEFAULT_POINTS: usize = 10_000;

/// The seed of scenes and rays when neither `--seed` nor the suite gives one.
pub const DEFAULT_SEED: u64 = 1;

/// A count that must be at least 1: `--rays 0` or `--threads abc` is refused by clap as
/// `invalid value '0' for '--rays <RAYS>': must be a whole number of at least 1`.
pub(crate) fn at_least_one(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err("must be a whole number of at least 1".to_string()),
    }
}

/// A budget of ray–triangle tests, at least 1.
pub(crate) fn budget(text: &str) -> Result<u64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x >= 1.0 && x <= u64::MAX as f64 && x.fract() == 0.0 => Ok(x as u64),
        _ => Err("must be a whole number of at least 1 (e.g. 200000000 or 2e8)".to_string()),
    }
}

/// What to run on: a suite and/or explicit scenes, structures, workloads, rays, seed, threads.
#[derive(Args, Debug, Clone)]
pub struct Selection {
    /// A suite from bench-scenes/ (see `raybench list`), or a manifest file of your own (a
    /// path ending in .json); flags below override its settings.
    #[arg(long)]
    pub suite: Option<String>,
    /// Scene specs (sphere, soup:triangles=5000) or .obj paths, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Structures, comma-separated (default: see the command's description).
    #[arg(long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Workloads, comma-separated: rays (primary, random, shadow, diffuse, whitted) and closest
    /// points (points-near, points-volume).
    #[arg(long, value_delimiter = ',')]
    pub workloads: Vec<Workload>,
    /// Rays per ray workload (primary: the image closest to this many pixels at 4:3).
    #[arg(long, value_parser = at_least_one)]
    pub rays: Option<usize>,
    /// Query points per closest-point workload (points-near, points-volume).
    #[arg(long, value_parser = at_least_one)]
    pub points: Option<usize>,
    /// Worker threads for builds and traces (Embree gets threads=N); at most 8 per core.
    #[arg(long, default_value_t = 1, value_parser = bounds::threads)]
    pub threads: usize,
    /// Seed of the generated scenes and the rays (default: the suite's, else 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Enable flush-to-zero and denormals-are-zero on every worker (Embree and native alike).
    #[arg(long)]
    pub ftz_daz: bool,
}

/// A selection with the suite read and every name checked, ready to run.
#[derive(Debug)]
pub struct Resolved {
    pub requests: Vec<SceneRequest>,
    pub structures: Vec<String>,
    pub workloads: Vec<Workload>,
    pub rays: usize,
    pub points: usize,
    pub seed: u64,
}

/// What applies when neither the flags nor the suite say.
#[derive(Debug, Clone)]
pub struct Defaults {
    pub structures: Vec<String>,
    pub rays: usize,
    pub points: usize,
}

impl Selection {
    /// Reads the suite, then checks scene specs, OBJ paths and structure names, so that a bad
    /// value fails before anything runs or is written. `defaults.structures` applies when
    /// neither the flags nor (if `suite_structures`) the suite name any; structure names are
    /// looked up in `registry`.
    pub fn resolve(
        &self,
        registry: &Registry,
        suite_structures: bool,
        defaults: Defaults,
    ) -> Result<Resolved> {
        let (suite, requests) = match &self.suite {
            Some(name) => {
                let path = suite_path(name);
                let suite = raybench_scenes::load_suite(&path)
                    .with_context(|| format!("suite '{name}'"))?;
                let requests = if self.scenes.is_empty() {
                    suite.requests(&path)
                } else {
                    specs(&self.scenes)
                };
                (Some(suite), requests)
            }
            None => {
                anyhow::ensure!(
                    !self.scenes.is_empty(),
                    "give --suite NAME or --scenes A,B (see `raybench list`)"
                );
                (None, specs(&self.scenes))
            }
        };
        check_requests(&requests)?;
        let from_suite = suite.as_ref().filter(|_| suite_structures);
        let structures = pick(
            self.structures.clone(),
            from_suite.map(|s| s.structures.clone()),
            || defaults.structures,
        );
        registry.select(&structures)?;
        let workloads = pick(
            self.workloads.clone(),
            suite.as_ref().map(|s| s.workloads.clone()),
            || Workload::ALL.to_vec(),
        );
        let rays = self
            .rays
            .or(suite.as_ref().map(|s| s.rays))
            .unwrap_or(defaults.rays);
        let points = self
            .points
            .or(suite.as_ref().and_then(|s| s.points))
            .unwrap_or(defaults.points);
        let seed = self
            .seed
            .or(suite.as_ref().and_then(|s| s.seed))
            .unwrap_or(DEFAULT_SEED);
        let source = |flag: &str| match (&self.suite, suite.is_some()) {
            (Some(name), true) => format!("{flag} (with suite '{name}')"),
            _ => flag.to_string(),
        };
        no_duplicates(&source("--scenes"), requests.iter().map(|r| r.label()))?;
        no_duplicates(&source("--structures"), structures.iter().cloned())?;
        no_duplicates(
            &source("--workloads"),
            workloads.iter().map(|w| w.name().to_string()),
        )?;
        let ray_workloads = workloads.iter().filter(|w| !w.is_point_query()).count();
        let whitted = workloads.contains(&Workload::Whitted);
        bounds::check_rays(rays, ray_workloads, whitted)?;
        bounds::check_points(points, workloads.len() - ray_workloads)?;
        Ok(Resolved {
            requests,
            structures,
            workloads,
            rays,
            points,
            seed,
        })
    }
}

/// Refuses a list that names something twice: a scene, structure or workload measured twice
/// in one run would be two entries under one name, which reports and `compare` cannot tell
/// apart.
pub(crate) fn no_duplicates(flag: &str, names: impl Iterator<Item = String>) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    for name in names {
        anyhow::ensure!(
            seen.insert(name.clone()),
            "{flag} names `{name}` twice; each may appear once"
        );
    }
    Ok(())
}

pub fn specs(scenes: &[String]) -> Vec<SceneRequest> {
    join_spec_parameters(scenes)
        .into_iter()
        .map(SceneRequest::Spec)
        .collect()
}

/// `--scenes` is split on commas, and so are a spec's parameters: `offset:triangles=500,offset=1e7`
/// arrives as `offset:triangles=500` and `offset=1e7`. A piece that is `key=value` (it has `=`
/// but no `:` and is not an `.obj` path) continues the spec before it.
pub fn join_spec_parameters(pieces: &[String]) -> Vec<String> {
    let mut specs: Vec<String> = Vec::new();
    for piece in pieces {
        let continues = piece.contains('=')
            && !piece.contains(':')
            && !piece.to_ascii_lowercase().ends_with(".obj");
        match specs.last_mut() {
            Some(last) if continues => {
                last.push(',');
                last.push_str(piece);
            }
            _ => specs.push(piece.clone()),
        }
    }
    specs
}

/// The manifest `--suite` names: the file itself when the value ends in `.json` (relative to
/// the working directory), else the suite of that name in [`raybench_scenes::suites_dir`].
fn suite_path(name: &str) -> std::path::PathBuf {
    let path = std::path::Path::new(name);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        path.to_owned()
    } else {
        raybench_scenes::suites_dir().join(format!("{name}.json"))
    }
}

/// Explicit flags win, then the suite's value, then the default.
pub fn pick<T>(
    explicit: Vec<T>,
    from_suite: Option<Vec<T>>,
    default: impl FnOnce() -> Vec<T>,
) -> Vec<T> {
    if !explicit.is_empty() {
        explicit
    } else {
        from_suite.unwrap_or_else(default)
    }
}

/// The output directories of a command, claimed (locked, checked, proven writable) before any
/// work; dropping it releases them.
#[derive(Debug)]
pub struct Claimed {
    pub out: OutDir,
    pub dumps: Option<OutDir>,
}

/// Claims `--out` (or a new `reports/<date>-<revision>[-N]`) for `outputs`, and `--dump-hits`
/// when given, the dump directory first so that a bad `--dump-hits` leaves not even an empty
/// `--out` behind. `force` replaces the outputs of an earlier command (see [`OutDir::claim`]).
pub fn claim_outputs(
    out: Option<&Path>,
    outputs: &[Output],
    dump_hits: Option<&Path>,
    force: bool,
) -> Result<Claimed> {
    let dumps = dump_hits
        .map(|d| OutDir::claim(d, outdir::DUMPS, force).context("--dump-hits"))
        .transpose()?;
    let out = match out {
        Some(dir) => OutDir::claim(dir, outputs, force).context("--out")?,
        None => {
            let date = &crate::env::utc_timestamp()[..10];
            let rev: String = crate::env::git_revision().chars().take(10).collect();
            OutDir::claim_new(Path::new("reports"), &format!("{date}-{rev}"), outputs)?
        }
    };
    Ok(Claimed { out, dumps })
}

/// 2 on any mismatch (the answers are wrong somewhere), else 1 on errors, else 0.
pub fn exit_status(mismatches: u64, errors: usize) -> ExitCode {
    if mismatches > 0 {
        ExitCode::from(2)
    } else if errors > 0 {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

#[cfg(test)]
mod tests {
    use super::{ExitCode, exit_status, join_spec_parameters};

    #[test]
    fn mismatches_outrank_errors_in_the_exit_status() {
        assert_eq!(exit_status(0, 0), ExitCode::SUCCESS);
        assert_eq!(exit_status(0, 3), ExitCode::from(1));
        assert_eq!(exit_status(1, 0), ExitCode::from(2));
        assert_eq!(exit_status(5, 2), ExitCode::from(2));
    }

    #[test]
    fn parameters_rejoin_their_spec() {
        let pieces: Vec<String> = [
            "offset:triangles=500",
            "offset=1e7",
            "sphere",
            "soup:triangles=5",
            "a/b=c.obj",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            join_spec_parameters(&pieces),
            [
                "offset:triangles=500,offset=1e7",
                "sphere",
                "soup:triangles=5",
                "a/b=c.obj"
            ]
        );
    }
}
