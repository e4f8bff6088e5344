//! `raybench run`: build, time, count and check every structure; write report.json and draw it.

// The doc comments are clap help text, where `<date>` is a placeholder, not HTML.
#![allow(rustdoc::invalid_html_tags)]

use super::report::print_rendered;
use super::{DEFAULT_POINTS, Defaults, Selection, claim_outputs, exit_status};
use crate::outdir;
use crate::output::render::render;
use crate::output::summary::summary_table;
use crate::pipeline::picture;
use crate::pipeline::run::{RunOptions, run_with};
use crate::registry::Registry;
use crate::report::run::Report;
use anyhow::Result;
use clap::Args;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Structures default to the suite's, or to every registered one.
    #[command(flatten)]
    selection: Selection,
    /// The structure every answer is checked against and every ratio is relative to.
    #[arg(long, default_value = "embree-medium")]
    reference: String,
    /// Timed builds after one warm-up build (1 to 1000).
    #[arg(long, default_value_t = 3, value_parser = super::bounds::runs)]
    build_runs: usize,
    /// Timed trace passes after one warm-up pass (1 to 1000).
    #[arg(long, default_value_t = 5, value_parser = super::bounds::runs)]
    trace_runs: usize,
    /// Output directory (default: a new reports/<date>-<revision>[-N]).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the report, drawing and dumps of an earlier run in --out and --dump-hits
    /// (without it, such a directory is refused).
    #[arg(long)]
    force: bool,
    /// Leave every per-pixel picture of primary rays out: no picture pass, no PNG files, no
    /// small planes in the report (smaller and quicker; for baselines).
    #[arg(long)]
    no_images: bool,
    /// Width in pixels of the full-resolution pictures (64 to 4096; the height is 3/4 of it),
    /// drawn by an untimed pass from the primary workload's view into <out>/images.
    #[arg(long, value_name = "W", default_value_t = picture::DEFAULT_WIDTH, value_parser = picture_width)]
    picture_width: u32,
    /// Write every ray and each structure's answer here (see docs/report-format.md, "Hit dumps").
    #[arg(long)]
    dump_hits: Option<PathBuf>,
    /// Finish the interrupted run in DIR: the scenes its report.json lists as remaining, with
    /// the settings it records (no other selection flag is taken), merged into that report.
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// After the fixed rounds, keep timing a structure in extra rounds while one of its ratios
    /// to the reference has a confidence interval wider than ±2 %, until its passes on the
    /// scene have taken this many seconds (at most 1,000 rounds).
    #[arg(long, value_name = "SECONDS", value_parser = super::bounds::seconds)]
    time_budget: Option<f64>,
}

pub fn run(registry: &Registry, args: RunArgs) -> Result<ExitCode> {
    if let Some(dir) = args.resume.clone() {
        return resume(registry, &args, &dir);
    }
    let defaults = Defaults {
        structures: registry.names(),
        rays: 100_000,
        points: DEFAULT_POINTS,
    };
    let r = args.selection.resolve(registry, true, defaults)?;
    if !args.no_images {
        check_picture_memory(args.picture_width, r.structures.len())?;
    }
    registry.find(&args.reference)?;
    let claimed = claim_outputs(
        args.out.as_deref(),
        outdir::RUN,
        args.dump_hits.as_deref(),
        args.force,
    )?;
    let dir = claimed.out.path();
    let sel = &args.selection;
    let opts = RunOptions {
        suite: sel.suite.clone(),
        structures: r.structures,
        // Structures the user did not name (a suite's list, or every structure) keep their
        // suite limits: brute force over a million triangles, which nobody asked for by name,
        // would take hours.
        suite_limits: sel.structures.is_empty(),
        workloads: r.workloads,
        rays: r.rays,
        points: r.points,
        threads: sel.threads,
        reference: args.reference,
        seed: r.seed,
        build_runs: args.build_runs,
        trace_runs: args.trace_runs,
        time_budget: args.time_budget.map(std::time::Duration::from_secs_f64),
        ftz_daz: sel.ftz_daz,
        progress: std::io::stdout().is_terminal(),
        images: !args.no_images,
        dump_hits: args.dump_hits.clone(),
        picture_dir: Some(dir.to_path_buf()),
        picture_width: args.picture_width,
    };
    crate::interrupt::stop_gracefully();
    let report = run_with(registry, &opts, &r.requests)?;
    finish(report, dir, args.dump_hits.as_deref())
}

/// Writes the report; an interrupted one is written as it is, marked incomplete, and nothing
/// is drawn (exit 130); a complete one is summarised and drawn.
fn finish(report: Report, dir: &Path, dump_hits: Option<&Path>) -> Result<ExitCode> {
    let path = report.write_atomic(dir)?;
    if let Some(inc) = &report.incomplete {
        eprintln!(
            "raybench: interrupted: {} written with the {} finished scene(s), marked incomplete \
             ({} scene request(s) left); nothing drawn. Finish it with: raybench run --resume {}",
            path.display(),
            report.scenes.len(),
            inc.remaining.len(),
            dir.display()
        );
        return Ok(ExitCode::from(130));
    }
    print!("{}", summary_table(&report));
    println!(
        "report: {}",
        raybench_scenes::printable(&path.display().to_string())
    );
    if let Some(d) = dump_hits {
        println!(
            "hit dumps: {}",
            raybench_scenes::printable(&d.display().to_string())
        );
    }
    // The report is safe on disk first: a drawing failure is reported and fails the command
    // (exit 1 unless a mismatch says 2), but never loses the report.
    let drawn = match render(&report, dir) {
        Ok(mut r) => {
            let pictures = report.pictures.iter().flat_map(|p| p.files());
            r.images.extend(pictures.map(|f| dir.join(f)));
            print_rendered(&r);
            true
        }
        Err(e) => {
            eprintln!(
                "raybench: error: drawing the report failed ({} is kept): {e:#}",
                path.display()
            );
            false
        }
    };
    if report.mismatches() > 0 {
        eprintln!(
            "raybench: {} mismatches against {}",
            report.mismatches(),
            report.run.reference
        );
    }
    Ok(exit_status(
        report.mismatches(),
        report.errors.len() + usize::from(!drawn),
    ))
}

