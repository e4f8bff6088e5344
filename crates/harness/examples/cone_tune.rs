//! The Whitted and diffuse batches of a scene (100,000 pixels, as `raybench run` makes them)
//! traced through `bvh8-binned` and through `bvh8-packets`' search for groups within a cone
//! (`cone_packets`) at each given cosine, one thread, the trees in rotated order round after
//! round; prints the groups within each cone and each cosine's rate over the plain walk's
//! (medians). For choosing `cone_packets` on a shared, noisy machine.
//!
//! `cargo run --release -p raybench-harness --example cone_tune -- SCENE ROUNDS 0.995 0.998`
use raybench_accel::{Accel, PreparedRays};
use raybench_bvh::{Bvh8, WideParams};
use raybench_geom::Ray;
use raybench_scenes::{RayRecipe, SurfaceHit, Workload};
use std::sync::Arc;
use std::time::Instant;
mod probe;
use probe::median;

fn main() {
    let mut args = std::env::args().skip(1);
    let spec = args.next().unwrap_or("grass".into());
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(9);
    let coses: Vec<f32> = args.map(|a| a.parse().unwrap()).collect();
    let scene = raybench_scenes::resolve(&spec, 1).expect("scene");
    let mesh = Arc::clone(&scene.mesh);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut trees =
        vec![one.install(|| Bvh8::build(Arc::clone(&mesh), &WideParams::for_width(8)).unwrap())];
    for &c in &coses {
        let p = WideParams {
            cone_packets: Some(c),
            ..WideParams::for_width(8).with_packets()
        };
        trees.push(one.install(|| Bvh8::build(Arc::clone(&mesh), &p).unwrap()));
    }
    let plain = &trees[0];
    let trace = |r: &Ray| {
        plain.intersect(r).map(|h| SurfaceHit {
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    };
    let recipe = RayRecipe::new(&scene, 100_000, 1, &trace);
    for w in [Workload::Whitted, Workload::Diffuse] {
        let rays = recipe.rays(w).unwrap();
        let mut out = vec![None; rays.len()];
        let mut ms = vec![Vec::new(); trees.len()];
        for round in 0..rounds {
            for k in 0..trees.len() {
                let i = (k + round) % trees.len();
                let s = Instant::now();
                trees[i].intersect_prepared(&rays, &PreparedRays::Native, 0, &mut out);
                ms[i].push(s.elapsed().as_secs_f64() * 1e3);
                std::hint::black_box(&out);
            }
        }
        let base = median(ms[0].clone());
        let mut line = format!("{spec:14} {w:8} {:6} rays plain {base:7.3} ms", rays.len());
        for (i, c) in coses.iter().enumerate() {
            let groups = rays
                .chunks_exact(16)
                .filter(|g| {
                    let d0 = g[0].dir().normalize();
                    g.iter().all(|r| r.dir().normalize().dot(d0) >= *c)
                })
                .count();
            line += &format!(
                " | {c}: {groups} groups x{:.3}",
                base / median(ms[i + 1].clone())
            );
        }
        println!("{line}");
    }
}
