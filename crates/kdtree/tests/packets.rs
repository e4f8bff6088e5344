//! `kd-packets`: the packet walk of coherent batches under the shared suite (whose
//! coherent-batch check holds it to brute force), and answer for answer against the single-ray
//! walk: each lane makes its ray's single-ray choices at every plane and tests its triangles with
//! the same arithmetic, so answers are identical but for exact ties between two triangles
//! (a leaf's triangles are met in lane order by the packet, nearest-lane-first by a single ray).

use raybench_accel::{Accel, PreparedRays};
use raybench_kdtree::{KdParams, KdTree};
use raybench_testkit::{conformance, packets_against_single_rays};

#[test]
fn packet_walk_conforms() {
    let params = KdParams::packets();
    let counts = conformance::<KdTree>(&params, &|kd, mesh| kd.validate(mesh));
    assert_eq!(counts.mismatch, 0);
    for case in raybench_testkit::seeded_cases()
        .into_iter()
        .chain(raybench_testkit::edge_cases())
    {
        let kd = KdTree::build(case.mesh.clone(), &params).expect("builds");
        let rays = raybench_testkit::valid_rays(&case);
        packets_against_single_rays(&kd, &case.mesh, &rays, &case.name);
    }
}

/// Camera rays in scanline order on scenes of every kind, from the scene's view and from an eye
/// inside the scene looking along an axis (so packets span octants and rays start inside the
/// root cell). Returns without checking (and says so) on a CPU without AVX2 (sixteen lanes with AVX-512F, eight with AVX2 alone).
#[test]
fn packet_walk_answers_camera_rays_as_the_single_ray_walk() {
    let params = KdParams::packets();
    let (mut hits, mut ties) = (0usize, 0usize);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair:triangles=20000",
        "plane:quads=64",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let mesh = scene.mesh.clone();
        let kd = KdTree::build(mesh.clone(), &params).expect("builds");
        if !kd.packet_walk() {
            eprintln!("no AVX2 on this CPU: the packet walk is not used, nothing to compare");
            return;
        }
        for rays in raybench_testkit::camera_ray_sets(&scene, 20_000) {
            let prepared = kd.prepare_coherent_rays(&rays).expect("rays are valid");
            assert!(matches!(prepared, PreparedRays::Foreign(_)));
            let (h, t) = packets_against_single_rays(&kd, &mesh, &rays, spec);
            hits += h;
            ties += t;
        }
    }
    eprintln!("camera rays: {hits} identical hits, {ties} ties");
    assert!(hits > 50_000, "only {hits} hits: the test proves little");
}
