//! The whole `raybench` command line as a library function: parses the arguments and hands
//! each subcommand to its module, with the structures of a given [`Registry`]. The stock
//! binary (src/main.rs) and a user's own binary (examples/custom-structure) differ only in the
//! registry they pass.

use crate::registry::Registry;
use clap::{Parser, Subcommand};
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
    #[arg(long, global = true, value_parser = super::bounds::byte_size)]
    max_input_size: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Scenes, structures, workloads and suites raybench knows.
    List,
    /// Build, time, count and check every answer; write DIR/report.json.
    Run(super::run::RunArgs),
    /// Look at scenes: list generators and views, export as OBJ, render a preview PNG.
    #[command(subcommand)]
    Scene(super::scene::SceneCommand),
    /// Draw a report: SVG charts, per-pixel PNG pictures and index.html (from report.json alone).
    Report(super::report::ReportArgs),
    /// Write a report's figures as a Markdown page: the headline geometric means per structure,
    /// a table per scene and the SAH costs, linked to the report (--headline-only: the headline
    /// table and the agreement sentence alone).
    Results(super::results::ResultsArgs),
    /// Compare two reports: the verdict, the findings and the changes (Markdown, JSON or
    /// JUnit); exit 2 on a regression (a mismatch rose, a deterministic figure changed, a
    /// timing ratio slower beyond --max-slowdown and significantly so).
    Compare(super::compare::CompareArgs),
    /// Reports from several commits, oldest first: one static page with a chart per structure
    /// × workload (ratio with its interval, work per query) and a Markdown summary marking
    /// where counters changed or a ratio left its interval.
    History(super::history::HistoryArgs),
    /// Check answers, not speed: every structure (default: all registered but the peers) × scene × workload
    /// against embree-medium, embree-robust and brute force; write DIR/verify.json. Exit 0
    /// with no mismatch, 2 on any mismatch, 1 on errors.
    Verify(super::verify::VerifyArgs),
    /// Trace one ray (bit patterns from a report or from `verify`) through every structure,
    /// the references and a double-precision test over every triangle.
    Replay(super::replay::ReplayArgs),
    /// Crack hunting: miss rates of rays aimed at the edges and vertices of closed meshes near
    /// and far from the origin, next to Embree's bar for robust mode (2e-5).
    Watertight(super::watertight::WatertightArgs),
}

/// Runs the `raybench` command line (arguments from the process) with `registry`: every
/// command that names structures (`run`, `verify`, `replay`, `watertight`, `list`) looks them
/// up there. The stock binary is `main_with(Registry::builtin())`; a program that registers
/// its own structures calls this from its `main` and gets the whole CLI for them. Returns the
/// exit status (0, 1 on errors, 2 on a mismatch or regression: see README, "Exit codes").
pub fn main_with(registry: Registry) -> ExitCode {
    one_line_panics();
    crate::interrupt::install();
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
        Command::List => super::list::run(&registry),
        Command::Run(args) => super::run::run(&registry, args),
        Command::Scene(cmd) => super::scene::run(cmd),
        Command::Report(args) => super::report::run(args),
        Command::Results(args) => super::results::run(args),
        Command::History(args) => super::history::run(args),
        Command::Compare(args) => super::compare::run(args),
        Command::Verify(args) => super::verify::run(&registry, args),
        Command::Replay(args) => super::replay::run(&registry, args),
        Command::Watertight(args) => super::watertight::run(&registry, args),
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
        let msg = crate::pipeline::workers::panic_message(info.payload());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("raybench: internal error{at}: {msg}");
    }));
}
