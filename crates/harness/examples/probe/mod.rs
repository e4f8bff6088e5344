//! What the knob probes (`grid2tune`, `octtune`, `skiptune`; `trace_scaling` and `sbvh_tune`
//! for their median and primary hits) share: a scene with its seeded random and primary rays,
//! the primary rays' hits, a median, and timed passes (`wide` and `placement` for the pass over
//! prepared rays).

use raybench_accel::{Accel, Counters, Hit, PreparedRays};
use raybench_geom::{Ray, TriangleMesh};
use std::sync::Arc;
use std::time::Instant;

/// The scene `spec` (an .obj path or a generator spec, seed 1) with `n` seeded random rays and
/// `n` primary rays from its view.
#[allow(dead_code)]
pub fn scene_rays(spec: &str, n: usize) -> (Arc<TriangleMesh>, Vec<Ray>, Vec<Ray>) {
    let scene = raybench_scenes::resolve(spec, 1).expect("scene");
    let mesh = Arc::clone(&scene.mesh);
    let random = raybench_scenes::random_rays(&mesh.bounds(), n, 1);
    let (primary, _, _) = raybench_scenes::primary_rays(&scene.view, &mesh.bounds(), n);
    (mesh, random, primary)
}

/// Where `a` finds each primary ray's closest hit: what the shadow and diffuse workloads start
/// from.
#[allow(dead_code)]
pub fn primary_hits(a: &dyn Accel, primary: &[Ray]) -> Vec<Option<raybench_scenes::SurfaceHit>> {
    primary
        .iter()
        .map(|r| {
            a.intersect(r).map(|h| raybench_scenes::SurfaceHit {
                prim: h.prim,
                u: h.u,
                v: h.v,
            })
        })
        .collect()
}

/// The median of `v` (the upper one of an even count).
#[allow(dead_code)]
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Mrays/s of `a` on `rays`, the median of `reps` timed passes (at least 3), and the counters
/// of one counted pass.
#[allow(dead_code)]
pub fn time<A: Accel>(a: &A, rays: &[Ray], reps: usize) -> (f64, Counters) {
    let times = (0..reps.max(3))
        .map(|_| {
            let t = Instant::now();
            let hits = rays.iter().filter(|r| a.intersect(r).is_some()).count();
            std::hint::black_box(hits);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let mut c = Counters::default();
    for r in rays {
        a.intersect_counted(r, &mut c);
    }
    (rays.len() as f64 / median(times) / 1e6, c)
}

/// Where a pass over prepared rays writes its answers: made once, before the timed passes, so
/// no pass pays for a fresh allocation or its page faults (as in the harness's rounds).
#[allow(dead_code)]
pub struct Answers {
    pub hits: Vec<Option<Hit>>,
    pub occluded: Vec<bool>,
}

#[allow(dead_code)]
impl Answers {
    pub fn for_rays(n: usize) -> Answers {
        Answers {
            hits: vec![None; n],
            occluded: vec![false; n],
        }
    }
}

/// Mrays/s of one pass of `a` over `rays` as prepared (closest hit, or any hit), through the
/// batch calls the harness times.
#[allow(dead_code)]
pub fn prepared_pass(
    a: &dyn Accel,
    rays: &[Ray],
    prepared: &PreparedRays,
    any_hit: bool,
    out: &mut Answers,
) -> f64 {
    let start = Instant::now();
    if any_hit {
        a.occluded_prepared(rays, prepared, 0, &mut out.occluded[..rays.len()]);
        std::hint::black_box(&out.occluded);
    } else {
        a.intersect_prepared(rays, prepared, 0, &mut out.hits[..rays.len()]);
        std::hint::black_box(&out.hits);
    }
    rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6
}
