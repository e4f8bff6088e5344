//! Criterion benches: building on the bunny and tracing 100k random rays through it, per
//! variant. Skips (and says so) when ../shared/scenes is absent. `cargo bench -p raybench-kdtree`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use raybench_accel::Accel;
use raybench_kdtree::{KdParams, KdTree};
use raybench_scenes::Scene;
use std::hint::black_box;
use std::sync::Arc;

fn bunny() -> Option<Scene> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/stanford-bunny.obj"
    );
    match raybench_scenes::load_obj(std::path::Path::new(path)) {
        Ok(s) => Some(s),
        Err(e) => {
            eprintln!("bench: SKIPPED, the bunny is not available ({e})");
            None
        }
    }
}

fn variants() -> [KdParams; 2] {
    [KdParams::sah(), KdParams::median()]
}

fn build(c: &mut Criterion) {
    let Some(scene) = bunny() else { return };
    let mut group = c.benchmark_group("kdtree-build-bunny");
    group.sample_size(10);
    group.throughput(Throughput::Elements(scene.mesh.len() as u64));
    for params in variants() {
        group.bench_with_input(
            BenchmarkId::from_parameter(params.name()),
            &params,
            |b, p| b.iter(|| black_box(KdTree::build(Arc::clone(&scene.mesh), p).expect("builds"))),
        );
    }
    group.finish();
}

fn trace(c: &mut Criterion) {
    let Some(scene) = bunny() else { return };
    let rays = raybench_scenes::random_rays(&scene.mesh.bounds(), 100_000, 1);
    let mut group = c.benchmark_group("kdtree-random-100k-bunny");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    for params in variants().into_iter().chain([KdParams {
        mailbox: false,
        ..KdParams::sah()
    }]) {
        let kd = KdTree::build(Arc::clone(&scene.mesh), &params).expect("builds");
        group.bench_function(params.name(), |b| {
            b.iter(|| rays.iter().filter(|r| kd.intersect(r).is_some()).count())
        });
    }
    group.finish();
}

criterion_group!(benches, build, trace);
criterion_main!(benches);
