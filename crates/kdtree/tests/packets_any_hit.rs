//! `kd-packets` on coherent any-hit batches: every ray's answer is its single-ray `occluded`'s,
//! on the seeded cases and edge cases and on shadow rays from camera hits (rays starting on
//! surfaces, finite `t` ranges, packets spanning octants), in ranges that end inside a packet and
//! that start off a packet boundary (the testkit helper). On a CPU without AVX2 the batches
//! go ray by ray and the checks still hold.

use raybench_accel::Accel;
use raybench_kdtree::{KdParams, KdTree};
use raybench_testkit::{
    edge_cases, occlusion_packets_against_single_rays, seeded_cases, shadow_ray_sets, valid_rays,
};

#[test]
fn any_hit_packets_answer_as_single_rays_on_every_case() {
    for case in seeded_cases().into_iter().chain(edge_cases()) {
        let kd = KdTree::build(case.mesh.clone(), &KdParams::packets()).expect("builds");
        kd.validate(&case.mesh)
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        occlusion_packets_against_single_rays(&kd, &valid_rays(&case), &case.name);
    }
}

#[test]
fn any_hit_packets_answer_shadow_rays_as_single_rays() {
    let (mut seen, mut occluded) = (0, 0);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair",
        "plane:quads=64",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let kd = KdTree::build(scene.mesh.clone(), &KdParams::packets()).expect("builds");
        kd.validate(&scene.mesh).expect("valid");
        if !kd.packet_walk() {
            eprintln!("no AVX2 on this CPU: batches go ray by ray");
        }
        for rays in shadow_ray_sets(&scene, &kd, 6_000) {
            occluded += occlusion_packets_against_single_rays(&kd, &rays, spec);
            seen += rays.len();
        }
    }
    eprintln!("shadow rays: {seen}, {occluded} occluded");
    assert!(
        occluded > 5_000 && seen - occluded > 5_000,
        "{seen} rays, {occluded} occluded"
    );
}
