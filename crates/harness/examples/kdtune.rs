//! Knob exploration: builds a k-d tree on one scene with the knobs given as `key=value`
//! arguments and traces seeded random and primary-style rays, printing build time, shape,
//! Mrays/s and counters per ray, next to `bvh-binned` on the same rays in the same process (a
//! same-run ratio: this machine is shared and noisy). Used to choose the defaults documented on
//! `KdParams::sah` and `MAILBOX_SLOTS`.
//!
//! `cargo run --release -p raybench-harness --example kdtune -- SCENE [builder=median]
//!  [kt=1] [ki=1.5] [bonus=0.8] [depth=N] [leaf=0] [mailbox=true] [rays=100000] [reps=3]`

use raybench_accel::{Accel, Counters};
use raybench_kdtree::{Builder, KdParams, KdTree};
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = raybench_scenes::resolve(&args[0], 1).expect("scene");
    let mut p = KdParams::sah();
    let (mut rays_n, mut reps) = (100_000usize, 3usize);
    for a in &args[1..] {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "builder" if v == "median" => {
                p = KdParams {
                    builder: Builder::Median,
                    leaf_size: 4,
                    ..p
                }
            }
            "kt" => p.traversal_cost = v.parse().unwrap(),
            "ki" => p.intersection_cost = v.parse().unwrap(),
            "bonus" => p.empty_bonus = v.parse().unwrap(),
            "depth" => p.max_depth = Some(v.parse().unwrap()),
            "leaf" => p.leaf_size = v.parse().unwrap(),
            "mailbox" => p.mailbox = v.parse().unwrap(),
            "rays" => rays_n = v.parse().unwrap(),
            "reps" => reps = v.parse().unwrap(),
            _ => panic!("unknown knob {k}"),
        }
    }
    let mesh = scene.mesh.clone();
    let mut build_ms = Vec::new();
    let mut kd = None;
    for _ in 0..reps {
        let t = Instant::now();
        kd = Some(KdTree::build(Arc::clone(&mesh), &p).expect("builds"));
        build_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let kd = kd.unwrap();
    build_ms.sort_by(f64::total_cmp);
    let s = kd.build_stats();
    println!(
        "{} n={} build {:.1} ms nodes {} leaves {} empty {} refs/tri {:.2} depth {} mean leaf depth {:.1} full leaf size {:.2} max leaf {} over 64 {} (sharing a point: {}) depth-capped {} sah {:.1}",
        args[0],
        mesh.len(),
        build_ms[build_ms.len() / 2],
        s.nodes,
        s.leaves,
        s.extra["empty_leaves"],
        s.extra["refs_per_triangle"],
        s.max_depth,
        s.extra["mean_leaf_depth"],
        s.extra["mean_full_leaf_size"],
        s.extra["max_leaf_size"],
        s.extra["leaves_over_64"],
        s.extra["leaves_over_64_sharing_a_point"],
        s.extra["depth_capped_leaves"],
        s.sah_cost.unwrap_or(0.0)
    );
    let random = raybench_scenes::random_rays(&mesh.bounds(), rays_n, 1);
    let (primary, _, _) = raybench_scenes::primary_rays(&scene.view, &mesh.bounds(), rays_n);
    let bvh =
        raybench_bvh::Bvh::build(Arc::clone(&mesh), &raybench_bvh::BvhParams::binned()).unwrap();
    for (name, rays) in [("random", &random), ("primary", &primary)] {
        let mut times = Vec::new();
        for _ in 0..reps.max(3) {
            let t = Instant::now();
            let hits = rays.iter().filter(|r| bvh.intersect(r).is_some()).count();
            std::hint::black_box(hits);
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        println!(
            "  bvh {name:8} {:6.2} Mr/s",
            rays.len() as f64 / times[times.len() / 2] / 1e6
        );
    }
    for (name, rays) in [("random", &random), ("primary", &primary)] {
        let mut times = Vec::new();
        for _ in 0..reps.max(3) {
            let t = Instant::now();
            let hits = rays.iter().filter(|r| kd.intersect(r).is_some()).count();
            std::hint::black_box(hits);
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let mut c = Counters::default();
        for r in rays.iter() {
            kd.intersect_counted(r, &mut c);
        }
        let n = rays.len() as f64;
        println!(
            "  {name:8} {:6.2} Mr/s nodes {:5.1} leaves {:4.1} tests {:4.2} skips {:4.2}",
            n / times[times.len() / 2] / 1e6,
            c.nodes as f64 / n,
            c.leaves as f64 / n,
            c.prim_tests as f64 / n,
            c.mailbox_skips as f64 / n
        );
    }
}
