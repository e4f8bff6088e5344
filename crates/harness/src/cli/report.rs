//! `raybench report`: draw a report again from its JSON alone (charts, pictures, index.html).

use crate::output::render::{Rendered, render};
use crate::report::run::Report;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The report.json to draw.
    report: PathBuf,
    /// Output directory (default: the report's own directory).
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: ReportArgs) -> Result<ExitCode> {
    let report = Report::read(&args.report)?;
    let dir = match args.out {
        Some(d) => d,
        None => args
            .report
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_else(|| PathBuf::from(".")),
    };
    print_rendered(&render(&report, &dir)?);
    Ok(ExitCode::SUCCESS)
}

/// One line naming what was drawn.
pub(crate) fn print_rendered(r: &Rendered) {
    println!(
        "page: {} ({} charts, {} images)",
        r.index.display(),
        r.charts.len(),
        r.images.len()
    );
}
