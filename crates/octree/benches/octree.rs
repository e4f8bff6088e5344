//! Criterion benches (the testkit's shared pair): building on the bunny and tracing 100k random
//! rays through it, at MAX_OBJ 4, 8 (the default) and 16. `cargo bench -p raybench-octree`.

use criterion::{Criterion, criterion_group, criterion_main};
use raybench_octree::{Octree, OctreeParams};
use raybench_testkit::bench::build_and_trace;

fn benches(c: &mut Criterion) {
    let variants: Vec<(String, OctreeParams)> = [4, 8, 16]
        .into_iter()
        .map(|max_obj| {
            let p = OctreeParams {
                max_obj,
                ..OctreeParams::default()
            };
            (format!("{}-max-obj-{max_obj}", p.name()), p)
        })
        .collect();
    build_and_trace::<Octree>(c, "octree", &variants, &variants);
}

criterion_group!(group, benches);
criterion_main!(group);
