//! `raybench report`: draw a report again from its JSON alone (charts, pictures, index.html).

use crate::outdir::{self, OutDir, Output};
use crate::output::render::{Rendered, render};
use crate::pipeline::picture_set::copy_pictures;
use crate::report::run::Report;
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The report.json to draw.
    report: PathBuf,
    /// Output directory (default: the report's own directory, whose earlier drawing is
    /// replaced).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Draw into an --out that holds another drawing, replacing it.
    #[arg(long)]
    force: bool,
}

pub fn run(args: ReportArgs) -> Result<ExitCode> {
    let report = Report::read(&args.report)?;
    let own_dir = args
        .report
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let at_home = args.out.as_ref().is_none_or(|dir| same_dir(dir, &own_dir));
    let claimed = match &args.out {
        // Redrawing a report where it lives replaces its own earlier drawing, but keeps the
        // run's full-resolution pictures in images/.
        None => OutDir::claim(&own_dir, REDRAW, true),
        Some(dir) if at_home => OutDir::claim(dir, REDRAW, true),
        // Elsewhere, a drawing already there belongs to another report, and so would a
        // drawing next to another report.json.
        Some(dir) => {
            anyhow::ensure!(
                !dir.join("report.json").exists(),
                "--out {} holds another report.json: draw this report elsewhere",
                dir.display()
            );
            OutDir::claim(dir, outdir::DRAWING, args.force)
        }
    }
    .context("--out")?;
    let copied = if at_home {
        Vec::new()
    } else {
        copy_pictures(&report.pictures, &own_dir, claimed.path())?
    };
    let mut drawn = render(&report, claimed.path())
        .with_context(|| format!("drawing {}", args.report.display()))?;
    drawn.images.extend(copied);
    print_rendered(&drawn);
    Ok(ExitCode::SUCCESS)
}

/// What redrawing a report in its own directory replaces: the drawing, not `images/`, which
/// holds the run's full-resolution pictures (the small pictures drawn there are overwritten
/// under the same names).
const REDRAW: &[Output] = &[Output::File("index.html"), Output::Dir("charts")];

/// Whether two paths name one directory (both exist once claimed; compared canonically).
fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// One line naming what was drawn.
pub(crate) fn print_rendered(r: &Rendered) {
    println!(
        "page: {} ({} charts, {} images)",
        raybench_scenes::printable(&r.index.display().to_string()),
        r.charts.len(),
        r.images.len()
    );
}
