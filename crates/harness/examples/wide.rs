//! Times the wide BVHs (4, 8 and 16 children) next to embree-medium on one scene, outside the
//! harness, for quick before/after checks of traversal changes on a shared, noisy machine: each
//! round times every structure once per workload, interleaved, and the figures printed are each
//! structure's best pass (the one least disturbed by other processes) and its ratio to Embree's
//! best pass. Short passes and many rounds make an undisturbed pass likely. Every pass writes
//! its answers into arrays made before the rounds, so none pays for an allocation.
//!
//! `cargo run --release -p raybench-harness --example wide -- ../shared/scenes/stanford-bunny.obj 50000 20`
//! (scene: an .obj path or a generator spec such as `hair`; rays per workload; rounds;
//! optionally one workload). Under `valgrind --tool=callgrind` use few rays and 1 round
//! (valgrind runs no AVX-512, so there `bvh8` takes the AVX2-only loops).
//!
//! Primary and shadow rays are prepared as the harness prepares them, as coherent batches, so
//! `bvh8-packets` and `embree-medium-stream` trace them in packets (and the random rays as
//! `bvh8` and `embree-medium` do). `bvh8-packets` is the registry's (packets that carry few
//! rays handed to the single-ray walk, `PacketFloors::MEASURED`); `bvh8-packets-all` walks
//! every packet as one; `RB_FLOORS=8:2,6:3` adds `bvh8-packets` with other `node:tri4` floors,
//! labelled `floors-8:2` and so on (name them in `RB_ONLY` too when it is set).
//!
//! `bvh16-sbvh` and `bvh16-sbvh-packets` are the registry's entries, built through it;
//! `RB_REGISTRY=bvh8-sbvh,bvh16-binned` adds other registry entries by name; `RB_SPATIAL=0.2`
//! adds `bvh16-sbvh` with another price of a triangle test in the spatial splits' choices;
//! `RB_TRI=0.2` adds both 16-wide trees with another price of a triangle slot against a node
//! step (`sbvh16-tri0.2`, `bin16-tri0.2`).
//!
//! `bvh8-avx2` is `bvh8` with its batch loops compiled for AVX2 alone (`NodeSimd::Avx2`); on a
//! CPU without AVX-512 the two are the same code. `RB_PACKETS_AVX2=1` adds
//! `bvh16-sbvh-packets-avx2` and `bvh8-packets-avx2`, held to AVX2 likewise: their packets are
//! the eight-lane walk of CPUs without AVX-512F. `RB_ONLY=embree-medium,bvh8` keeps only the
//! structures named, for profiling one structure alone; ratios are then to the first one kept
//! (embree-medium whenever it is kept).

use raybench_accel::{Accel, PreparedRays};
use raybench_bvh::{Bvh, Bvh4, Bvh8, Bvh16, BvhParams, NodeSimd, PacketFloors, WideParams};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::Ray;
use raybench_harness::Registry;
use raybench_harness::registry::BuildContext;
use raybench_scenes::{RayRecipe, SurfaceHit, Workload};
use std::sync::Arc;
use std::time::Instant;

mod probe;
use probe::{Answers, prepared_pass};

/// The prices listed in the variable `name` (`0.2,0.15`), skipping anything that is not a number.
fn env_prices(name: &str) -> Vec<f32> {
    std::env::var(name)
        .unwrap_or_default()
        .split(',')
        .filter_map(|c| c.parse().ok())
        .collect()
}

