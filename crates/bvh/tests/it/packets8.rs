//! The eight-lane packet walk (AVX2, `packets8.rs`), held to `NodeSimd::Avx2` so that a CPU
//! with AVX-512F runs it too (there the other tests walk sixteen lanes): under the shared
//! conformance suite, and ray for ray against the single-ray walk, closest and any hit, on the
//! seeded and edge cases, camera rays and shadow rays. Without AVX2 nothing is walked in
//! packets, and the tests say so.

use raybench_accel::Accel;
use raybench_bvh::{Bvh8, BvhWide, NodeSimd, WideParams};
use raybench_testkit::{
    camera_ray_sets, conformance, edge_cases, occlusion_packets_against_single_rays,
    packets_against_single_rays, seeded_cases, shadow_ray_sets, valid_rays,
};

fn eight_lanes(width: u32) -> WideParams {
    WideParams {
        coherent_packets: true,
        node_simd: NodeSimd::Avx2,
        ..WideParams::for_width(width)
    }
}

/// Whether this CPU walks eight-lane packets; says so when it does not.
fn runs_here<const W: usize>(bvh: &BvhWide<W>) -> bool {
    let lanes = bvh.packet_lanes();
    #[cfg(target_arch = "x86_64")]
    assert_eq!(
        lanes.is_some(),
        std::arch::is_x86_feature_detected!("avx2"),
        "the packet walk runs exactly where AVX2 does"
    );
    match lanes {
        Some(lanes) => {
            assert_eq!(lanes, 8, "NodeSimd::Avx2 walks eight lanes");
            true
        }
        None => {
            eprintln!("no AVX2 on this CPU: batches go ray by ray");
            false
        }
    }
}

#[test]
fn eight_lane_packets_conform_and_answer_as_single_rays_on_every_case() {
    fn at<const W: usize>()
    where
        BvhWide<W>: Accel<Params = WideParams>,
    {
        let params = eight_lanes(W as u32);
        let counts = conformance::<BvhWide<W>>(&params, &|b, mesh| b.validate(mesh));
        assert_eq!(counts.mismatch, 0, "{W} wide");
        assert!(counts.exact > 10_000, "{counts:?}");
        for case in seeded_cases().into_iter().chain(edge_cases()) {
            let bvh = BvhWide::<W>::build(case.mesh.clone(), &params).expect("builds");
            if !runs_here(&bvh) {
                return;
            }
            let rays = valid_rays(&case);
            packets_against_single_rays(&bvh, &case.mesh, &rays, &case.name);
            occlusion_packets_against_single_rays(&bvh, &rays, &case.name);
        }
    }
    at::<8>();
    at::<4>();
    at::<16>();
}

/// Camera rays from views whose packets span octants, and shadow rays from their hits: every
/// ray's closest hit is the single-ray walk's, bit for bit but for exact ties, and every
/// occlusion answer is; the counts are asserted so the test cannot pass on nothing.
#[test]
fn eight_lane_packets_answer_camera_and_shadow_rays_as_single_rays() {
    let (mut hits, mut occluded, mut shadow_rays) = (0usize, 0usize, 0usize);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair",
        "plane:quads=64",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 4).expect("generates");
        let bvh = Bvh8::build(scene.mesh.clone(), &eight_lanes(8)).expect("builds");
        if !runs_here(&bvh) {
            return;
        }
        bvh.validate(&scene.mesh).expect("valid");
        for rays in camera_ray_sets(&scene, 10_000) {
            let prepared = bvh.prepare_coherent_rays(&rays).expect("rays are valid");
            assert!(matches!(prepared, raybench_accel::PreparedRays::Foreign(_)));
            hits += packets_against_single_rays(&bvh, &scene.mesh, &rays, spec).0;
        }
        for rays in shadow_ray_sets(&scene, &bvh, 6_000) {
            occluded += occlusion_packets_against_single_rays(&bvh, &rays, spec);
            shadow_rays += rays.len();
        }
        let bvh16 = BvhWide::<16>::build(scene.mesh.clone(), &eight_lanes(16)).expect("builds");
        bvh16.validate(&scene.mesh).expect("valid");
        for rays in camera_ray_sets(&scene, 10_000) {
            hits += packets_against_single_rays(&bvh16, &scene.mesh, &rays, spec).0;
        }
    }
    eprintln!(
        "eight lanes: {hits} identical hits, {occluded} of {shadow_rays} shadow rays occluded"
    );
    assert!(hits > 50_000, "only {hits} hits");
    assert!(occluded > 3_000, "only {occluded} occluded");
    assert!(
        shadow_rays - occluded > 3_000,
        "only {} unoccluded",
        shadow_rays - occluded
    );
}
