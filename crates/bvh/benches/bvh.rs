//! Criterion benches (the testkit's shared pair): building on the bunny and tracing 100k random
//! rays through it, per builder. `cargo bench -p raybench-bvh`.

use criterion::{Criterion, criterion_group, criterion_main};
use raybench_bvh::{Bvh, Bvh8, Bvh8Params, BvhParams};
use raybench_testkit::bench::build_and_trace;

fn named(params: Vec<BvhParams>) -> Vec<(String, BvhParams)> {
    params.into_iter().map(|p| (p.name(), p)).collect()
}

fn benches(c: &mut Criterion) {
    let builders = named(vec![
        BvhParams::median(),
        BvhParams::sweep(),
        BvhParams::binned(),
    ]);
    let mut traversals = builders.clone();
    traversals.extend(named(vec![BvhParams::binned_unordered()]));
    build_and_trace::<Bvh>(c, "bvh", &builders, &traversals);
    let wide = vec![("bvh8-binned".to_string(), Bvh8Params::default())];
    build_and_trace::<Bvh8>(c, "bvh8", &wide, &wide);
}

criterion_group!(group, benches);
criterion_main!(group);
