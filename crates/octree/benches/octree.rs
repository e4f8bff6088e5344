//! Criterion benches: building on the bunny and tracing 100k random rays through it, per
//! MAX_OBJ setting. Falls back to a generated teapot of the bunny's size when ../shared/scenes
//! is absent (and says so). `cargo bench -p raybench-octree`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use raybench_accel::Accel;
use raybench_octree::{Octree, OctreeParams};
use raybench_scenes::Scene;
use std::hint::black_box;
use std::sync::Arc;

fn bunny() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/stanford-bunny.obj"
    );
    raybench_scenes::load_obj(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("bench: the bunny is not available ({e}); using teapot:triangles=69451");
        raybench_scenes::generate("teapot:triangles=69451", 1).expect("teapot generates")
    })
}

fn variants() -> [OctreeParams; 3] {
    let d = OctreeParams::default();
    [
        OctreeParams {
            max_obj: 4,
            ..d.clone()
        },
        d.clone(),
        OctreeParams { max_obj: 16, ..d },
    ]
}

fn build(c: &mut Criterion) {
    let scene = bunny();
    let mut group = c.benchmark_group("octree-build-bunny");
    group.sample_size(10);
    group.throughput(Throughput::Elements(scene.mesh.len() as u64));
    for params in variants() {
        group.bench_with_input(
            BenchmarkId::from_parameter(params.name()),
            &params,
            |b, p| b.iter(|| black_box(Octree::build(Arc::clone(&scene.mesh), p).expect("builds"))),
        );
    }
    group.finish();
}

fn trace(c: &mut Criterion) {
    let scene = bunny();
    let rays = raybench_scenes::random_rays(&scene.mesh.bounds(), 100_000, 1);
    let mut group = c.benchmark_group("octree-random-100k-bunny");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    for params in variants() {
        let tree = Octree::build(Arc::clone(&scene.mesh), &params).expect("builds");
        group.bench_function(params.name(), |b| {
            b.iter(|| rays.iter().filter(|r| tree.intersect(r).is_some()).count())
        });
    }
    group.finish();
}

criterion_group!(benches, build, trace);
criterion_main!(benches);
