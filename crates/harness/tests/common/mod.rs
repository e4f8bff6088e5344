//! Shared by the harness's integration tests.
#![allow(dead_code)]

use raybench_harness::pipeline::run::RunOptions;
use raybench_scenes::Workload;

/// A quick, explicit run: every ray workload, 3000 rays (500 points if a test adds a point workload), one thread, one build and one trace pass,
/// against embree-medium. Tests override what they need with struct update syntax.
pub fn options(structures: &[&str]) -> RunOptions {
    RunOptions {
        suite: None,
        structures: structures.iter().map(|s| s.to_string()).collect(),
        workloads: Workload::RAYS.to_vec(),
        rays: 3000,
        points: 500,
        threads: 1,
        reference: "embree-medium".into(),
        seed: 7,
        build_runs: 1,
        trace_runs: 1,
        ftz_daz: false,
        progress: false,
        images: true,
        dump_hits: None,
    }
}
