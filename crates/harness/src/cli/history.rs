//! `raybench history REPORT...|DIR...`: reports from several commits as one static page and a
//! Markdown summary (see [`crate::output::history`]).

use crate::atomic::write_atomic;
use crate::output::history::{Entry, markdown, order, page, series};
use crate::report::run::Report;
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The most reports one history reads.
const MAX_REPORTS: usize = 1000;

#[derive(Args, Debug)]
pub struct HistoryArgs {
    /// Report files, or directories searched for `report.json` (in them and one level down).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Where to write `index.html` and `history.md` (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// Events listed in the Markdown summary (the page lists all).
    #[arg(long, default_value_t = 50)]
    max_events: usize,
}

pub fn run(args: HistoryArgs) -> Result<ExitCode> {
    anyhow::ensure!(
        args.max_events <= 1_000_000,
        "--max-events must be at most 1000000 (got {})",
        args.max_events
    );
    let mut paths = Vec::new();
    for input in &args.inputs {
        let meta = std::fs::metadata(input)
            .with_context(|| format!("history input {}", input.display()))?;
        if meta.is_dir() {
            let found = reports_in(input)?;
            anyhow::ensure!(
                !found.is_empty(),
                "history input {}: no report.json in it or one level down",
                input.display()
            );
            paths.extend(found);
        } else {
            paths.push(input.clone());
        }
    }
    anyhow::ensure!(
        paths.len() <= MAX_REPORTS,
        "history: {} reports; at most {MAX_REPORTS}",
        paths.len()
    );
    let mut entries = Vec::new();
    for path in paths {
        let report = Report::read(&path)?;
        entries.push(Entry { path, report });
    }
    let entries = order(entries);
    let series = series(&entries);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating --out {}", args.out.display()))?;
    let md = markdown(&entries, &series, args.max_events);
    write_atomic(&args.out.join("history.md"), md.as_bytes())?;
    write_atomic(
        &args.out.join("index.html"),
        page(&entries, &series).as_bytes(),
    )?;
    print!("{md}");
    eprintln!(
        "history: {} and {}",
        args.out.join("history.md").display(),
        args.out.join("index.html").display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `dir/report.json` and `dir/*/report.json`, sorted by path.
fn reports_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    let direct = dir.join("report.json");
    if direct.is_file() {
        found.push(direct);
    }
    let mut subdirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    subdirs.sort();
    found.extend(
        subdirs
            .into_iter()
            .map(|d| d.join("report.json"))
            .filter(|p| p.is_file()),
    );
    Ok(found)
}
