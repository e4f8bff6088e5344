//! `raybench replay`: one ray, given as bit patterns, through every structure, the references
//! and a double-precision test over every triangle.

use crate::output::replay_text::replay_text;
use crate::pipeline::replay::{parse_ray_bits, replay_with};
use crate::registry::Registry;
use anyhow::{Context, Result};
use clap::Args;
use std::process::ExitCode;

#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// The scene: a generator spec or an .obj path, as printed by `verify`.
    #[arg(long)]
    pub scene: String,
    /// Structures to trace, comma-separated (default: every registered one); the references
    /// embree-medium, embree-robust and bruteforce are always shown.
    #[arg(long, value_delimiter = ',')]
    pub structure: Vec<String>,
    /// The ray: 8 hex f32 bit patterns ox,oy,oz,dx,dy,dz,tmin,tmax (with or without 0x,
    /// separated by commas or spaces), as in a report's `ray_bits`.
    #[arg(long, num_args = 1..=8, required = true)]
    pub ray: Vec<String>,
    /// The seed the scene was generated with.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// `raybench replay`: one ray through every structure, the references and an f64 test.
pub fn run(registry: &Registry, args: ReplayArgs) -> Result<ExitCode> {
    let ray = parse_ray_bits(&args.ray.join(","))?;
    registry.select(&args.structure)?;
    if !args.scene.to_ascii_lowercase().ends_with(".obj") {
        raybench_scenes::check_spec(&args.scene)
            .with_context(|| format!("scene '{}'", args.scene))?;
    }
    let replay = replay_with(registry, &args.scene, &args.structure, ray, args.seed)?;
    print!("{}", replay_text(&replay));
    Ok(ExitCode::SUCCESS)
}
