//! The criterion bench shape every family shares: building on the Stanford bunny and tracing
//! 100k seeded random rays through it, per named variant.

use criterion::{BenchmarkId, Criterion, Throughput};
use raybench_accel::Accel;
use raybench_scenes::Scene;
use std::hint::black_box;
use std::sync::Arc;

/// The bunny from `../shared/scenes`, or — saying so on stderr — a generated teapot of the
/// same size when the folder is absent (a fresh clone), so the benches always run.
pub fn bench_scene() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/stanford-bunny.obj"
    );
    raybench_scenes::load_obj(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("bench: the bunny is not available ({e}); using teapot:triangles=69451");
        raybench_scenes::generate("teapot:triangles=69451", 1).expect("teapot generates")
    })
}

/// Two criterion groups, `{prefix}-build-bunny` over `build` and `{prefix}-random-100k-bunny`
/// over `trace`; each variant is `(label, params)`. Ten samples each: builds are long.
pub fn build_and_trace<A: Accel + 'static>(
    c: &mut Criterion,
    prefix: &str,
    build: &[(String, A::Params)],
    trace: &[(String, A::Params)],
) {
    let scene = bench_scene();
    let mut group = c.benchmark_group(format!("{prefix}-build-bunny"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(scene.mesh.len() as u64));
    for (label, params) in build {
        group.bench_with_input(BenchmarkId::from_parameter(label), params, |b, p| {
            b.iter(|| black_box(A::build(Arc::clone(&scene.mesh), p).expect("builds")))
        });
    }
    group.finish();
    let rays = raybench_scenes::random_rays(&scene.mesh.bounds(), 100_000, 1);
    let mut group = c.benchmark_group(format!("{prefix}-random-100k-bunny"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    for (label, params) in trace {
        let accel = A::build(Arc::clone(&scene.mesh), params).expect("builds");
        group.bench_function(label.as_str(), |b| {
            b.iter(|| rays.iter().filter(|r| accel.intersect(r).is_some()).count())
        });
    }
    group.finish();
}
