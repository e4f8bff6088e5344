//! Knob exploration for the octree: builds `octree` on each scene with the knobs given as
//! `key=value` arguments (median of several builds on the global rayon pool), and traces seeded
//! random and primary-style rays, printing build time, shape, Mrays/s and counters per ray next
//! to `bvh-binned` on the same rays in the same process (same-run ratios: this machine is shared
//! and noisy). Used to choose the defaults documented on `OctreeParams`.
//!
//! `cargo run --release -p raybench-harness --example octtune -- SCENE[,SCENE...] [obj=8]
//!  [depth=20] [ct=1] [rays=100000] [reps=3] [builds=5]`

use raybench_accel::Accel;
use raybench_octree::{Octree, OctreeParams};
use std::sync::Arc;
use std::time::Instant;

mod probe;

use probe::{median, scene_rays, time};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut p = OctreeParams::default();
    let (mut rays_n, mut reps, mut builds) = (100_000usize, 3usize, 5usize);
    for a in &args[1..] {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "par" => p.parallel_threshold = v.parse().unwrap(),
            "obj" => p.max_obj = v.parse().unwrap(),
            "depth" => p.max_depth = Some(v.parse().unwrap()),
            "ct" => p.traversal_cost = v.parse().unwrap(),
            "rays" => rays_n = v.parse().unwrap(),
            "reps" => reps = v.parse().unwrap(),
            "builds" => builds = v.parse().unwrap(),
            _ => panic!("unknown knob {k}"),
        }
    }
    for spec in args[0].split(',') {
        let (mesh, random, primary) = scene_rays(spec, rays_n);
        let mut bt = Vec::new();
        let mut oct = None;
        for _ in 0..builds.max(1) {
            let t = Instant::now();
            let o = Octree::build(Arc::clone(&mesh), &p).expect("builds");
            bt.push(t.elapsed().as_secs_f64() * 1e3);
            oct = Some(o);
        }
        let oct = oct.unwrap();
        let mut bb = Vec::new();
        let mut bvh = None;
        for _ in 0..builds.max(1) {
            let t = Instant::now();
            let b = raybench_bvh::Bvh::build(Arc::clone(&mesh), &raybench_bvh::BvhParams::binned())
                .unwrap();
            bb.push(t.elapsed().as_secs_f64() * 1e3);
            bvh = Some(b);
        }
        let bvh = bvh.unwrap();
        let s = oct.build_stats();
        println!(
            "{spec} n={} octree build {:.1} ms (bvh-binned {:.1}) nodes {} depth {} refs/tri {:.2} max/leaf {} at-max-depth {} over64-apart {} mem {:.1} MB",
            mesh.len(),
            median(bt),
            median(bb),
            s.nodes,
            s.max_depth,
            s.extra["refs_per_triangle"],
            s.extra["max_refs_per_leaf"],
            s.extra["leaves_at_max_depth"],
            s.extra["leaves_over_64_not_sharing_a_point"],
            oct.memory().total() as f64 / 1e6,
        );
        for (name, rays) in [("random", &random), ("primary", &primary)] {
            let (b, _) = time(&bvh, rays, reps);
            let (m, c) = time(&oct, rays, reps);
            let n = rays.len() as f64;
            println!(
                "  {name:8} octree {m:6.2} Mr/s ({:.2}× bvh) nodes {:6.1} leaves {:5.1} tests {:7.1}",
                m / b,
                c.nodes as f64 / n,
                c.leaves as f64 / n,
                c.prim_tests as f64 / n,
            );
        }
    }
}
