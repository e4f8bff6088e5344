//! Coherent any-hit batches: shadow rays as the `shadow` workload makes them (from the primary
//! rays' hits in scanline order, towards the scene's light), and the check that a structure's
//! coherent any-hit path answers every ray as its single-ray `occluded`.

use raybench_accel::Accel;
use raybench_geom::Ray;
use raybench_scenes::{Scene, SurfaceHit, shadow_rays};

/// Shadow rays of both camera ray sets of [`crate::camera_ray_sets`] (about `n` primary rays
/// each): the primary rays are traced with `primary` (a structure that passed the conformance
/// suite, so that large scenes need not go through brute force), and every hit that faces the
/// light gives one ray from just off the surface to just short of the light, in pixel order.
/// Rays start on surfaces and have finite `t` ranges.
pub fn shadow_ray_sets(scene: &Scene, primary_tracer: &dyn Accel, n: usize) -> [Vec<Ray>; 2] {
    crate::camera_ray_sets(scene, n).map(|primary| {
        let hits: Vec<Option<SurfaceHit>> = primary
            .iter()
            .map(|r| {
                primary_tracer.intersect(r).map(|h| SurfaceHit {
                    prim: h.prim,
                    u: h.u,
                    v: h.v,
                })
            })
            .collect();
        shadow_rays(&scene.mesh, scene.view.light, &primary, &hits)
    })
}

/// Traces `rays[first..end]` as a coherent any-hit batch (`prepare_coherent_rays` over all of
/// `rays`, then `occluded_prepared` from `first`) for each `(first, end)` of a few ranges,
/// including ones that end inside a packet of sixteen and one that does not start on a packet,
/// and panics unless every answer is the single-ray `occluded`'s. Returns how many of `rays`
/// are occluded.
pub fn occlusion_packets_against_single_rays<A: Accel>(
    accel: &A,
    rays: &[Ray],
    what: &str,
) -> usize {
    let prepared = accel.prepare_coherent_rays(rays).expect("rays are valid");
    let single: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
    let n = rays.len();
    let ranges = [
        (0, n),
        (0, n / 2),
        (16.min(n), n),
        (32.min(n), n.min(37)),
        (5.min(n), n),
    ];
    for (first, end) in ranges {
        let mut out = vec![false; end - first];
        accel.occluded_prepared(rays, &prepared, first, &mut out);
        for (k, (&o, &s)) in out.iter().zip(&single[first..end]).enumerate() {
            assert_eq!(
                o,
                s,
                "{what}: coherent any-hit batch [{first}..{end}) on ray {} {:08x?}",
                first + k,
                rays[first + k].to_bits()
            );
        }
    }
    single.iter().filter(|&&o| o).count()
}
