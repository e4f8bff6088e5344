//! `raybench`: list what can be measured, and run measurements into a validated JSON report.

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use raybench_harness::registry;
use raybench_harness::run::{RunOptions, SceneRequest, run, suite_requests};
use raybench_harness::summary::summary_table;
use raybench_scenes::Workload;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "raybench",
    version,
    about = "Ray-tracing acceleration structures, timed and checked against Embree 3"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Scenes, structures, workloads and suites raybench knows.
    List,
    /// Build, time, count and validate; write DIR/report.json.
    Run(RunArgs),
}

#[derive(Args, Debug)]
struct RunArgs {
    /// A suite from bench-scenes/ (see `raybench list`); flags below override its settings.
    #[arg(long)]
    suite: Option<String>,
    /// Scene specs (sphere, soup:triangles=5000) or .obj paths, comma-separated.
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
    /// Structures, comma-separated (default: the suite's, or every registered one).
    #[arg(long, value_delimiter = ',')]
    structures: Vec<String>,
    /// Workloads, comma-separated: primary, random, shadow, diffuse.
    #[arg(long, value_delimiter = ',')]
    workloads: Vec<Workload>,
    /// Rays per workload (primary: the image closest to this many pixels at 4:3).
    #[arg(long)]
    rays: Option<usize>,
    /// Worker threads for builds and traces (Embree gets threads=N).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// The structure every answer is checked against and every ratio is relative to.
    #[arg(long, default_value = "embree-medium")]
    reference: String,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Timed builds after one warm-up build.
    #[arg(long, default_value_t = 3)]
    build_runs: usize,
    /// Timed trace passes after one warm-up pass.
    #[arg(long, default_value_t = 5)]
    trace_runs: usize,
    /// Enable flush-to-zero and denormals-are-zero on every worker (Embree and native alike).
    #[arg(long)]
    ftz_daz: bool,
    /// Output directory (default: reports/<date>-<revision>).
    #[arg(long)]
    out: Option<PathBuf>,
}

fn main() -> ExitCode {
    match real_main() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("raybench: error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn real_main() -> Result<ExitCode> {
    match Cli::parse().command {
        Command::List => list().map(|_| ExitCode::SUCCESS),
        Command::Run(args) => run_command(args),
    }
}

fn list() -> Result<()> {
    println!("Structures:");
    for e in registry::registry() {
        let limit = e
            .suite_triangle_limit
            .map(|l| format!(" (suites: up to {l} triangles)"))
            .unwrap_or_default();
        println!("  {:<24} {}{limit}", e.name, e.description);
    }
    println!("\nScene generators (spec: name[:key=value,...]):");
    for g in raybench_scenes::generators() {
        println!("  {:<24} {}", g.name, g.description);
        for p in g.params {
            println!("  {:<24}   {}: {}", "", p.key, p.describe());
        }
    }
    println!(
        "  {:<24} {}",
        "PATH.obj", "a Wavefront OBJ file (triangulated, positions only)"
    );
    let shared = raybench_scenes::suites_dir().join("../../shared/scenes");
    match std::fs::read_dir(&shared) {
        Ok(entries) => {
            let mut files: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("obj")))
                .collect();
            files.sort();
            println!("\nReal scenes ({}):", shared.display());
            for f in files {
                println!("  {}", f.display());
            }
        }
        Err(_) => println!(
            "\nReal scenes: {} is absent (suites skip those files with a note)",
            shared.display()
        ),
    }
    println!("\nWorkloads:");
    for w in Workload::ALL {
        println!("  {:<24} {}", w.name(), w.description());
    }
    println!("\nSuites ({}):", raybench_scenes::suites_dir().display());
    for (path, suite) in raybench_scenes::list_suites()? {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        println!(
            "  {stem:<24} {} ({} scenes, {} rays)",
            suite.description,
            suite.scenes.len(),
            suite.rays
        );
    }
    Ok(())
}

fn default_out_dir() -> PathBuf {
    let date = &raybench_harness::env::utc_timestamp()[..10];
    let rev: String = raybench_harness::env::git_revision()
        .chars()
        .take(10)
        .collect();
    PathBuf::from("reports").join(format!("{date}-{rev}"))
}

fn run_command(args: RunArgs) -> Result<ExitCode> {
    let (suite, requests) = match &args.suite {
        Some(name) => {
            let path = raybench_scenes::suites_dir().join(format!("{name}.json"));
            let suite =
                raybench_scenes::load_suite(&path).with_context(|| format!("suite '{name}'"))?;
            let requests = if args.scenes.is_empty() {
                suite_requests(&path, &suite.scenes)
            } else {
                specs(&args.scenes)
            };
            (Some(suite), requests)
        }
        None => {
            anyhow::ensure!(
                !args.scenes.is_empty(),
                "give --suite NAME or --scenes A,B (see `raybench list`)"
            );
            (None, specs(&args.scenes))
        }
    };
    let all_structures = || {
        registry::registry()
            .iter()
            .map(|e| e.name.to_string())
            .collect::<Vec<_>>()
    };
    let opts = RunOptions {
        suite: args.suite.clone(),
        scenes: requests.iter().map(|r| format!("{r:?}")).collect(),
        structures: pick(
            args.structures,
            suite.as_ref().map(|s| s.structures.clone()),
            all_structures,
        ),
        workloads: pick(
            args.workloads,
            suite.as_ref().map(|s| s.workloads.clone()),
            || Workload::ALL.to_vec(),
        ),
        rays: args
            .rays
            .or(suite.as_ref().map(|s| s.rays))
            .unwrap_or(100_000),
        threads: args.threads,
        reference: args.reference,
        seed: args.seed,
        build_runs: args.build_runs,
        trace_runs: args.trace_runs,
        ftz_daz: args.ftz_daz,
        progress: std::io::stdout().is_terminal(),
    };
    let report = run(&opts, &requests)?;
    let dir = args.out.unwrap_or_else(default_out_dir);
    let path = report.write_atomic(&dir)?;
    print!("{}", summary_table(&report));
    println!("report: {}", path.display());
    Ok(if report.mismatches() > 0 {
        eprintln!(
            "raybench: {} mismatches against {}",
            report.mismatches(),
            report.run.reference
        );
        ExitCode::from(2)
    } else if !report.errors.is_empty() {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn specs(scenes: &[String]) -> Vec<SceneRequest> {
    scenes
        .iter()
        .map(|s| SceneRequest::Spec(s.clone()))
        .collect()
}

/// Explicit flags win, then the suite's value, then the default.
fn pick<T>(
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
