//! `raybench results REPORT.json --out FILE.md`: a report's figures as one Markdown page (the
//! pages of docs/results are made with it), or with `--headline-only` just the headline table
//! and the agreement sentence (what the README shows).

use crate::atomic::write_atomic;
use crate::output::results::{against_group, headline, results_page};
use crate::report::run::Report;
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct ResultsArgs {
    /// The report.json to write up.
    report: PathBuf,
    /// The Markdown file to write (atomically); without it the page goes to standard output.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Where the page links the report (default: the report's path relative to the page's
    /// directory).
    #[arg(long)]
    report_link: Option<String>,
    /// Only the headline table and the agreement sentence (to paste into the README).
    #[arg(long)]
    headline_only: bool,
    /// Repeat the headline relative to this structure of the run too (e.g. embree-high);
    /// comma-separated or repeated. Structures joined by `+` are raced as one, the faster of
    /// them on each scene and workload (e.g. embree-medium-stream+embree-medium-packet16).
    #[arg(long, value_delimiter = ',')]
    also_against: Vec<String>,
}

pub fn run(args: ResultsArgs) -> Result<ExitCode> {
    let report = Report::read(&args.report)?;
    for other in &args.also_against {
        let group = against_group(other);
        for (i, name) in group.iter().enumerate() {
            if name.is_empty() {
                anyhow::bail!(
                    "--also-against {other}: an empty structure name (`+` joins two names)"
                );
            }
            if group[..i].contains(name) {
                anyhow::bail!("--also-against {other}: '{name}' is named twice");
            }
            if !report.results.iter().any(|r| r.structure == *name) {
                anyhow::bail!(
                    "--also-against {other}: {} has no results of '{name}'",
                    args.report.display()
                );
            }
        }
    }
    let page_dir = match args.out.as_deref().and_then(Path::parent) {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if args.out.is_some() {
        std::fs::create_dir_all(&page_dir)
            .with_context(|| format!("creating {}", page_dir.display()))?;
    }
    let text = if args.headline_only {
        headline(&report)
    } else {
        let link = match args.report_link {
            Some(link) => link,
            None => relative_link(&args.report, &page_dir)?,
        };
        results_page(&report, &link, &args.also_against)
    };
    match &args.out {
        Some(out) => {
            write_atomic(out, text.as_bytes())?;
            println!("results: {}", out.display());
        }
        None => print!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}

/// The path of `target` as seen from the directory `from`, with `/` separators (a Markdown
/// link), through the real paths of both so that symbolic links and `..` cannot mislead it.
fn relative_link(target: &Path, from: &Path) -> Result<String> {
    let real = |p: &Path| {
        p.canonicalize()
            .with_context(|| format!("resolving {}", p.display()))
    };
    let (target, from) = (real(target)?, real(from)?);
    let t: Vec<Component> = target.components().collect();
    let f: Vec<Component> = from.components().collect();
    let common = t.iter().zip(&f).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); f.len() - common];
    parts.extend(
        t[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    Ok(parts.join("/"))
}

#[cfg(test)]
mod tests {
    use super::relative_link;

    #[test]
    fn links_climb_out_of_the_page_directory_and_into_the_report_s() {
        let root = std::env::temp_dir().join(format!("raybench-link-{}", std::process::id()));
        let report = root.join("reports/2026-01-01-abc/report.json");
        std::fs::create_dir_all(report.parent().unwrap()).unwrap();
        std::fs::write(&report, b"{}").unwrap();
        let docs = root.join("docs/results");
        std::fs::create_dir_all(&docs).unwrap();
        assert_eq!(
            relative_link(&report, &docs).unwrap(),
            "../../reports/2026-01-01-abc/report.json"
        );
        assert_eq!(
            relative_link(&report, report.parent().unwrap()).unwrap(),
            "report.json"
        );
        std::fs::remove_dir_all(root).unwrap();
    }
}
