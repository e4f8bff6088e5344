//! `raybench`: list what can be measured, run measurements into a validated JSON report, and
//! look at scenes (`raybench scene list|export|preview`).

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use raybench_harness::registry;
use raybench_harness::run::{RunOptions, SceneRequest, run, suite_requests};
use raybench_harness::scene_cmd;
use raybench_harness::summary::summary_table;
use raybench_scenes::Workload;
use std::io::{IsTerminal, Write};
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
    /// Look at scenes: list generators and views, export as OBJ, render a preview PNG.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Draw a report: SVG charts, per-pixel PNG pictures and index.html (from report.json alone).
    Report(ReportArgs),
    /// Compare two reports: a Markdown table of changes; exit 2 on a regression (a mismatch
    /// rose, a deterministic figure changed, a timing ratio worsened beyond --max-slowdown).
    Compare(CompareArgs),
}

#[derive(Args, Debug)]
struct ReportArgs {
    /// The report.json to draw.
    report: PathBuf,
    /// Output directory (default: the report's own directory).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct CompareArgs {
    /// The baseline report.json.
    base: PathBuf,
    /// The report.json to judge.
    new: PathBuf,
    /// A timing ratio to the reference worse by more than this percentage is a regression.
    #[arg(long, default_value_t = 10.0)]
    max_slowdown: f64,
    /// Print timing slowdowns without failing on them (for CI on shared machines).
    #[arg(long)]
    timing_advisory: bool,
}

#[derive(Subcommand, Debug)]
enum SceneCommand {
    /// Every generator (parameters, named views) and the real OBJ scenes.
    List,
    /// Write a scene as a Wavefront OBJ file (loads back bit for bit).
    Export(ExportArgs),
    /// Render a shaded picture of a scene from its camera (traced with Embree) as a PNG.
    Preview(PreviewArgs),
}

#[derive(Args, Debug)]
struct ExportArgs {
    /// A generator spec (teapot, grass:density=500) or an .obj path.
    name: String,
    /// Sets the generator's `triangles` parameter (an error for generators without one).
    #[arg(long)]
    triangles: Option<u64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The OBJ file to write (atomically: a temporary file, then a rename).
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct PreviewArgs {
    /// A generator spec (teapot, grass:density=500) or an .obj path.
    name: String,
    /// A named view of the scene (see `raybench scene list`); default: the scene's default.
    #[arg(long)]
    view: Option<String>,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The PNG file to write (atomically: a temporary file, then a rename).
    #[arg(long)]
    out: PathBuf,
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
    /// Leave the per-pixel pictures of primary rays out of the report (smaller; for baselines).
    #[arg(long)]
    no_images: bool,
}

fn main() -> ExitCode {
    match real_main() {
        Ok(code) => code,
        // `raybench list | head`: the reader left; nothing went wrong.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            ExitCode::SUCCESS
        }
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
        Command::Scene(cmd) => scene_command(cmd).map(|_| ExitCode::SUCCESS),
        Command::Compare(args) => compare_command(args),
        Command::Report(args) => report_command(args).map(|_| ExitCode::SUCCESS),
    }
}

fn report_command(args: ReportArgs) -> Result<()> {
    let report = raybench_harness::report::Report::read(&args.report)?;
    let dir = match args.out {
        Some(d) => d,
        None => args
            .report
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_else(|| PathBuf::from(".")),
    };
    print_rendered(&raybench_harness::render::render(&report, &dir)?);
    Ok(())
}

fn print_rendered(r: &raybench_harness::render::Rendered) {
    println!(
        "page: {} ({} charts, {} images)",
        r.index.display(),
        r.charts.len(),
        r.images.len()
    );
}

fn compare_command(args: CompareArgs) -> Result<ExitCode> {
    use raybench_harness::compare::{CompareOptions, compare};
    use raybench_harness::report::Report;
    anyhow::ensure!(
        args.max_slowdown.is_finite() && args.max_slowdown >= 0.0,
        "--max-slowdown must be a percentage >= 0 (got {})",
        args.max_slowdown
    );
    let base = Report::read(&args.base)?;
    let new = Report::read(&args.new)?;
    let opts = CompareOptions {
        max_slowdown: args.max_slowdown / 100.0,
        timing_advisory: args.timing_advisory,
    };
    let c = compare(&base, &new, &opts);
    print!("{}", c.markdown);
    Ok(if c.regressions() > 0 {
        eprintln!("raybench compare: {} regression(s)", c.regressions());
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    })
}

fn scene_command(cmd: SceneCommand) -> Result<()> {
    match cmd {
        SceneCommand::List => scene_cmd::list(&mut std::io::stdout().lock())?,
        SceneCommand::Export(a) => {
            let s = scene_cmd::export(&a.name, a.triangles, a.seed, &a.out)?;
            for note in &s.notes {
                eprintln!("note: {note}");
            }
            if s.renumbered {
                eprintln!(
                    "note: vertices renumbered in order of first use ({} unused dropped), as \
                     OBJ loaders read them back; triangle order is unchanged",
                    s.unused_vertices
                );
            }
            println!(
                "{}: {} vertices, {} triangles ({}, seed {})",
                a.out.display(),
                s.vertices,
                s.triangles,
                s.spec,
                a.seed
            );
        }
        SceneCommand::Preview(a) => {
            let start = std::time::Instant::now();
            let s = scene_cmd::preview(
                &a.name,
                a.view.as_deref(),
                a.width,
                a.height,
                a.seed,
                &a.out,
            )?;
            println!(
                "{}: {}×{} of {} ({} triangles), view `{}`, {:.0} % of pixels hit, {:.2} s",
                a.out.display(),
                a.width,
                a.height,
                s.scene,
                s.triangles,
                s.view,
                s.coverage * 100.0,
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
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
    let mut out = std::io::stdout().lock();
    writeln!(out)?;
    scene_cmd::write_generators(&mut out, false)?;
    writeln!(out)?;
    scene_cmd::write_real_scenes(&mut out)?;
    drop(out);
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
        images: !args.no_images,
    };
    let report = run(&opts, &requests)?;
    let dir = args.out.unwrap_or_else(default_out_dir);
    let path = report.write_atomic(&dir)?;
    print!("{}", summary_table(&report));
    println!("report: {}", path.display());
    // The report is safe on disk first: a drawing failure is reported, never loses it.
    match raybench_harness::render::render(&report, &dir) {
        Ok(r) => print_rendered(&r),
        Err(e) => eprintln!("raybench: drawing the report failed: {e:#}"),
    }
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
    join_spec_parameters(scenes)
        .into_iter()
        .map(SceneRequest::Spec)
        .collect()
}

/// `--scenes` is split on commas, and so are a spec's parameters: `offset:triangles=500,offset=1e7`
/// arrives as `offset:triangles=500` and `offset=1e7`. A piece that is `key=value` (it has `=`
/// but no `:` and is not an `.obj` path) continues the spec before it.
fn join_spec_parameters(pieces: &[String]) -> Vec<String> {
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

#[cfg(test)]
mod tests {
    use super::join_spec_parameters;

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
