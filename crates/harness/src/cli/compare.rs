//! `raybench compare`: the diff of two reports as Markdown, JSON or JUnit XML; exit 2 on a
//! regression.

use crate::output::compare_table::{MarkdownLimits, full_table, json, junit, markdown};
use crate::report::compare::{CompareOptions, compare};
use crate::report::run::Report;
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

/// The most rows or findings `--max-rows` and `--max-findings` accept.
const MAX_LIMIT: usize = 1_000_000;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Format {
    /// Verdict, findings and the worst rows, sized for a pull-request comment.
    Md,
    /// Verdict, every finding and every row, for scripts.
    Json,
    /// JUnit XML: a test case per row, failed by its regressions.
    Junit,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The baseline report.json.
    base: PathBuf,
    /// The report.json to judge.
    new: PathBuf,
    /// A structure × workload's geometric-mean ratio to the reference (over the scenes both
    /// reports ran) slower by more than this percentage is a regression, when significant.
    #[arg(long, default_value_t = 10.0)]
    max_slowdown: f64,
    /// The same for one scene's ratio (looser: a run shifts single figures as a whole).
    #[arg(long, default_value_t = 50.0)]
    max_scene_slowdown: f64,
    /// Print timing slowdowns without failing on them.
    #[arg(long)]
    timing_advisory: bool,
    /// The new report ran part of the base on purpose: entries and workloads it lacks are
    /// "not run", not regressions.
    #[arg(long)]
    subset: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Md)]
    format: Format,
    /// Only rows where something changed (counters, mismatches, a ratio beyond the threshold).
    #[arg(long)]
    only_changed: bool,
    /// Markdown: rows shown, worst first.
    #[arg(long, default_value_t = 40)]
    max_rows: usize,
    /// Markdown: findings shown per severity.
    #[arg(long, default_value_t = 25)]
    max_findings: usize,
    /// Also write every row as a Markdown table to this file.
    #[arg(long)]
    full_table: Option<PathBuf>,
    /// When every regression is a timing slowdown, write the structures they concern to this
    /// file, comma-separated, for a second timing of just those (scripts/ci-gate); otherwise
    /// remove the file, so that no list from an earlier comparison is left behind.
    #[arg(long, value_name = "FILE")]
    timing_regressions_to: Option<PathBuf>,
}

pub fn run(args: CompareArgs) -> Result<ExitCode> {
    for (flag, v) in [
        ("--max-slowdown", args.max_slowdown),
        ("--max-scene-slowdown", args.max_scene_slowdown),
    ] {
        anyhow::ensure!(
            v.is_finite() && (0.0..=1e6).contains(&v),
            "{flag} must be a percentage from 0 to 1e6 (got {v})"
        );
    }
    for (flag, v) in [
        ("--max-rows", args.max_rows),
        ("--max-findings", args.max_findings),
    ] {
        anyhow::ensure!(
            v <= MAX_LIMIT,
            "{flag} must be at most {MAX_LIMIT} (got {v})"
        );
    }
    let base = Report::read(&args.base)?;
    let new = Report::read(&args.new)?;
    let opts = CompareOptions {
        max_slowdown: args.max_slowdown / 100.0,
        max_scene_slowdown: args.max_scene_slowdown / 100.0,
        timing_advisory: args.timing_advisory,
        subset: args.subset,
    };
    let c = compare(&base, &new, &opts);
    if let Some(path) = &args.full_table {
        crate::atomic::write_atomic(path, full_table(&c).as_bytes())
            .with_context(|| format!("--full-table {}", path.display()))?;
    }
    if let Some(path) = &args.timing_regressions_to {
        write_timing_regressions(path, c.timing_only())?;
    }
    let text = match args.format {
        Format::Md => {
            let limits = MarkdownLimits {
                max_rows: args.max_rows,
                max_findings: args.max_findings,
                only_changed: args.only_changed,
            };
            let table = args.full_table.as_ref().map(|p| p.display().to_string());
            markdown(&base, &new, &c, &opts, &limits, table.as_deref())
        }
        Format::Json => json(&c, &opts, args.only_changed),
        Format::Junit => junit(&c),
    };
    print!("{text}");
    Ok(if c.regressions() > 0 {
        eprintln!("raybench compare: {} regression(s)", c.regressions());
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    })
}

/// `--timing-regressions-to`: the structures, comma-separated, or no file at all.
fn write_timing_regressions(path: &std::path::Path, structures: Option<Vec<String>>) -> Result<()> {
    let flag = || format!("--timing-regressions-to {}", path.display());
    match structures {
        Some(names) => {
            crate::atomic::write_atomic(path, format!("{}\n", names.join(",")).as_bytes())
                .with_context(flag)
        }
        None => match std::fs::symlink_metadata(path) {
            Ok(m) if m.is_file() => std::fs::remove_file(path).with_context(flag),
            Ok(_) => anyhow::bail!("{}: exists and is not a regular file", flag()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(e).with_context(flag),
        },
    }
}
