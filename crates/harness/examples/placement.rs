//! How much a structure's rate depends on where its copy sits in memory: builds one registry
//! entry `copies` times in one process (each copy at other addresses, the same tree), times
//! every copy's camera rays in interleaved rounds beside embree-medium, and prints each copy's
//! best pass and its ratio to Embree's. A copy more than 5 % below the median is timed again
//! from a new thread (another call stack and traversal stack, on the core the first ran on
//! when the process is pinned with `taskset`), and with the rays prepared for another copy,
//! to tell what the slowness follows.
//!
//! `cargo run --release -p raybench-harness --example placement -- teapot bvh16-sbvh 40`
//! (scene: an .obj path or a generator spec; entry; copies; optionally rounds, 7 by default).

use raybench_accel::{Accel, PreparedRays};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::Ray;
use raybench_harness::Registry;
use raybench_harness::registry::BuildContext;
use raybench_scenes::{RayRecipe, SurfaceHit, Workload};
use std::sync::Arc;

mod probe;
use probe::{Answers, median};

/// Millions of camera rays a second of one pass.
fn mrays(accel: &dyn Accel, rays: &[Ray], prepared: &PreparedRays, out: &mut Answers) -> f64 {
    probe::prepared_pass(accel, rays, prepared, false, out)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let spec = args.next().unwrap_or("teapot".into());
    let name = args.next().unwrap_or("bvh16-sbvh".into());
    let copies: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(40)
        .max(2);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(7).max(1);
    let scene = raybench_scenes::resolve(&spec, 1).expect("scene loads");
    let mesh = Arc::clone(&scene.mesh);
    let embree = EmbreeScene::build(Arc::clone(&mesh), &EmbreeParams::medium()).expect("builds");
    let trace = |r: &Ray| {
        embree.intersect(r).map(|h| SurfaceHit {
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    };
    let rays = RayRecipe::new(&scene, 100_000, 1, &trace)
        .rays(Workload::Primary)
        .expect("a ray workload");
    let entry = Registry::builtin()
        .select(std::slice::from_ref(&name))
        .expect("a registered structure")
        .into_iter()
        .next()
        .expect("one entry");
    // Each copy is built while the ones before it are alive, so it lands elsewhere.
    let built: Vec<(Box<dyn Accel>, PreparedRays)> = (0..copies)
        .map(|_| {
            let accel = entry
                .build(Arc::clone(&mesh), &BuildContext::new(1))
                .expect("builds")
                .accel;
            let prepared = accel.prepare_coherent_rays(&rays).expect("valid rays");
            (accel, prepared)
        })
        .collect();
    let embree_rays = embree.prepare_coherent_rays(&rays).expect("valid rays");
    let mut out = Answers::for_rays(rays.len());
    let mut best = vec![0f64; copies];
    let mut best_embree = 0f64;
    for _ in 0..rounds {
        for (k, (accel, prepared)) in built.iter().enumerate() {
            best[k] = best[k].max(mrays(accel.as_ref(), &rays, prepared, &mut out));
        }
        best_embree = best_embree.max(mrays(&embree, &rays, &embree_rays, &mut out));
    }
    let median = median(best.clone());
    for (k, rate) in best.iter().enumerate() {
        println!(
            "copy {k:3} {rate:7.2} Mrays/s  {:.3}x embree",
            rate / best_embree
        );
    }
    println!("embree-medium {best_embree:7.2} Mrays/s; median copy {median:.2}");
    let good = (0..copies)
        .find(|&k| best[k] >= 0.99 * median)
        .expect("the median copy");
    for slow in (0..copies).filter(|&k| best[k] < 0.95 * median) {
        let mut again = [0f64; 3];
        for _ in 0..rounds {
            let (accel, prepared) = &built[slow];
            again[0] = again[0].max(mrays(accel.as_ref(), &rays, prepared, &mut out));
            again[1] = again[1].max(mrays(accel.as_ref(), &rays, &built[good].1, &mut out));
            let (accel, _) = &built[good];
            again[2] = again[2].max(mrays(accel.as_ref(), &rays, prepared, &mut out));
        }
        let other_thread = std::thread::scope(|s| {
            s.spawn(|| {
                let mut out = Answers::for_rays(rays.len());
                let mut r = [0f64; 2];
                for _ in 0..rounds {
                    for (i, k) in [slow, good].into_iter().enumerate() {
                        let (accel, prepared) = &built[k];
                        r[i] = r[i].max(mrays(accel.as_ref(), &rays, prepared, &mut out));
                    }
                }
                r
            })
            .join()
            .expect("the timing thread")
        });
        println!(
            "slow copy {slow}: again {:.2}; its tree with copy {good}'s rays {:.2}; copy {good}'s \
             tree with its rays {:.2}; from a new thread {:.2} (copy {good} there {:.2})",
            again[0], again[1], again[2], other_thread[0], other_thread[1]
        );
    }
}
