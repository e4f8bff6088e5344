//! Build time and tree quality of `bvh8-sbvh` under given spatial-split knobs, beside
//! `bvh8-binned` and `embree-high` built in the same rounds (interleaved, medians), for choosing
//! the knobs' defaults on a shared, noisy machine. Prints each build's median milliseconds, its
//! ratio to embree-high's, the SAH cost, the reference growth, the spatial splits taken, and
//! the nodes and triangle tests per closest-hit query over 20,000 random rays. With
//! `TRACE=1` in the environment it also builds each configuration once more and traces
//! 100,000 primary, random and shadow rays through every tree, one thread, in rotated order
//! round after round (the same number of rounds, at least 3), and prints per workload each tree's median time over bvh8-binned's in
//! the same round, with nodes and triangle tests per ray: what the SAH cost does not show.
//!
//! `cargo run --release -p raybench-harness --example sbvh_tune -- hair 2 5 1e-5,0.5,32 1e-4,0.5,32`
//! (scene: an .obj path or a generator spec; threads; rounds; then one
//! `alpha,growth,bins[,intersection_cost[,overlap_share[,max_cuts]]]` per configuration).

use raybench_accel::Accel;
use raybench_bvh::{Bvh8, SpatialSplits, WideParams};
use raybench_embree::{Device, EmbreeParams, EmbreeScene};
use std::sync::Arc;
use std::time::Instant;

mod probe;
use probe::{median, primary_hits};

fn main() {
    let mut args = std::env::args().skip(1);
    let spec = args.next().unwrap_or("hair".into());
    let threads: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(2);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(5);
    let configs: Vec<SpatialSplits> = args
        .map(|a| {
            let v: Vec<f32> = a.split(',').map(|x| x.parse().expect("a number")).collect();
            let d = SpatialSplits::default();
            SpatialSplits {
                alpha: v[0],
                max_reference_growth: v[1],
                spatial_bins: v[2] as u32,
                intersection_cost: v.get(3).copied().unwrap_or(d.intersection_cost),
                overlap_share: v.get(4).copied().unwrap_or(d.overlap_share),
                max_cuts: v.get(5).map_or(d.max_cuts, |&c| c as u32),
            }
        })
        .collect();
    let scene = raybench_scenes::resolve(&spec, 1).expect("scene loads");
    let mesh = Arc::clone(&scene.mesh);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let high = EmbreeParams {
        threads,
        ..EmbreeParams::high()
    };
    let _device = Device::shared(&high.config_string()).expect("Embree device");
    let mut params = vec![("bvh8-binned".to_string(), WideParams::for_width(8))];
    for c in &configs {
        let mut p = WideParams::sbvh();
        p.binary.spatial_splits = Some(*c);
        // The six knobs in the order the configuration takes them.
        let name = format!(
            "sbvh {},{},{},{},{},{}",
            c.alpha,
            c.max_reference_growth,
            c.spatial_bins,
            c.intersection_cost,
            c.overlap_share,
            c.max_cuts
        );
        params.push((name, p));
    }
    let mut times = vec![Vec::new(); params.len() + 1];
    let mut stats = vec![None; params.len()];
    let mut work = vec![(0.0, 0.0); params.len()];
    let rays = raybench_scenes::random_rays(&mesh.bounds(), 20_000, 3);
    for _ in 0..rounds {
        let t = Instant::now();
        drop(EmbreeScene::build(Arc::clone(&mesh), &high).expect("builds"));
        times[0].push(t.elapsed().as_secs_f64() * 1e3);
        for (i, (_, p)) in params.iter().enumerate() {
            let t = Instant::now();
            let bvh = pool.install(|| Bvh8::build(Arc::clone(&mesh), p).expect("builds"));
            times[i + 1].push(t.elapsed().as_secs_f64() * 1e3);
            stats[i] = Some(bvh.build_stats());
            let mut c = raybench_accel::Counters::default();
            for ray in &rays {
                bvh.intersect_counted(ray, &mut c);
            }
            let per = |x: u64| x as f64 / rays.len() as f64;
            work[i] = (per(c.nodes), per(c.prim_tests));
        }
    }
    if std::env::var_os("TRACE").is_some() {
        trace(&scene, &params, rounds);
    }
    let high_ms = median(times[0].clone());
    println!(
        "{spec}: {} triangles, {threads} threads, {rounds} rounds",
        mesh.len()
    );
    println!("embree-high {high_ms:.1} ms");
    for (i, (name, _)) in params.iter().enumerate() {
        let ms = median(times[i + 1].clone());
        let s = stats[i].as_ref().expect("built");
        let extra = |k: &str| s.extra.get(k).copied().unwrap_or(f64::NAN);
        println!(
            "{name:24} {ms:9.1} ms {:6.2}x high  sah {:10.3}  growth {:.3}  splits {} of {} searched  random ray: {:.2} nodes {:.2} tests",
            ms / high_ms,
            s.sah_cost.unwrap_or(f64::NAN),
            extra("reference_growth"),
            extra("spatial_splits"),
            extra("spatial_searches"),
            work[i].0,
            work[i].1
        );
    }
}

/// Times primary, random and shadow rays through one tree per configuration (see the module
/// note), on one thread, through the pass `raybench run` times.
fn trace(scene: &raybench_scenes::Scene, params: &[(String, WideParams)], rounds: usize) {
    use raybench_harness::pipeline::measure::{Answers, trace_pass};
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mesh = &scene.mesh;
    let trees: Vec<Bvh8> = params
        .iter()
        .map(|(_, p)| one.install(|| Bvh8::build(Arc::clone(mesh), p).expect("builds")))
        .collect();
    let bounds = mesh.bounds();
    let (primary, _, _) = raybench_scenes::primary_rays(&scene.view, &bounds, 100_000);
    let hits = primary_hits(&trees[0], &primary);
    let shadow = raybench_scenes::shadow_rays(mesh, scene.view.light, &primary, &hits);
    let random = raybench_scenes::random_rays(&bounds, 100_000, 1);
    for (label, rays, any_hit) in [
        ("primary", &primary, false),
        ("random", &random, false),
        ("shadow", &shadow, true),
    ] {
        let mut ratios = vec![Vec::new(); trees.len()];
        let mut out = Answers::new(any_hit, rays.len());
        let native = raybench_accel::PreparedRays::Native;
        for t in &trees {
            one.install(|| trace_pass(t, rays, &native, 1, &mut out));
        }
        for round in 0..rounds.max(3) {
            let mut ms = vec![0.0; trees.len()];
            for k in 0..trees.len() {
                let i = (k + round) % trees.len();
                let d = one.install(|| trace_pass(&trees[i], rays, &native, 1, &mut out));
                ms[i] = d.as_secs_f64() * 1e3;
            }
            for i in 0..trees.len() {
                ratios[i].push(ms[i] / ms[0]);
            }
        }
        for (i, (name, _)) in params.iter().enumerate() {
            let mut c = raybench_accel::Counters::default();
            for ray in rays.iter() {
                if any_hit {
                    trees[i].occluded_counted(ray, &mut c);
                } else {
                    trees[i].intersect_counted(ray, &mut c);
                }
            }
            let per = |x: u64| x as f64 / rays.len() as f64;
            println!(
                "{label:8} {name:24} time / bvh8-binned {:.3}  {:.2} nodes {:.2} tests",
                median(ratios[i].clone()),
                per(c.nodes),
                per(c.prim_tests)
            );
        }
    }
}