/// `--picture-width`: a whole number of pixels within [`picture::MIN_WIDTH`] and
/// [`picture::MAX_WIDTH`].
/// `--resume DIR`: runs what DIR/report.json lists as remaining, with its settings, and merges
/// the new scenes into it.
fn resume(registry: &Registry, args: &RunArgs, dir: &Path) -> Result<ExitCode> {
    let sel = &args.selection;
    let given = [
        ("--suite", sel.suite.is_some()),
        ("--scenes", !sel.scenes.is_empty()),
        ("--structures", !sel.structures.is_empty()),
        ("--workloads", !sel.workloads.is_empty()),
        ("--rays", sel.rays.is_some()),
        ("--points", sel.points.is_some()),
        ("--out", args.out.is_some()),
        ("--dump-hits", args.dump_hits.is_some()),
        ("--force", args.force),
        ("--time-budget", args.time_budget.is_some()),
    ];
    if let Some((flag, _)) = given.iter().find(|(_, on)| *on) {
        anyhow::bail!(
            "--resume takes every setting from {}/report.json: drop {flag}",
            dir.display()
        );
    }
    let path = dir.join("report.json");
    let done = Report::read(&path)?;
    let Some(incomplete) = done.incomplete.clone() else {
        anyhow::bail!("--resume {}: {} is complete", dir.display(), path.display());
    };
    let (was, now) = (
        &done.header.environment.git_revision,
        crate::env::git_revision(),
    );
    anyhow::ensure!(
        was == now,
        "--resume {}: the report was written by revision {was} and this raybench is {now}; \
         one report cannot mix two builds",
        dir.display()
    );
    let claimed = outdir::OutDir::claim_to_resume(dir)?;
    let rs = &done.run;
    let workloads = rs
        .workloads
        .iter()
        .map(|w| w.parse())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| anyhow::anyhow!("--resume {}: {e}", path.display()))?;
    let opts = RunOptions {
        suite: rs.suite.clone(),
        structures: rs.structures.clone(),
        suite_limits: rs.suite_limits,
        workloads,
        rays: rs.rays,
        points: rs.points.max(1),
        threads: rs.threads,
        reference: rs.reference.clone(),
        seed: rs.seed,
        build_runs: rs.build_runs,
        trace_runs: rs.trace_runs,
        time_budget: rs.time_budget_s.map(std::time::Duration::from_secs_f64),
        ftz_daz: rs.ftz_daz,
        progress: std::io::stdout().is_terminal(),
        images: rs.images,
        dump_hits: None,
        picture_dir: Some(claimed.path().to_path_buf()),
        picture_width: if rs.picture_width == 0 {
            picture::DEFAULT_WIDTH
        } else {
            rs.picture_width
        },
    };
    let requests: Vec<_> = incomplete.remaining.iter().map(Into::into).collect();
    crate::interrupt::stop_gracefully();
    let more = run_with(registry, &opts, &requests)?;
    finish(merge(done, more), claimed.path(), None)
}

/// The finished part of an interrupted run followed by the run that finished it: one report
/// with the first run's header, incomplete only if the second was interrupted too. Ratios are
/// per scene, so each part's stand; the claims are decided again on the whole.
fn merge(mut done: Report, more: Report) -> Report {
    done.scenes.extend(more.scenes);
    done.results.extend(more.results);
    done.notes.extend(more.notes);
    done.errors.extend(more.errors);
    done.pictures.extend(more.pictures);
    done.notes.push(format!(
        "resumed at {} (revision {}) after an interruption",
        more.header.environment.timestamp, more.header.environment.git_revision
    ));
    done.incomplete = more.incomplete;
    done.claims = crate::report::claims::evaluate(&done)
        .into_iter()
        .map(|e| e.claim)
        .collect();
    done
}

fn picture_width(text: &str) -> Result<u32, String> {
    let (lo, hi) = (picture::MIN_WIDTH, picture::MAX_WIDTH);
    match text.trim().parse::<u64>() {
        Ok(w) if (u64::from(lo)..=u64::from(hi)).contains(&w) => Ok(w as u32),
        Ok(_) => Err(format!(
            "must be {lo} to {hi} pixels (the height is three quarters of the width)"
        )),
        Err(_) => Err(format!(
            "must be a whole number of pixels from {lo} to {hi}"
        )),
    }
}

/// Refuses a picture width whose per-scene pictures would not fit in half of this machine's
/// memory, before any work.
fn check_picture_memory(width: u32, structures: usize) -> Result<()> {
    let need = picture::picture_bytes(width, structures);
    let have = crate::memory::physical();
    anyhow::ensure!(
        need <= have / 2,
        "--picture-width {width} needs about {} per scene with {structures} structures, \
         more than half of this machine's {}: give a smaller width or --no-images",
        crate::memory::gib(need as f64),
        crate::memory::gib(have as f64)
    );
    Ok(())
}
