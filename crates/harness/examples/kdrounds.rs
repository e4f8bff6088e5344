//! Same-run comparison of k-d tree knob values: one tree per value of one knob, built and traced
//! in interleaved rounds (round r times every tree once, so a slow minute on this shared
//! machine hits every value alike), printing each value's median build time, tree shape and
//! Mrays/s for random rays, primary rays ray by ray and primary rays as packets. Used to choose
//! `KdParams::sah`'s costs (docs/experiments.md, k-d tree).
//!
//! `cargo run --release -p raybench-harness --example kdrounds -- SCENE ki=0.75,0.35
//!  [rounds=7] [rays=100000]` (knobs: ki, kt, bonus, leaf)

use raybench_accel::{Accel, Hit};
use raybench_kdtree::{KdParams, KdTree};
use std::sync::Arc;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = raybench_scenes::resolve(&args[0], 1).expect("scene");
    let (mut rounds, mut rays_n) = (7usize, 100_000usize);
    let mut configs: Vec<(String, KdParams)> = Vec::new();
    for a in &args[1..] {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "rounds" => rounds = v.parse().unwrap(),
            "rays" => rays_n = v.parse().unwrap(),
            _ => {
                for x in v.split(',') {
                    let mut p = KdParams::packets();
                    match k {
                        "ki" => p.intersection_cost = x.parse().unwrap(),
                        "kt" => p.traversal_cost = x.parse().unwrap(),
                        "bonus" => p.empty_bonus = x.parse().unwrap(),
                        "leaf" => p.leaf_size = x.parse().unwrap(),
                        _ => panic!("unknown knob {k}"),
                    }
                    configs.push((format!("{k}={x}"), p));
                }
            }
        }
    }
    let mesh = scene.mesh.clone();
    let random = raybench_scenes::random_rays(&mesh.bounds(), rays_n, 1);
    let (primary, _, _) = raybench_scenes::primary_rays(&scene.view, &mesh.bounds(), rays_n);
    let trees: Vec<KdTree> = configs
        .iter()
        .map(|(_, p)| KdTree::build(Arc::clone(&mesh), p).expect("builds"))
        .collect();
    let prepared: Vec<_> = trees
        .iter()
        .map(|t| t.prepare_coherent_rays(&primary).unwrap())
        .collect();
    let n = configs.len();
    let (mut build, mut rnd, mut pri, mut pkt) = (
        vec![vec![]; n],
        vec![vec![]; n],
        vec![vec![]; n],
        vec![vec![]; n],
    );
    let mut out: Vec<Option<Hit>> = vec![None; primary.len()];
    for round in 0..rounds {
        for k in 0..n {
            let i = (k + round) % n;
            let t = Instant::now();
            std::hint::black_box(KdTree::build(Arc::clone(&mesh), &configs[i].1).unwrap());
            build[i].push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            std::hint::black_box(
                random
                    .iter()
                    .filter(|r| trees[i].intersect(r).is_some())
                    .count(),
            );
            rnd[i].push(random.len() as f64 / t.elapsed().as_secs_f64() / 1e6);
            let t = Instant::now();
            std::hint::black_box(
                primary
                    .iter()
                    .filter(|r| trees[i].intersect(r).is_some())
                    .count(),
            );
            pri[i].push(primary.len() as f64 / t.elapsed().as_secs_f64() / 1e6);
            let t = Instant::now();
            trees[i].intersect_prepared(&primary, &prepared[i], 0, &mut out);
            std::hint::black_box(&out);
            pkt[i].push(primary.len() as f64 / t.elapsed().as_secs_f64() / 1e6);
        }
    }
    for (i, (name, _)) in configs.iter().enumerate() {
        let s = trees[i].build_stats();
        println!(
            "{} {name:10} build {:7.1} ms nodes {:8} refs/tri {:5.2} | random {:6.2} primary {:6.2} packets {:6.2} Mr/s",
            args[0],
            median(build[i].clone()),
            s.nodes,
            s.extra["refs_per_triangle"],
            median(rnd[i].clone()),
            median(pri[i].clone()),
            median(pkt[i].clone()),
        );
    }
}
