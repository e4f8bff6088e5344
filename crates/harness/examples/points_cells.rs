//! Closest-point queries on one scene for the three space-subdivision structures (`kd-sah`,
//! `grid`, `octree`), side by side in one process (this machine is shared and noisy: compare
//! within a run). Points are the benchmark's `points-near` workload (seeded): a random point
//! on a triangle picked in proportion to its area, moved by up to 1 % of the scene's diagonal
//! in a random direction. Each structure is first checked
//! against brute force on the first 1000 points, then timed on one thread (median of the
//! runs, by the wall clock and by the thread's on-CPU time), then walked once more with
//! counters for the work per query (per query: nodes, leaves, cells, point–triangle tests,
//! mailbox skips).
//!
//! `cargo run --release -p raybench-harness --example points_cells -- [SCENE.obj] [points=100000]
//!  [reps=5]` (default scene: ../shared/scenes/stanford-bunny.obj)

use raybench_accel::{Accel, BuildError, Counters, build_dyn};
use raybench_geom::{TriangleMesh, Vec3};
use raybench_grid::{Grid, GridParams};
use raybench_kdtree::{KdParams, KdTree};
use raybench_octree::{Octree, OctreeParams};
use raybench_scenes::points::PointWorkload;
use raybench_testkit::points::check_points;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

const SEED: u64 = 0x5eed_7101;

type Builder = fn(Arc<TriangleMesh>) -> Result<Box<dyn Accel>, BuildError>;

fn main() {
    let mut scene = raybench_testkit::shared_scenes_dir().join("stanford-bunny.obj");
    let (mut n, mut reps) = (100_000usize, 5usize);
    for a in std::env::args().skip(1) {
        match a.split_once('=') {
            Some(("points", v)) => n = v.parse().expect("points=N"),
            Some(("reps", v)) => reps = v.parse::<usize>().expect("reps=N").max(1),
            _ => scene = PathBuf::from(a),
        }
    }
    let mesh = raybench_scenes::load_obj(&scene)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.display()))
        .mesh;
    let points = PointWorkload::Near.generate(&mesh, n, SEED);
    println!(
        "{}: {} triangles, {n} points-near (seed {SEED:#x}), 1 thread",
        scene.display(),
        mesh.len()
    );
    let builders: [(&str, Builder); 3] = [
        ("kd-sah", |m| build_dyn::<KdTree>(m, &KdParams::sah())),
        ("grid", |m| build_dyn::<Grid>(m, &GridParams::default())),
        ("octree", |m| {
            build_dyn::<Octree>(m, &OctreeParams::default())
        }),
    ];
    println!(
        "{:<8} {:>9} {:>7} {:>11} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}",
        "name",
        "build ms",
        "Mq/s",
        "(min-max)",
        "on-CPU",
        "nodes",
        "leaves",
        "cells",
        "tests",
        "skips"
    );
    for (name, build) in builders {
        let t = Instant::now();
        let accel = build(mesh.clone()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        let checked = &points[..points.len().min(1000)];
        let counts = check_points(accel.as_ref(), &mesh, checked, f32::INFINITY)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(counts.mismatch, 0);
        let (mut rates, mut cpu): (Vec<f64>, Vec<f64>) =
            (0..reps).map(|_| rate(accel.as_ref(), &points)).unzip();
        rates.sort_by(f64::total_cmp);
        cpu.sort_by(f64::total_cmp);
        let mut c = Counters::default();
        for &p in &points {
            accel.closest_point_counted(p, f32::INFINITY, &mut c);
        }
        let per = |x: u64| x as f64 / points.len() as f64;
        println!(
            "{name:<8} {build_ms:>9.1} {:>7.3} {:>5.3}-{:<5.3} {:>7.3} {:>7.1} {:>7.1} {:>7.1} {:>7.1} {:>7.1}",
            rates[reps / 2],
            rates[0],
            rates[reps - 1],
            cpu[reps / 2],
            per(c.nodes),
            per(c.leaves),
            per(c.cells),
            per(c.prim_tests),
            per(c.mailbox_skips),
        );
    }
}

/// Million queries per second over all points, one thread: by the wall clock, and by the
/// thread's time on a CPU (Linux's schedstat; NaN elsewhere), which a loaded machine disturbs
/// less.
fn rate(accel: &dyn Accel, points: &[Vec3]) -> (f64, f64) {
    let (t, cpu) = (Instant::now(), on_cpu_seconds());
    let mut found = 0usize;
    for &p in points {
        found += std::hint::black_box(accel.closest_point(p, f32::INFINITY)).is_some() as usize;
    }
    let (wall, cpu) = (t.elapsed().as_secs_f64(), on_cpu_seconds() - cpu);
    assert_eq!(found, points.len(), "every point has a nearest triangle");
    let mq = |s: f64| points.len() as f64 / s / 1e6;
    (mq(wall), mq(cpu))
}

/// Seconds this thread has run on a CPU (first field of /proc/thread-self/schedstat, in ns).
fn on_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
