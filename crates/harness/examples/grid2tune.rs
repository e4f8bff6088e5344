//! Knob exploration for the hierarchical grid: builds `grid2` on each scene with the knobs
//! given as `key=value` arguments, and traces seeded random and primary-style rays, printing
//! build time, shape, Mrays/s and counters per ray next to the uniform `grid` and
//! `bvh-binned` on the same rays in the same process (same-run ratios: this machine is shared
//! and noisy). Used to choose the defaults documented on `Grid2Params`.
//!
//! `cargo run --release -p raybench-harness --example grid2tune -- SCENE[,SCENE...] [top=1]
//!  [cell=2] [levels=3] [crowded=8] [maxres=128] [enter=8] [step=4] [refs=64] [rays=100000]
//!  [reps=3]`

use raybench_accel::Accel;
use raybench_grid::{Grid, Grid2, Grid2Params, GridParams};
use std::sync::Arc;
use std::time::Instant;

fn parse(v: &str) -> f64 {
    match v.split_once('/') {
        Some((a, b)) => a.parse::<f64>().unwrap() / b.parse::<f64>().unwrap(),
        None => v.parse().unwrap(),
    }
}

mod probe;

use probe::{scene_rays, time};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut p = Grid2Params::default();
    let (mut rays_n, mut reps) = (100_000usize, 3usize);
    for a in &args[1..] {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "top" => p.top_density = parse(v),
            "cell" => p.cell_density = parse(v),
            "levels" => p.max_levels = v.parse().unwrap(),
            "crowded" => p.crowded = v.parse().unwrap(),
            "maxres" => p.max_cell_resolution = v.parse().unwrap(),
            "enter" => p.entry_cost = v.parse().unwrap(),
            "step" => p.cell_cost = v.parse().unwrap(),
            "refs" => p.max_refs_per_triangle = v.parse().unwrap(),
            "rays" => rays_n = v.parse().unwrap(),
            "reps" => reps = v.parse().unwrap(),
            _ => panic!("unknown knob {k}"),
        }
    }
    for spec in args[0].split(',') {
        let (mesh, random, primary) = scene_rays(spec, rays_n);
        let t = Instant::now();
        let g2 = Grid2::build(Arc::clone(&mesh), &p).expect("builds");
        let build2 = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let g1 = Grid::build(Arc::clone(&mesh), &GridParams::default()).unwrap();
        let build1 = t.elapsed().as_secs_f64() * 1e3;
        let bvh = raybench_bvh::Bvh::build(Arc::clone(&mesh), &raybench_bvh::BvhParams::binned())
            .unwrap();
        let s = g2.build_stats();
        println!(
            "{spec} n={} grid2 build {build2:.1} ms (grid {build1:.1}) levels {} grids {} cells {} refs/tri {:.2} max/cell {}",
            mesh.len(),
            s.max_depth + 1,
            s.extra["cell_grids"],
            s.extra["cells"],
            s.extra["refs_per_triangle"],
            s.extra["max_refs_per_cell"],
        );
        for (name, rays) in [("random", &random), ("primary", &primary)] {
            let (b, _) = time(&bvh, rays, reps);
            let (m1, c1) = time(&g1, rays, reps);
            let (m2, c2) = time(&g2, rays, reps);
            let n = rays.len() as f64;
            println!(
                "  {name:8} grid2 {m2:6.2} Mr/s ({:.2}× bvh) cells {:6.1} tests {:7.1} | grid {m1:6.2} ({:.2}× bvh) cells {:6.1} tests {:7.1}",
                m2 / b,
                c2.cells as f64 / n,
                c2.prim_tests as f64 / n,
                m1 / b,
                c1.cells as f64 / n,
                c1.prim_tests as f64 / n,
            );
        }
    }
}
