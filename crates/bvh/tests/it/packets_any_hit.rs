//! The any-hit packet walk of coherent batches (`coherent_packets`, `occluded_prepared` on a
//! batch from `prepare_coherent_rays`): every ray's answer is its single-ray `occluded`'s, bit for
//! bit — on the seeded cases and edge cases, on shadow rays from camera hits (rays starting on
//! surfaces, finite `t` ranges, several octants per packet), on camera rays cut to `t` windows,
//! in ranges that end inside a packet and that start off a packet boundary. On a CPU without
//! AVX2 the batches are traced ray by ray and the checks still hold (and say so).

use raybench_accel::Accel;
use raybench_bvh::{Bvh8, BvhWide, WideParams};
use raybench_geom::Ray;
use raybench_testkit::{
    camera_ray_sets, edge_cases, occlusion_packets_against_single_rays, seeded_cases,
    shadow_ray_sets, valid_rays,
};

fn packets(width: u32) -> WideParams {
    WideParams {
        coherent_packets: true,
        ..WideParams::for_width(width)
    }
}

#[test]
fn any_hit_packets_answer_as_single_rays_on_every_case() {
    fn at<const W: usize>()
    where
        BvhWide<W>: Accel<Params = WideParams>,
    {
        for case in seeded_cases().into_iter().chain(edge_cases()) {
            let bvh = BvhWide::<W>::build(case.mesh.clone(), &packets(W as u32)).expect("builds");
            bvh.validate(&case.mesh)
                .unwrap_or_else(|e| panic!("{}: {e}", case.name));
            let rays = valid_rays(&case);
            occlusion_packets_against_single_rays(&bvh, &rays, &case.name);
        }
    }
    at::<8>();
    at::<4>();
}

/// Shadow rays as the `shadow` workload makes them, on scenes of every kind: many are occluded
/// and many are not, so both answers are exercised; counts of rays and packets that span
/// octants are asserted so the test cannot pass on nothing.
#[test]
fn any_hit_packets_answer_shadow_rays_as_single_rays() {
    let (mut rays_seen, mut occluded, mut mixed) = (0usize, 0usize, 0usize);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair",
        "plane:quads=64",
        "sphere:triangles=5000",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let bvh = Bvh8::build(scene.mesh.clone(), &packets(8)).expect("builds");
        bvh.validate(&scene.mesh).expect("valid");
        if !bvh.packet_walk() {
            eprintln!("no AVX2 on this CPU: batches go ray by ray");
        }
        for rays in shadow_ray_sets(&scene, &bvh, 8_000) {
            occluded += occlusion_packets_against_single_rays(&bvh, &rays, spec);
            rays_seen += rays.len();
            mixed += rays.chunks(16).filter(|c| spans_octants(c)).count();
        }
    }
    eprintln!("shadow rays: {rays_seen}, {occluded} occluded, {mixed} packets span octants");
    assert!(occluded > 5_000, "only {occluded} occluded rays");
    assert!(
        rays_seen - occluded > 5_000,
        "only {} unoccluded",
        rays_seen - occluded
    );
    assert!(mixed > 20, "only {mixed} packets span octants");
}

/// Camera rays whose `t` window is cut to a slice of the scene's depth (different per ray):
/// rays whose blocker lies before `t_min` or after `t_max` must not report it.
#[test]
fn any_hit_packets_respect_t_windows() {
    let scene = raybench_testkit::scenes::generate("city", 5).expect("generates");
    let bvh = Bvh8::build(scene.mesh.clone(), &packets(8)).expect("builds");
    let oracle =
        raybench_accel::BruteForce::build(scene.mesh.clone(), &Default::default()).expect("builds");
    let extent = scene.mesh.bounds().diagonal();
    let (mut occluded, mut cut) = (0, 0);
    for rays in camera_ray_sets(&scene, 6_000) {
        let windowed: Vec<Ray> = rays
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let len = r.dir().length();
                let t_min = extent * (i % 7) as f32 / (10.0 * len);
                let t_max = t_min + extent * (1 + i % 5) as f32 / (10.0 * len);
                Ray::new(r.origin(), r.dir(), t_min, t_max)
            })
            .collect();
        occluded += occlusion_packets_against_single_rays(&bvh, &windowed, "city windows");
        // The window changes answers: some ray that would hit without it does not with it.
        cut += rays
            .iter()
            .zip(&windowed)
            .filter(|(r, w)| oracle.occluded(r) && !oracle.occluded(w))
            .count();
        for w in windowed.iter().step_by(7) {
            assert_eq!(bvh.occluded(w), oracle.occluded(w), "{w:?}");
        }
    }
    assert!(
        occluded > 1_000 && cut > 1_000,
        "{occluded} occluded, {cut} cut by their window"
    );
}

/// The single-leaf tree, a partial last packet of one ray, and no triangles at all.
#[test]
fn any_hit_packets_on_tiny_batches() {
    let scene = raybench_testkit::scenes::generate("sphere:triangles=200", 1).expect("generates");
    let oracle =
        raybench_accel::BruteForce::build(scene.mesh.clone(), &Default::default()).expect("builds");
    let shadow = shadow_ray_sets(&scene, &oracle, 400);
    for mesh in [scene.mesh.clone(), raybench_testkit::mesh(vec![], vec![])] {
        let bvh = Bvh8::build(mesh.clone(), &packets(8)).expect("builds");
        bvh.validate(&mesh).expect("valid");
        for rays in &shadow {
            for n in [1, 15, 16, 17] {
                occlusion_packets_against_single_rays(&bvh, &rays[..n], "tiny");
            }
        }
    }
}

fn spans_octants(c: &[Ray]) -> bool {
    let octant = |r: &Ray| r.inv_dir().to_array().map(|x| x < 0.0);
    c.iter().any(|r| octant(r) != octant(&c[0]))
}
