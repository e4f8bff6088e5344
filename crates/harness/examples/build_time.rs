//! Times the builds of the binary BVH, the 8-wide BVH and embree-medium on one scene with a
//! given number of threads, outside the harness, for before/after checks of builder changes on
//! a shared, noisy machine. Each round builds every structure once, interleaved; the figures
//! printed are each structure's median over the rounds and its ratio to Embree's median, so
//! ratios come from the same run.
//!
//! Threads: ours run in a rayon pool of `threads` workers; Embree ignores rayon (it has its own
//! TBB workers), so its device gets the same count through `threads=N` in its config, as the
//! harness does (`Workers::start`). The device is created before the first timed build and
//! kept alive, so no timed build pays for Embree's thread start-up.
//!
//! `bvh-bin4` is the binary tree the 8-wide BVH is collapsed from (`WideParams::default()`'s
//! `binary` knobs) built and flattened on its own: the difference to `bvh8` is the collapse and
//! the `Tri4` leaves; `bvh-sbvh` is the binary tree `bvh8-sbvh` is collapsed from (spatial
//! splits at their defaults). The digests identify the trees (nodes and triangle order), to check
//! that a builder change keeps them identical, and with any thread count.
//!
//! `cargo run --release -p raybench-harness --example build_time -- ../shared/scenes/stanford-bunny.obj 2 21`
//! (scene: an .obj path or a generator spec such as `city`; threads; rounds; optionally a label
//! filter). Under `valgrind --tool=callgrind` use 1 round. `GAP_MS=N` in the environment sleeps
//! N ms before each timed build, so that no pool's idle workers (rayon's, or Embree's own
//! after its build) are still spinning when the next build starts.

use raybench_accel::Accel;
use raybench_bvh::{Bvh, Bvh8, BvhParams, Collapse, WideParams};
use raybench_embree::{Device, EmbreeParams, EmbreeScene};
use std::sync::Arc;
use std::time::Instant;

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let mid = s.len() / 2;
    if s.len().is_multiple_of(2) {
        (s[mid - 1] + s[mid]) / 2.0
    } else {
        s[mid]
    }
}

/// FNV-1a over the nodes' planes and children and the triangle order.
fn digest(bvh: &Bvh) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u32| {
        h ^= x as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    };
    for n in bvh.nodes() {
        n.planes.iter().flatten().for_each(|f| eat(f.to_bits()));
        n.child.iter().for_each(|c| {
            eat(c.index);
            eat(c.count);
        });
    }
    bvh.prim_ids().iter().for_each(|&i| eat(i));
    h
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or("../shared/scenes/stanford-bunny.obj".into());
    let threads: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(11);
    // Only the structures whose label contains this (embree-medium is always built, as the
    // base of the ratios), to profile one build alone.
    let only = args.next();
    // An .obj path, or a generator spec as the harness takes them (`hair`, `soup:triangles=5000`).
    let scene = raybench_scenes::resolve(&path, 1).expect("scene loads");
    let mesh = Arc::clone(&scene.mesh);

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let embree = EmbreeParams {
        threads,
        ..EmbreeParams::medium()
    };
    let _device = Device::shared(&embree.config_string()).expect("Embree device");
    let binned = BvhParams::binned();
    let wide = WideParams::default();
    let greedy = WideParams {
        collapse: Collapse::Greedy,
        ..WideParams::default()
    };
    let bin4 = wide.binary.clone();
    let sbvh = WideParams::sbvh().binary;

    type Build<'a> = Box<dyn Fn() -> Box<dyn Accel> + Sync + 'a>;
    let structures: Vec<(&str, Build)> = vec![
        (
            "embree-medium",
            Box::new(|| Box::new(EmbreeScene::build(Arc::clone(&mesh), &embree).expect("builds"))),
        ),
        (
            "bvh-binned",
            Box::new(|| Box::new(Bvh::build(Arc::clone(&mesh), &binned).expect("builds"))),
        ),
        (
            "bvh-bin4",
            Box::new(|| Box::new(Bvh::build(Arc::clone(&mesh), &bin4).expect("builds"))),
        ),
        (
            "bvh-sbvh",
            Box::new(|| Box::new(Bvh::build(Arc::clone(&mesh), &sbvh).expect("builds"))),
        ),
        (
            "bvh8",
            Box::new(|| Box::new(Bvh8::build(Arc::clone(&mesh), &wide).expect("builds"))),
        ),
        (
            "bvh8-greedy",
            Box::new(|| Box::new(Bvh8::build(Arc::clone(&mesh), &greedy).expect("builds"))),
        ),
    ];
    let structures: Vec<_> = structures
        .into_iter()
        .enumerate()
        .filter(|(k, (label, _))| *k == 0 || only.as_deref().is_none_or(|o| label.contains(o)))
        .map(|(_, s)| s)
        .collect();
    let gap = std::time::Duration::from_millis(
        std::env::var("GAP_MS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0),
    );
    let mut ms = vec![Vec::new(); structures.len()];
    pool.install(|| {
        // Round 0 warms up (page faults, caches, rayon's workers) and is not counted.
        for round in 0..=rounds {
            for (k, (_, build)) in structures.iter().enumerate() {
                std::thread::sleep(gap);
                let start = Instant::now();
                let built = build();
                let elapsed = start.elapsed().as_secs_f64() * 1e3;
                drop(built);
                if round > 0 {
                    ms[k].push(elapsed);
                }
            }
        }
    });
    let name = std::path::Path::new(&path)
        .file_stem()
        .map_or(path.clone(), |s| s.to_string_lossy().into_owned());
    let base = median(&ms[0]);
    for (k, (label, _)) in structures.iter().enumerate() {
        let m = median(&ms[k]);
        println!(
            "{name:22} t={threads} {label:14} {m:8.2} ms  {:5.3}x embree",
            m / base
        );
    }
    pool.install(|| {
        let b = Bvh::build(Arc::clone(&mesh), &binned).expect("builds");
        let b4 = Bvh::build(Arc::clone(&mesh), &bin4).expect("builds");
        let s = Bvh::build(Arc::clone(&mesh), &sbvh).expect("builds");
        let w = Bvh8::build(Arc::clone(&mesh), &wide).expect("builds");
        let sah = |a: &dyn Accel| a.build_stats().sah_cost.unwrap_or(f64::NAN);
        println!(
            "{name:22} t={threads} digest binned {:016x} bin4 {:016x} sbvh {:016x}  sah binned {:.6} bin4 {:.6} sbvh {:.6} bvh8 {:.6}",
            digest(&b),
            digest(&b4),
            digest(&s),
            sah(&b),
            sah(&b4),
            sah(&s),
            sah(&w)
        );
    });
}
