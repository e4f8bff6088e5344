//! `raybench`: list what can be measured, run measurements into a checked JSON report, and
//! look at scenes (`raybench scene list|export|preview`). This file parses the command line and
//! hands each subcommand to its module in `raybench_harness::cli`.

use clap::{Parser, Subcommand};
use raybench_harness::cli;
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
    /// The largest file raybench reads (scenes, suites, reports), e.g. 8G; default 4G.
    #[arg(long, global = true, value_parser = cli::bounds::byte_size)]
    max_input_size: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Scenes, structures, workloads and suites raybench knows.
    List,
    /// Build, time, count and check every answer; write DIR/report.json.
    Run(cli::run::RunArgs),
    /// Look at scenes: list generators and views, export as OBJ, render a preview PNG.
    #[command(subcommand)]
    Scene(cli::scene::SceneCommand),
    /// Draw a report: SVG charts, per-pixel PNG pictures and index.html (from report.json alone).
    Report(cli::report::ReportArgs),
    /// Write a report's figures as a Markdown page: the headline geometric means per structure,
    /// a table per scene and the SAH costs, linked to the report (--headline-only: the headline
    /// table and the agreement sentence alone).
    Results(cli::results::ResultsArgs),
    /// Compare two reports: a Markdown table of changes; exit 2 on a regression (a mismatch
    /// rose, a deterministic figure changed, a timing ratio worsened beyond --max-slowdown).
    Compare(cli::compare::CompareArgs),
    /// Check answers, not speed: every structure (default: all registered) × scene × workload
    /// against embree-medium, embree-robust and brute force; write DIR/verify.json. Exit 0
    /// with no mismatch, 2 on any mismatch, 1 on errors.
    Verify(cli::verify::VerifyArgs),
    /// Trace one ray (bit patterns from a report or from `verify`) through every structure,
    /// the references and a double-precision test over every triangle.
    Replay(cli::replay::ReplayArgs),
    /// Crack hunting: miss rates of rays aimed at the edges and vertices of closed meshes near
    /// and far from the origin, next to Embree's bar for robust mode (2e-5).
    Watertight(cli::watertight::WatertightArgs),
}

fn main() -> ExitCode {
    one_line_panics();
    raybench_harness::interrupt::install();
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
    if let Some(limit) = cli.max_input_size {
        raybench_scenes::input::set_max_input_bytes(limit);
    }
    let outcome = match cli.command {
        Command::List => cli::list::run(),
        Command::Run(args) => cli::run::run(args),
        Command::Scene(cmd) => cli::scene::run(cmd),
        Command::Report(args) => cli::report::run(args),
        Command::Results(args) => cli::results::run(args),
        Command::Compare(args) => cli::compare::run(args),
        Command::Verify(args) => cli::verify::run(args),
        Command::Replay(args) => cli::replay::run(args),
        Command::Watertight(args) => cli::watertight::run(args),
    };
    match outcome {
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
            eprintln!(
                "raybench: error: {}",
                raybench_scenes::printable(&format!("{e:#}"))
            );
            ExitCode::from(1)
        }
    }
}

/// A panic (a bug) prints one line naming where it happened instead of a backtrace prompt;
/// the harness catches panics per structure and records them as errors in the report.
fn one_line_panics() {
    std::panic::set_hook(Box::new(|info| {
        let msg = raybench_harness::pipeline::workers::panic_message(info.payload());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("raybench: internal error{at}: {msg}");
    }));
}
