//! Knob exploration for the skipping grid: builds `grid` and `grid-skip` with each `min_jump`
//! given (and, with `lambda=`, at another density) on each scene, traces seeded random and
//! primary rays through all of them interleaved, round after round (this machine is shared and
//! noisy: same-run, same-rounds ratios), and prints each one's best pass, its ratio to `grid`,
//! build time and cells, jumps and triangle tests per ray; a second copy of `grid`, timed last
//! in each round, shows the noise. Used to choose the default
//! documented on `SkipGridParams::MIN_JUMP`.
//!
//! `cargo run --release -p raybench-harness --example skiptune -- SCENE[,SCENE...]
//!  [jumps=2,3,4] [lambda=1] [rays=100000] [rounds=8]`

use raybench_accel::{Accel, Counters};
use raybench_geom::Ray;
use raybench_grid::{Grid, GridParams, SkipGrid, SkipGridParams};
use std::sync::Arc;
use std::time::Instant;

mod probe;

use probe::scene_rays;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut jumps, mut lambda, mut rays_n, mut rounds) = (vec![2u8, 3, 4], 1.0, 100_000, 8);
    for a in &args[1..] {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "jumps" => jumps = v.split(',').map(|j| j.parse().unwrap()).collect(),
            "lambda" => lambda = v.parse().unwrap(),
            "rays" => rays_n = v.parse().unwrap(),
            "rounds" => rounds = v.parse().unwrap(),
            _ => panic!("unknown knob {k}"),
        }
    }
    for spec in args[0].split(',') {
        let (mesh, random, primary) = scene_rays(spec, rays_n);
        let grid_params = GridParams::with_density(lambda);
        let mut accels: Vec<(String, Box<dyn Accel>, f64)> = Vec::new();
        let t = Instant::now();
        let grid = Grid::build(Arc::clone(&mesh), &grid_params).unwrap();
        accels.push((
            "grid".into(),
            Box::new(grid),
            t.elapsed().as_secs_f64() * 1e3,
        ));
        // The same grid again, timed last in each round: its ratio to the first is the noise
        // (and any bias of the timing order).
        let control = Grid::build(Arc::clone(&mesh), &grid_params).unwrap();
        for &j in &jumps {
            let p = SkipGridParams {
                grid: grid_params.clone(),
                min_jump: j,
            };
            let t = Instant::now();
            let s = SkipGrid::build(Arc::clone(&mesh), &p).unwrap();
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let e = s.build_stats().extra;
            if j == jumps[0] {
                println!(
                    "{spec} n={} cells {} empty {:.3} max distance {} mean empty distance {:.2}",
                    mesh.len(),
                    e["cells"],
                    e["empty_cell_fraction"],
                    e["skip_max_distance"],
                    e["skip_mean_empty_distance"]
                );
            }
            accels.push((format!("skip{j}"), Box::new(s), ms));
        }
        accels.push(("grid'".into(), Box::new(control), accels[0].2));
        for (name, rays) in [("random", &random), ("primary", &primary)] {
            let mut best = vec![f64::INFINITY; accels.len()];
            for _ in 0..rounds {
                for (k, (_, a, _)) in accels.iter().enumerate() {
                    let t = Instant::now();
                    let hits = rays.iter().filter(|r| a.intersect(r).is_some()).count();
                    std::hint::black_box(hits);
                    best[k] = best[k].min(t.elapsed().as_secs_f64());
                }
            }
            let n = rays.len() as f64;
            for (k, (label, a, ms)) in accels.iter().enumerate() {
                let c = count(a.as_ref(), rays);
                println!(
                    "  {name:8} {label:6} {:7.3} Mr/s {:5.2}× grid  build {ms:7.1} ms  cells {:7.2} jumps {:6.2} tests {:8.1}",
                    n / best[k] / 1e6,
                    best[0] / best[k],
                    c.cells as f64 / n,
                    c.jumps as f64 / n,
                    c.prim_tests as f64 / n,
                );
            }
        }
    }
}

fn count(a: &dyn Accel, rays: &[Ray]) -> Counters {
    let mut c = Counters::default();
    for r in rays {
        a.intersect_counted(r, &mut c);
    }
    c
}
