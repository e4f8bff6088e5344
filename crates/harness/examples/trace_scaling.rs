//! Same-process trace scaling: every structure traces every workload on one thread and on two,
//! the two passes side by side in each round (round r times every structure, in
//! an order rotated by r), through the pass `raybench run` times. Prints, per structure and
//! workload, the median over rounds of (2-thread rate / 1-thread rate): separate runs at
//! `--threads 1` and `--threads 2` moved by ±15 % between them on this shared machine, pairs of
//! passes a moment apart do not. A third pass per round, on one thread in the calls of
//! [`CHUNK`] rays a multi-threaded pass makes, gives the cost of those calls alone (its rate
//! over the one-call pass's: below 1 when a structure pays something per call). Used for the
//! scaling figures in docs/experiments.md ("rayon tasks of at most four chunks", "traversal
//! stacks of the batch paths kept per thread").
//!
//! `cargo run --release -p raybench-harness --example trace_scaling -- SCENE[;SCENE...]
//!  STRUCTURE[,STRUCTURE...] [rounds=9] [rays=100000]`

use raybench_accel::Accel;
use raybench_harness::Registry;
use raybench_harness::pipeline::measure::{Answers, CHUNK, trace_pass};
use raybench_harness::registry::BuildContext;
use raybench_scenes::Workload;
use std::time::Duration;

mod probe;
use probe::{median, primary_hits};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// One pass on this thread in the calls a multi-threaded pass makes, one per [`CHUNK`] rays.
fn chunked_pass(
    a: &dyn Accel,
    rays: &[raybench_geom::Ray],
    p: &raybench_accel::PreparedRays,
    out: &mut Answers,
) -> Duration {
    let start = std::time::Instant::now();
    match out {
        Answers::Closest(h) => {
            for (j, c) in h.chunks_mut(CHUNK).enumerate() {
                a.intersect_prepared(rays, p, j * CHUNK, c);
            }
        }
        Answers::Any(o) => {
            for (j, c) in o.chunks_mut(CHUNK).enumerate() {
                a.occluded_prepared(rays, p, j * CHUNK, c);
            }
        }
    }
    start.elapsed()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut rounds, mut n) = (9usize, 100_000usize);
    for a in &args[2..] {
        match a.split_once('=') {
            Some(("rounds", v)) => rounds = v.parse().expect("rounds=N"),
            Some(("rays", v)) => n = v.parse().expect("rays=N"),
            _ => panic!("unknown argument {a}"),
        }
    }
    let names: Vec<String> = args[1].split(',').map(str::to_string).collect();
    let entries = Registry::builtin().select(&names).expect("structures");
    // One pool for both: the 1-thread pass is the plain loop on one of its workers. With a
    // second pool, its idle workers spun on the cores the other pool's pass needed.
    let two = pool(2);
    println!(
        "scene | structure | workload | 1-thread Mrays/s | 2 threads / 1 thread | 1 thread in calls of {CHUNK} / in one call"
    );
    for spec in args[0].split(';') {
        let scene = raybench_scenes::resolve(spec, 1).expect("scene");
        let mesh = scene.mesh.clone();
        let bounds = mesh.bounds();
        let accels: Vec<Box<dyn Accel>> = entries
            .iter()
            .map(|e| {
                let ctx = BuildContext::new(2);
                two.install(|| e.build(mesh.clone(), &ctx).expect("builds").accel)
            })
            .collect();
        let (primary, _, _) = raybench_scenes::primary_rays(&scene.view, &bounds, n);
        let hits = primary_hits(accels[0].as_ref(), &primary);
        let workloads = [
            (Workload::Primary, primary.clone()),
            (
                Workload::Random,
                raybench_scenes::random_rays(&bounds, n, 1),
            ),
            (
                Workload::Shadow,
                raybench_scenes::shadow_rays(&mesh, scene.view.light, &primary, &hits),
            ),
            (
                Workload::Diffuse,
                raybench_scenes::diffuse_rays(&mesh, &primary, &hits, 1),
            ),
        ];
        for (workload, rays) in &workloads {
            let any_hit = *workload == Workload::Shadow;
            let prepared: Vec<_> = accels
                .iter()
                .map(|a| {
                    if workload.coherent() {
                        a.prepare_coherent_rays(rays)
                    } else {
                        a.prepare_rays(rays)
                    }
                    .expect("valid rays")
                })
                .collect();
            let mut out = Answers::new(any_hit, rays.len());
            let mut rate1 = vec![Vec::new(); accels.len()];
            let mut ratio = vec![Vec::new(); accels.len()];
            let mut chunked = vec![Vec::new(); accels.len()];
            let rate = |d: Duration| rays.len() as f64 / d.as_secs_f64() / 1e6;
            // One untimed pass each, both ways, so caches and workers are warm.
            for (a, p) in accels.iter().zip(&prepared) {
                two.install(|| trace_pass(a.as_ref(), rays, p, 1, &mut out));
                two.install(|| trace_pass(a.as_ref(), rays, p, 2, &mut out));
            }
            for round in 0..rounds {
                for k in 0..accels.len() {
                    let i = (k + round) % accels.len();
                    let (a, p) = (accels[i].as_ref(), &prepared[i]);
                    // Which pool goes first alternates too.
                    let (r1, r2) = if round % 2 == 0 {
                        let r1 = rate(two.install(|| trace_pass(a, rays, p, 1, &mut out)));
                        (
                            r1,
                            rate(two.install(|| trace_pass(a, rays, p, 2, &mut out))),
                        )
                    } else {
                        let r2 = rate(two.install(|| trace_pass(a, rays, p, 2, &mut out)));
                        (
                            rate(two.install(|| trace_pass(a, rays, p, 1, &mut out))),
                            r2,
                        )
                    };
                    let rc = rate(two.install(|| chunked_pass(a, rays, p, &mut out)));
                    rate1[i].push(r1);
                    ratio[i].push(r2 / r1);
                    chunked[i].push(rc / r1);
                }
            }
            for (i, e) in entries.iter().enumerate() {
                println!(
                    "{spec} | {} | {} | {:.2} | {:.2} | {:.2}",
                    e.name,
                    workload.name(),
                    median(rate1[i].clone()),
                    median(ratio[i].clone()),
                    median(chunked[i].clone())
                );
            }
        }
    }
}
