//! `raybench run`: build, time, count and check every structure; write report.json and draw it.

use super::report::print_rendered;
use super::{
    DEFAULT_POINTS, Defaults, Selection, all_structures, check_outputs, default_out_dir,
    exit_status,
};
use crate::output::render::render;
use crate::output::summary::summary_table;
use crate::pipeline::run::{RunOptions, run as run_pipeline};
use crate::registry;
use anyhow::Result;
use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Structures default to the suite's, or to every registered one.
    #[command(flatten)]
    selection: Selection,
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
    /// Write every ray and each structure's answer here (see docs/report-format.md, "Hit dumps").
    #[arg(long)]
    dump_hits: Option<PathBuf>,
}

pub fn run(args: RunArgs) -> Result<ExitCode> {
    let defaults = Defaults {
        structures: all_structures(),
        rays: 100_000,
        points: DEFAULT_POINTS,
    };
    let r = args.selection.resolve(true, defaults)?;
    registry::find(&args.reference)?;
    let dir = args.out.unwrap_or_else(default_out_dir);
    check_outputs(&dir, args.dump_hits.as_deref())?;
    let sel = &args.selection;
    let opts = RunOptions {
        suite: sel.suite.clone(),
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
    let report = run_pipeline(&opts, &r.requests)?;
    let path = report.write_atomic(&dir)?;
    print!("{}", summary_table(&report));
    println!("report: {}", path.display());
    if let Some(d) = &args.dump_hits {
        println!("hit dumps: {}", d.display());
    }
    // The report is safe on disk first: a drawing failure is reported, never loses it.
    match render(&report, &dir) {
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
    Ok(exit_status(report.mismatches(), report.errors.len()))
}
