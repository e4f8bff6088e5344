//! `raybench compare`: the diff of two reports as Markdown; exit 2 on a regression.

use crate::report::compare::{CompareOptions, compare};
use crate::report::run::Report;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct CompareArgs {
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

pub fn run(args: CompareArgs) -> Result<ExitCode> {
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
