//! Prints, per scene and per reinsertion setting, the 8-wide tree's build time (median of 5)
//! and the binary SAH cost before and after the optimizer, with its rounds and moves (how the
//! `Reinsertion` defaults were chosen):
//! `cargo run --release -p raybench-harness --example reinsert -- SCENE...` (generator specs
//! or .obj paths).
use raybench_accel::Accel;
use raybench_bvh::{Bvh8, Reinsertion, WideParams};
use std::time::Instant;

fn main() {
    let settings: Vec<Option<Reinsertion>> = vec![
        None,
        Some(Reinsertion::default()),
        Some(Reinsertion {
            batch_fraction: 0.005,
            ..Reinsertion::default()
        }),
        Some(Reinsertion {
            batch_fraction: 0.02,
            ..Reinsertion::default()
        }),
        Some(Reinsertion {
            batch_fraction: 0.05,
            max_rounds: 8,
            ..Reinsertion::default()
        }),
        Some(Reinsertion {
            min_round_gain: 0.0,
            max_rounds: 32,
            ..Reinsertion::default()
        }),
    ];
    for spec in std::env::args().skip(1) {
        let mesh = if spec.ends_with(".obj") {
            raybench_scenes::load_obj(std::path::Path::new(&spec))
                .expect("load")
                .mesh
        } else {
            raybench_scenes::generate(&spec, 1).expect("scene").mesh
        };
        for r in &settings {
            let mut p = WideParams::for_width(8);
            p.binary.reinsertion = *r;
            let mut times = Vec::new();
            let mut stats = None;
            for _ in 0..5 {
                let t = Instant::now();
                let b = Bvh8::build(mesh.clone(), &p).expect("build");
                times.push(t.elapsed().as_secs_f64() * 1e3);
                stats = Some(b.build_stats());
            }
            times.sort_by(f64::total_cmp);
            let s = stats.expect("built");
            let x = |k: &str| s.extra.get(k).copied().unwrap_or(f64::NAN);
            println!(
                "{:40} {:>44} {:8.1} ms  wide SAH {:9.3}  binary SAH {:9.3} -> {:9.3}  rounds {:3} moves {:6}",
                spec.rsplit('/').next().unwrap_or(&spec),
                r.map_or("off".to_string(), |r| format!(
                    "batch {} rounds {} min {}",
                    r.batch_fraction, r.max_rounds, r.min_round_gain
                )),
                times[2],
                s.sah_cost.unwrap_or(0.0),
                x("reinsert_sah_before"),
                x("reinsert_sah_after"),
                x("reinsert_rounds"),
                x("reinsert_moves"),
            );
        }
    }
}