fn best(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or("../shared/scenes/stanford-bunny.obj".into());
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(50_000);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let only = args.next(); // one workload's name, to profile it alone
    // An .obj path, or a generator spec as the harness takes them (`hair`, `soup:triangles=5000`).
    let scene = raybench_scenes::resolve(&path, 1).expect("scene loads");
    let mesh = Arc::clone(&scene.mesh);

    let mut structures: Vec<(String, Box<dyn Accel>, f64)> = Vec::new();
    let mut add = |name: &str, build: &dyn Fn() -> Box<dyn Accel>| {
        let start = Instant::now();
        let accel = build();
        structures.push((name.into(), accel, start.elapsed().as_secs_f64() * 1e3));
    };
    add("embree-medium", &|| {
        Box::new(EmbreeScene::build(Arc::clone(&mesh), &EmbreeParams::medium()).expect("builds"))
    });
    add("embree-medium-stream", &|| {
        Box::new(
            EmbreeScene::build(Arc::clone(&mesh), &EmbreeParams::medium_stream()).expect("builds"),
        )
    });
    add("bvh-binned", &|| {
        Box::new(Bvh::build(Arc::clone(&mesh), &BvhParams::binned()).expect("builds"))
    });
    add("bvh4", &|| {
        Box::new(Bvh4::build(Arc::clone(&mesh), &WideParams::for_width(4)).expect("builds"))
    });
    add("bvh8", &|| {
        Box::new(Bvh8::build(Arc::clone(&mesh), &WideParams::default()).expect("builds"))
    });
    // `bvh8-packets` as registered (packets that carry few rays handed to the single-ray
    // walk), and every packet walked as one.
    let floors = |floors: PacketFloors| WideParams {
        coherent_packets: true,
        packet_floors: floors,
        ..WideParams::default()
    };
    add("bvh8-packets", &|| {
        Box::new(Bvh8::build(Arc::clone(&mesh), &floors(PacketFloors::MEASURED)).expect("builds"))
    });
    add("bvh8-packets-all", &|| {
        Box::new(Bvh8::build(Arc::clone(&mesh), &floors(PacketFloors::OFF)).expect("builds"))
    });
    // `RB_FLOORS=8:2,6:3`: `bvh8-packets` again with each `node:tri4` floor pair, labelled
    // `floors-8:2` and so on.
    for pair in std::env::var("RB_FLOORS").unwrap_or_default().split(',') {
        let Some((node, tri4)) = pair.split_once(':') else {
            continue;
        };
        let (Ok(node), Ok(tri4)) = (node.parse(), tri4.parse()) else {
            continue;
        };
        add(&format!("floors-{pair}"), &|| {
            let f = floors(PacketFloors { node, tri4 });
            Box::new(Bvh8::build(Arc::clone(&mesh), &f).expect("builds"))
        });
    }
    // The 16-wide entries as registered, built through the registry so they cannot drift from it.
    // `RB_REGISTRY=bvh8-sbvh,bvh16-binned` adds more registry entries by name.
    let mut names = vec!["bvh16-sbvh".to_string(), "bvh16-sbvh-packets".to_string()];
    if let Ok(more) = std::env::var("RB_REGISTRY") {
        names.extend(more.split(',').filter(|n| !n.is_empty()).map(String::from));
    }
    for e in Registry::builtin().select(&names).expect("registered") {
        add(e.name, &|| {
            e.build(Arc::clone(&mesh), &BuildContext::new(1))
                .expect("builds")
                .accel
        });
    }
    // `RB_SPATIAL=0.2,0.15`: `bvh16-sbvh` again with each price of a triangle test in the
    // spatial splits' choices, labelled `sbvh16-0.2` and so on.
    for cost in env_prices("RB_SPATIAL") {
        add(&format!("sbvh16-{cost}"), &|| {
            let mut p = WideParams {
                width: 16,
                ..WideParams::sbvh()
            };
            if let Some(s) = p.binary.spatial_splits.as_mut() {
                s.intersection_cost = cost;
            }
            Box::new(Bvh16::build(Arc::clone(&mesh), &p).expect("builds"))
        });
    }
    // `RB_TRI=0.2,0.25`: `bvh16-sbvh` and `bvh16-binned` again with another price of a
    // triangle slot against a node step (the binary build's and the collapse's
    // `intersection_cost`), labelled `sbvh16-tri0.2`, `bin16-tri0.2` and so on.
    for cost in env_prices("RB_TRI") {
        for (label, base) in [
            ("sbvh16", WideParams::sbvh()),
            ("bin16", WideParams::default()),
        ] {
            add(&format!("{label}-tri{cost}"), &|| {
                let mut p = WideParams {
                    width: 16,
                    ..base.clone()
                };
                p.binary.intersection_cost = cost;
                Box::new(Bvh16::build(Arc::clone(&mesh), &p).expect("builds"))
            });
        }
    }
    let sse = WideParams {
        node_simd: NodeSimd::Sse,
        ..WideParams::default()
    };
    let only_avx2 = WideParams {
        node_simd: NodeSimd::Avx2,
        ..WideParams::default()
    };
    // `RB_PACKETS_AVX2=1`: `bvh16-sbvh-packets` and `bvh8-packets` with every walk compiled for
    // AVX2 alone: packets of eight rays a register, the 8-lane walk of CPUs without AVX-512F.
    if std::env::var_os("RB_PACKETS_AVX2").is_some() {
        let packets_avx2 = |p: WideParams| WideParams {
            coherent_packets: true,
            packet_floors: PacketFloors::MEASURED,
            node_simd: NodeSimd::Avx2,
            ..p
        };
        add("bvh16-sbvh-packets-avx2", &|| {
            let p = packets_avx2(WideParams {
                width: 16,
                ..WideParams::sbvh()
            });
            Box::new(Bvh16::build(Arc::clone(&mesh), &p).expect("builds"))
        });
        add("bvh8-packets-avx2", &|| {
            let p = packets_avx2(WideParams::default());
            Box::new(Bvh8::build(Arc::clone(&mesh), &p).expect("builds"))
        });
    }
    add("bvh8-avx2", &|| {
        Box::new(Bvh8::build(Arc::clone(&mesh), &only_avx2).expect("builds"))
    });
    add("bvh8-sse", &|| {
        Box::new(Bvh8::build(Arc::clone(&mesh), &sse).expect("builds"))
    });

    if let Ok(keep) = std::env::var("RB_ONLY") {
        structures.retain(|(n, _, _)| keep.split(',').any(|k| k == n));
        if structures.is_empty() {
            eprintln!("RB_ONLY={keep}: no structure of this example has that name");
            std::process::exit(2);
        }
    }
    let reference = &structures[0].1;
    let trace = |r: &Ray| {
        reference.intersect(r).map(|h| SurfaceHit {
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    };
    let recipe = RayRecipe::new(&scene, n, 1, &trace);
    let workloads = [Workload::Primary, Workload::Random, Workload::Shadow].map(|w| {
        (
            w.name(),
            recipe.rays(w).expect("a ray workload"),
            w.any_hit(),
        )
    });
    for (name, rays, any_hit) in &workloads {
        if only.as_deref().is_some_and(|o| o != *name) {
            continue;
        }
        let prepared: Vec<PreparedRays> = structures
            .iter()
            .map(|(_, a, _)| {
                // Primary and shadow rays are prepared as the harness prepares them: as a
                // coherent batch.
                if *name == "primary" || *name == "shadow" {
                    a.prepare_coherent_rays(rays).expect("valid rays")
                } else {
                    a.prepare_rays(rays).expect("valid rays")
                }
            })
            .collect();
        let mut out = Answers::for_rays(rays.len());
        let mut rates = vec![Vec::new(); structures.len()];
        for _ in 0..rounds + 1 {
            for (k, (_, accel, _)) in structures.iter().enumerate() {
                rates[k].push(prepared_pass(
                    accel.as_ref(),
                    rays,
                    &prepared[k],
                    *any_hit,
                    &mut out,
                ));
            }
        }
        for r in &mut rates {
            r.remove(0); // the warm-up round
        }
        for (k, (label, _, build_ms)) in structures.iter().enumerate() {
            println!(
                "{name:8} {label:14} {:7.2} Mrays/s  {:5.3}x embree   (build {build_ms:6.1} ms)",
                best(&rates[k]),
                best(&rates[k]) / best(&rates[0])
            );
        }
    }
}
