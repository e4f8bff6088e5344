//! `custom-structure`: the whole `raybench` command line with one more entry, `toy-bvh`
//! (see src/lib.rs). `cargo run --release -p custom-structure -- verify --structures
//! toy-bvh,bvh8-binned --scenes teapot` checks it; `run` times it beside Embree.

use custom_structure::{ToyBvh, ToyParams};
use raybench_harness::Registry;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut registry = Registry::builtin();
    let added = registry.register::<ToyBvh>(
        "toy-bvh",
        "example crate: binary BVH, object median on the widest centroid axis, leaves of up to 4 triangles, unordered stack walk, two-sided Möller–Trumbore",
        ToyParams::default(),
    );
    if let Err(e) = added {
        eprintln!("custom-structure: {e}");
        return ExitCode::from(1);
    }
    raybench_harness::cli::main_with(registry)
}
