//! `raybench`: list what can be measured, run measurements into a validated JSON report, and
//! look at scenes (`raybench scene list|export|preview`).

use anyhow::Result;
use clap::{Args, Parser, Subcommand};
use raybench_harness::cli;
use raybench_harness::registry;
use raybench_harness::run::{RunOptions, run};
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
    /// Check answers, not speed: every structure (default: all registered) × scene × workload
    /// against embree-medium, embree-robust and brute force; write DIR/verify.json. Exit 0
    /// with no mismatch, 2 on any mismatch, 1 on errors.
    Verify(cli::VerifyArgs),
    /// Trace one ray (bit patterns from a report or from `verify`) through every structure,
    /// the references and a double-precision test over every triangle.
    Replay(cli::ReplayArgs),
    /// Crack hunting: miss rates of rays aimed at the edges and vertices of closed meshes near
    /// and far from the origin, next to Embree's bar for robust mode (2e-5).
    Watertight(cli::WatertightArgs),
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
    /// Structures default to the suite's, or to every registered one.
    #[command(flatten)]
    selection: cli::Selection,
    /// The structure every answer is checked against and every ratio is relative to.
    #[arg(long, default_value = "embree-medium")]
    reference: String,
    /// Timed builds after one warm-up build.
    #[arg(long, default_value_t = 3)]
    build_runs: usize,
    /// Timed trace passes after one warm-up pass.
    #[arg(long, default_value_t = 5)]
    trace_runs: usize,
    /// Output directory (default: reports/<date>-<revision>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Leave the per-pixel pictures of primary rays out of the report (smaller; for baselines).
    #[arg(long)]
    no_images: bool,
    /// Write every ray and each structure's answer here (see README, "Hit dumps").
    #[arg(long)]
    dump_hits: Option<PathBuf>,
}

fn main() -> ExitCode {
    one_line_panics();
    // Usage errors exit 1 like every other error: 2 means "mismatch" to scripts.
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(1)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    match real_main(cli) {
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

/// A panic (a bug) prints one line naming where it happened instead of a backtrace prompt;
/// the harness catches panics per structure and records them as errors in the report.
fn one_line_panics() {
    std::panic::set_hook(Box::new(|info| {
        let msg = raybench_harness::run::panic_message(info.payload());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("raybench: internal error{at}: {msg}");
    }));
}

fn real_main(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Verify(args) => cli::verify_command(args),
        Command::Replay(args) => cli::replay_command(args),
        Command::Watertight(args) => cli::watertight_command(args),
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
            "  {stem:<24} {} ({} scenes, {} rays{})",
            suite.description,
            suite.scenes.len(),
            suite.rays,
            suite
                .points
                .map(|p| format!(", {p} points"))
                .unwrap_or_default()
        );
    }
    Ok(())
}

fn run_command(args: RunArgs) -> Result<ExitCode> {
    let defaults = cli::Defaults {
        structures: cli::all_structures(),
        rays: 100_000,
        points: cli::DEFAULT_POINTS,
    };
    let r = args.selection.resolve(true, defaults)?;
    registry::find(&args.reference)?;
    let dir = args.out.unwrap_or_else(cli::default_out_dir);
    cli::check_outputs(&dir, args.dump_hits.as_deref())?;
    let sel = &args.selection;
    let opts = RunOptions {
        suite: sel.suite.clone(),
        scenes: r.requests.iter().map(|r| format!("{r:?}")).collect(),
        structures: r.structures,
        workloads: r.workloads,
        rays: r.rays,
        points: r.points,
        threads: sel.threads,
        reference: args.reference,
        seed: sel.seed,
        build_runs: args.build_runs,
        trace_runs: args.trace_runs,
        ftz_daz: sel.ftz_daz,
        progress: std::io::stdout().is_terminal(),
        images: !args.no_images,
        dump_hits: args.dump_hits.clone(),
    };
    let report = run(&opts, &r.requests)?;
    let path = report.write_atomic(&dir)?;
    print!("{}", summary_table(&report));
    println!("report: {}", path.display());
    if let Some(d) = &args.dump_hits {
        println!("hit dumps: {}", d.display());
    }
    // The report is safe on disk first: a drawing failure is reported, never loses it.
    match raybench_harness::render::render(&report, &dir) {
        Ok(r) => print_rendered(&r),
        Err(e) => eprintln!("raybench: drawing the report failed: {e:#}"),
    }
    if report.mismatches() > 0 {
        eprintln!(
            "raybench: {} mismatches against {}",
            report.mismatches(),
            report.run.reference
        );
    }
    Ok(cli::exit_status(report.mismatches(), report.errors.len()))
}
