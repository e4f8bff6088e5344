//! `raybench verify`: check answers, not speed, against three references; write verify.json.

// The doc comments are clap help text, where `<date>` is a placeholder, not HTML.
#![allow(rustdoc::invalid_html_tags)]

use super::{DEFAULT_POINTS, Defaults, Selection, budget, claim_outputs, exit_status};
use crate::outdir;
use crate::output::verify_table::verify_table;
use crate::pipeline::verify::{BRUTE_FORCE_BUDGET, VerifyOptions, verify_with};
use crate::registry::Registry;
use anyhow::Result;
use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub selection: Selection,
    /// Output directory for verify.json (default: a new reports/<date>-<revision>[-N]).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the verify.json and dumps of an earlier command in --out and --dump-hits.
    #[arg(long)]
    pub force: bool,
    /// Write every ray and each structure's answer here (see docs/report-format.md, "Hit dumps").
    #[arg(long)]
    pub dump_hits: Option<PathBuf>,
    /// Ray–triangle tests brute force may spend per scene × workload (it checks an evenly
    /// spaced subsample when a workload would cost more).
    #[arg(long, default_value_t = BRUTE_FORCE_BUDGET, value_parser = budget)]
    pub brute_force_budget: u64,
}

/// `raybench verify`: exit 0 with no mismatch, 2 on any mismatch (or counted-path
/// difference), 1 on errors.
pub fn run(registry: &Registry, args: VerifyArgs) -> Result<ExitCode> {
    // Verify checks every registered structure unless told otherwise: a suite's structure list
    // says what is worth timing, not what may go unchecked. Peers (other crates' structures)
    // only when named: their known failures are findings about those crates, and a gate on
    // raybench's own answers must not fail for them.
    let defaults = Defaults {
        structures: registry
            .entries()
            .iter()
            .filter(|e| !e.peer)
            .map(|e| e.name.to_string())
            .collect(),
        rays: 10_000,
        points: DEFAULT_POINTS,
    };
    let r = args.selection.resolve(registry, false, defaults)?;
    let claimed = claim_outputs(
        args.out.as_deref(),
        outdir::VERIFY,
        args.dump_hits.as_deref(),
        args.force,
    )?;
    let dir = claimed.out.path();
    let opts = VerifyOptions {
        suite: args.selection.suite.clone(),
        structures: r.structures,
        workloads: r.workloads,
        rays: r.rays,
        points: r.points,
        threads: args.selection.threads,
        seed: r.seed,
        ftz_daz: args.selection.ftz_daz,
        progress: std::io::stdout().is_terminal(),
        brute_force_budget: args.brute_force_budget,
        dump_hits: args.dump_hits.clone(),
    };
    let report = verify_with(registry, &opts, &r.requests)?;
    let path = report.write_atomic(dir)?;
    print!("{}", verify_table(&report));
    println!(
        "verify: {}",
        raybench_scenes::printable(&path.display().to_string())
    );
    if let Some(d) = &args.dump_hits {
        println!(
            "hit dumps: {}",
            raybench_scenes::printable(&d.display().to_string())
        );
    }
    Ok(exit_status(report.mismatches(), report.errors.len()))
}
