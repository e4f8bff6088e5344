//! Times closest-point queries of both BVHs next to Embree's `rtcPointQuery` (embree-medium) on
//! one scene, outside the harness, one thread. Every structure's answers are first checked
//! against the binary BVH's (same distance within a few ulps of the scene's magnitude); then
//! each round times every structure once per workload, and the figures printed are the median
//! Mqueries/s over rounds and the median of the per-round ratio to Embree, plus nodes and
//! point–triangle tests per query from one counted pass.
//!
//! `cargo run --release -p raybench-harness --example points_bvh -- ../shared/scenes/stanford-bunny.obj 100000 7`
//! (scene, points per workload, rounds).

use raybench_accel::{Accel, Counters, PointHit};
use raybench_bvh::{Bvh, Bvh8, BvhParams, WideParams};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::Vec3;
use raybench_scenes::points::PointWorkload;
use std::sync::Arc;
use std::time::Instant;

/// Seed of the timed point sets.
const SEED: u64 = 0x5eed_7100;

/// Queries per second of one pass over `points`, in millions.
fn mqueries(accel: &dyn Accel, points: &[Vec3], radius: f32, out: &mut [Option<PointHit>]) -> f64 {
    let start = Instant::now();
    for (o, p) in out.iter_mut().zip(points) {
        *o = accel.closest_point(*p, radius);
    }
    std::hint::black_box(&out);
    points.len() as f64 / start.elapsed().as_secs_f64() / 1e6
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Every answer of `accel` has the reference's distance within `tol`; returns how many
/// answers name a different triangle (ties).
fn check_against(
    accel: &dyn Accel,
    reference: &[Option<PointHit>],
    points: &[Vec3],
    radius: f32,
    tol: f32,
) -> usize {
    let mut ties = 0;
    for (p, expected) in points.iter().zip(reference) {
        let got = accel.closest_point(*p, radius);
        match (got, expected) {
            (Some(a), Some(b)) if (a.distance - b.distance).abs() <= tol => {
                ties += usize::from(a.prim != b.prim)
            }
            _ => panic!("{}: at {p} got {got:?}, bvh {expected:?}", accel.name()),
        }
    }
    ties
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or("../shared/scenes/stanford-bunny.obj".into());
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(7);
    let scene = raybench_scenes::load_obj(std::path::Path::new(&path)).expect("scene loads");
    let mesh = Arc::clone(&scene.mesh);
    let magnitude = mesh
        .bounds()
        .min
        .abs()
        .max(mesh.bounds().max.abs())
        .max_element();
    let tol = 8.0 * f32::EPSILON * magnitude;
    println!("{path}: {} triangles, {n} points per workload", mesh.len());

    let embree = EmbreeParams {
        threads: 1,
        ..EmbreeParams::medium()
    };
    let structures: Vec<Box<dyn Accel>> = vec![
        Box::new(EmbreeScene::build(Arc::clone(&mesh), &embree).expect("builds")),
        Box::new(Bvh::build(Arc::clone(&mesh), &BvhParams::binned()).expect("builds")),
        Box::new(Bvh8::build(Arc::clone(&mesh), &WideParams::default()).expect("builds")),
    ];
    for workload in PointWorkload::ALL {
        let points = workload.generate(&mesh, n, SEED);
        let radius = workload.default_radius();
        let reference: Vec<_> = points
            .iter()
            .map(|p| structures[1].closest_point(*p, radius))
            .collect();
        let mut out = vec![None; points.len()];
        let mut rates = vec![Vec::new(); structures.len()];
        for round in 0..=rounds {
            for (k, accel) in structures.iter().enumerate() {
                let rate = mqueries(accel.as_ref(), &points, radius, &mut out);
                if round > 0 {
                    rates[k].push(rate); // round 0 warms up
                }
            }
        }
        for (k, accel) in structures.iter().enumerate() {
            let ties = check_against(accel.as_ref(), &reference, &points, radius, tol);
            let mut c = Counters::default();
            for p in &points {
                accel.closest_point_counted(*p, radius, &mut c);
            }
            let per = |x: u64| x as f64 / points.len() as f64;
            let ratios = rates[k].iter().zip(&rates[0]).map(|(a, b)| a / b).collect();
            let counters = if accel.has_counters() {
                format!(
                    "per query: {:5.1} nodes {:5.1} leaves {:5.1} tests",
                    per(c.nodes),
                    per(c.leaves),
                    per(c.prim_tests)
                )
            } else {
                "(no counters)".to_string()
            };
            println!(
                "{:14} {:18} {:7.3} Mqueries/s {:6.3}x embree  {counters}  ({ties} ties)",
                workload.name(),
                accel.name(),
                median(rates[k].clone()),
                median(ratios),
            );
        }
    }
}
