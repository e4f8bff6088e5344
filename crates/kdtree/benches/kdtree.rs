//! Criterion benches (the testkit's shared pair): building on the bunny and tracing 100k random
//! rays through it, per variant, and the SAH tree without its mailbox. `cargo bench -p
//! raybench-kdtree`.

use criterion::{Criterion, criterion_group, criterion_main};
use raybench_kdtree::{KdParams, KdTree};
use raybench_testkit::bench::build_and_trace;

fn benches(c: &mut Criterion) {
    let variants: Vec<(String, KdParams)> = [KdParams::sah(), KdParams::median()]
        .into_iter()
        .map(|p| (p.name(), p))
        .collect();
    let mut traversals = variants.clone();
    traversals.push((
        "kd-sah-no-mailbox".into(),
        KdParams {
            mailbox: false,
            ..KdParams::sah()
        },
    ));
    build_and_trace::<KdTree>(c, "kdtree", &variants, &traversals);
}

criterion_group!(group, benches);
criterion_main!(group);
