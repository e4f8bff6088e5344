//! The subcommands of `raybench`, one module each (its clap arguments and its handler), and
//! what several of them share: which scenes, structures, workloads and rays (the [`Selection`]
//! flags and their resolution), checks of every value and output directory before any work
//! starts, and the exit status. Every bad value is one error line naming it, exit status 1.

pub mod compare;
pub mod list;
pub mod replay;
pub mod report;
pub mod results;
pub mod run;
pub mod scene;
pub mod verify;
pub mod watertight;

use crate::atomic::ensure_writable_dir;
use crate::pipeline::scenes::check_requests;
use crate::registry;
use anyhow::{Context, Result};
use clap::Args;
use raybench_scenes::{SceneRequest, Workload};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Query points per closest-point workload when neither `--points` nor the suite say: a point
/// query costs about a hundred rays (bvh on the bunny: ~0.5 Mqueries/s near the surface against
/// tens of Mrays/s), so 10,000 points take about as long as a 100,000-ray workload.
pub const DEFAULT_POINTS: usize = 10_000;

/// A count that must be at least 1: `--rays 0` or `--threads abc` is refused by clap as
/// "invalid value '0' for '--rays <RAYS>': must be a whole number of at least 1".
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
    /// A suite from bench-scenes/ (see `raybench list`); flags below override its settings.
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
    /// Worker threads for builds and traces (Embree gets threads=N).
    #[arg(long, default_value_t = 1, value_parser = at_least_one)]
    pub threads: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
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
    /// neither the flags nor (if `suite_structures`) the suite name any.
    pub fn resolve(&self, suite_structures: bool, defaults: Defaults) -> Result<Resolved> {
        let (suite, requests) = match &self.suite {
            Some(name) => {
                let path = raybench_scenes::suites_dir().join(format!("{name}.json"));
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
        registry::select(&structures)?;
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
        Ok(Resolved {
            requests,
            structures,
            workloads,
            rays,
            points,
        })
    }
}

/// Every registered structure's name.
pub fn all_structures() -> Vec<String> {
    registry::registry()
        .iter()
        .map(|e| e.name.to_string())
        .collect()
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

/// `reports/<date>-<revision>`: where reports go unless `--out` says otherwise.
pub fn default_out_dir() -> PathBuf {
    let date = &crate::env::utc_timestamp()[..10];
    let rev: String = crate::env::git_revision().chars().take(10).collect();
    PathBuf::from("reports").join(format!("{date}-{rev}"))
}

/// Proves both output directories writable (creating them) before any work, the dump directory
/// first so that a bad `--dump-hits` leaves not even an empty `--out` behind.
pub fn check_outputs(out: &Path, dump_hits: Option<&Path>) -> Result<()> {
    if let Some(d) = dump_hits {
        ensure_writable_dir(d).context("--dump-hits")?;
    }
    ensure_writable_dir(out).context("--out")
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
