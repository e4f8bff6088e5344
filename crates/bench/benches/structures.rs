//! Criterion benches of every native family: building on the bunny and tracing 100k seeded
//! random rays through it, per named variant. `cargo bench -p raybench-bench`. The harness's
//! `raybench run` is the benchmark of record (same rays for every structure, checked against
//! Embree); these are for quick local comparisons of one family's variants.

mod common;

use common::build_and_trace;
use criterion::{Criterion, criterion_group, criterion_main};
use raybench_bvh::{Bvh, Bvh8, BvhParams, WideParams};
use raybench_grid::{Grid, GridParams};
use raybench_kdtree::{KdParams, KdTree};
use raybench_octree::{Octree, OctreeParams};

fn named<P: Clone>(params: &[P], name: impl Fn(&P) -> String) -> Vec<(String, P)> {
    params.iter().map(|p| (name(p), p.clone())).collect()
}

fn bvh(c: &mut Criterion) {
    let builders = named(
        &[BvhParams::median(), BvhParams::sweep(), BvhParams::binned()],
        BvhParams::name,
    );
    let mut traversals = builders.clone();
    traversals.extend(named(&[BvhParams::binned_unordered()], BvhParams::name));
    build_and_trace::<Bvh>(c, "bvh", &builders, &traversals);
    let wide = vec![("bvh8-binned".to_string(), WideParams::default())];
    build_and_trace::<Bvh8>(c, "bvh8", &wide, &wide);
}

fn kdtree(c: &mut Criterion) {
    let variants = named(&[KdParams::sah(), KdParams::median()], KdParams::name);
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

fn grid(c: &mut Criterion) {
    let variants = named(
        &[
            GridParams::coarse(),
            GridParams::default(),
            GridParams::fine(),
        ],
        GridParams::name,
    );
    build_and_trace::<Grid>(c, "grid", &variants, &variants);
}

fn octree(c: &mut Criterion) {
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

criterion_group!(group, bvh, kdtree, grid, octree);
criterion_main!(group);
