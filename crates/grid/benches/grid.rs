//! Criterion benches (the testkit's shared pair): building on the bunny and tracing 100k random
//! rays through it, per density preset. `cargo bench -p raybench-grid`.

use criterion::{Criterion, criterion_group, criterion_main};
use raybench_grid::{Grid, GridParams};
use raybench_testkit::bench::build_and_trace;

fn benches(c: &mut Criterion) {
    let variants: Vec<(String, GridParams)> = [
        GridParams::coarse(),
        GridParams::default(),
        GridParams::fine(),
    ]
    .into_iter()
    .map(|p| (p.name(), p))
    .collect();
    build_and_trace::<Grid>(c, "grid", &variants, &variants);
}

criterion_group!(group, benches);
criterion_main!(group);
