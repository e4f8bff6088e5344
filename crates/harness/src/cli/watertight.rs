//! `raybench watertight`: crack hunting; write watertight.json and print the miss rates.

// The doc comments are clap help text, where `<date>` is a placeholder, not HTML.
#![allow(rustdoc::invalid_html_tags)]

use super::{at_least_one, budget, exit_status, pick};
use crate::output::watertight_table::watertight_table;
use crate::pipeline::verify::BRUTE_FORCE_BUDGET;
use crate::pipeline::watertight::{WatertightOptions, default_cases, watertight_with};
use crate::registry::Registry;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct WatertightArgs {
    /// Structures, comma-separated (default: every registered one).
    #[arg(long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Rays generated per case.
    #[arg(long, default_value_t = 100_000, value_parser = at_least_one)]
    pub rays: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads for builds and traces; at most 8 per core.
    #[arg(long, default_value_t = 1, value_parser = super::bounds::threads)]
    pub threads: usize,
    /// Output directory for watertight.json (default: a new reports/<date>-<revision>[-N]).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the watertight.json of an earlier command in --out.
    #[arg(long)]
    pub force: bool,
    /// Ray–triangle tests brute force may spend per case (it traces an evenly spaced subsample).
    #[arg(long, default_value_t = BRUTE_FORCE_BUDGET, value_parser = budget)]
    pub brute_force_budget: u64,
}

/// `raybench watertight`: exit 0, or 1 on errors (a crack is a figure, not a failure).
pub fn run(registry: &Registry, args: WatertightArgs) -> Result<ExitCode> {
    let structures = pick(args.structures, None, || registry.names());
    registry.select(&structures)?;
    super::no_duplicates("--structures", structures.iter().cloned())?;
    super::bounds::check_rays(args.rays, 1, false)?;
    let claimed = super::claim_outputs(
        args.out.as_deref(),
        crate::outdir::WATERTIGHT,
        None,
        args.force,
    )?;
    let dir = claimed.out.path();
    let opts = WatertightOptions {
        cases: default_cases(),
        structures,
        rays: args.rays,
        seed: args.seed,
        threads: args.threads,
        brute_force_budget: args.brute_force_budget,
    };
    let report = watertight_with(registry, &opts)?;
    let path = report.write_atomic(dir)?;
    print!("{}", watertight_table(&report));
    println!(
        "watertight: {}",
        raybench_scenes::printable(&path.display().to_string())
    );
    Ok(exit_status(0, report.errors.len()))
}
