//! Prints the SAH cost and build time of the sweep builder and of the binned builder at 8, 16,
//! 32 and 64 bins on an OBJ file (how the `bins` default was chosen):
//! `cargo run --release -p raybench-harness --example sah -- FILE.obj`.
use raybench_accel::Accel;
use raybench_bvh::{Bvh, BvhParams};
use std::time::Instant;

fn main() {
    let path = std::env::args().nth(1).expect("usage: sah FILE.obj");
    let scene = raybench_scenes::load_obj(std::path::Path::new(&path)).expect("load");
    let mut configs: Vec<(String, BvhParams)> = vec![("sweep".into(), BvhParams::sweep())];
    for bins in [8, 16, 32, 64] {
        configs.push((
            format!("binned bins={bins}"),
            BvhParams {
                bins,
                ..BvhParams::binned()
            },
        ));
    }
    for (name, p) in configs {
        let t = Instant::now();
        let bvh = Bvh::build(scene.mesh.clone(), &p).expect("build");
        let ms = t.elapsed().as_secs_f64() * 1e3;
        println!(
            "{name:28} SAH {:.3}  {ms:.1} ms",
            bvh.build_stats().sah_cost.unwrap_or(0.0)
        );
    }
}
