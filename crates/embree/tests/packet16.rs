//! `embree-medium-packet16` against `embree-medium` ray for ray: coherent batches traced through
//! `rtcIntersect16`/`rtcOccluded16` give the answers of `rtcIntersect1`/`rtcOccluded1` on camera
//! rays and on shadow rays from their hits (rays starting on surfaces, finite `t` ranges), in
//! ranges ending inside a packet. Where an answer differs it must be a tie or within tolerance
//! of brute force's, as between any two structures; the counts of identical answers are asserted
//! so that the test cannot pass on nothing.

use raybench_accel::classify::{Tolerance, Verdict, classify, classify_occlusion};
use raybench_accel::{Accel, BruteForce, Hit};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::{Ray, TriangleMesh};
use raybench_testkit::{camera_ray_sets, occlusion_packets_against_single_rays, shadow_ray_sets};

/// Traces `rays` as one coherent batch from `first` and compares with `reference` ray by ray;
/// returns the answers identical to the reference's.
fn closest_agree(
    packet16: &EmbreeScene,
    reference: &EmbreeScene,
    oracle: &BruteForce,
    mesh: &TriangleMesh,
    rays: &[Ray],
    first: usize,
) -> usize {
    let prepared = packet16.prepare_coherent_rays(rays).expect("valid rays");
    let mut out: Vec<Option<Hit>> = vec![None; rays.len() - first];
    packet16.intersect_prepared(rays, &prepared, first, &mut out);
    let mut same = 0;
    for (r, o) in rays[first..].iter().zip(&out) {
        let expected = reference.intersect(r);
        if *o == expected {
            same += 1;
            continue;
        }
        let v = classify(mesh, r, *o, oracle.intersect(r), &Tolerance::default());
        assert_ne!(
            v,
            Verdict::Mismatch,
            "{r:?}: packet16 {o:?}, rtcIntersect1 {expected:?}"
        );
    }
    same
}

#[test]
fn packet16_answers_as_embree_medium() {
    let packet16 = EmbreeParams::medium_packet16();
    let (mut same, mut total, mut occluded) = (0, 0, 0);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair",
        "sphere:triangles=5000",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let ours = EmbreeScene::build(scene.mesh.clone(), &packet16).expect("builds");
        let reference =
            EmbreeScene::build(scene.mesh.clone(), &EmbreeParams::medium()).expect("builds");
        let oracle = BruteForce::build(scene.mesh.clone(), &Default::default()).expect("builds");
        for rays in camera_ray_sets(&scene, 4_000) {
            for first in [0, 16, 5] {
                same += closest_agree(&ours, &reference, &oracle, &scene.mesh, &rays, first);
                total += rays.len() - first;
            }
        }
        for rays in shadow_ray_sets(&scene, &reference, 4_000) {
            let prepared = ours.prepare_coherent_rays(&rays).expect("valid rays");
            let mut out = vec![false; rays.len()];
            ours.occluded_prepared(&rays, &prepared, 0, &mut out);
            for (r, &o) in rays.iter().zip(&out) {
                let expected = reference.occluded(r);
                if o != expected {
                    let v = classify_occlusion(
                        &scene.mesh,
                        r,
                        o,
                        oracle.occluded(r),
                        || (ours.intersect(r), oracle.intersect(r)),
                        &Tolerance::default(),
                    );
                    assert_ne!(
                        v,
                        Verdict::Mismatch,
                        "{r:?}: rtcOccluded16 {o}, rtcOccluded1 {expected}"
                    );
                } else {
                    same += 1;
                }
                occluded += o as usize;
            }
            total += rays.len();
        }
    }
    eprintln!(
        "packet16: {same} of {total} answers identical to embree-medium's, {occluded} occluded"
    );
    assert!(
        total > 50_000 && occluded > 5_000,
        "{total} rays, {occluded} occluded"
    );
    assert!(
        same * 1000 >= total * 999,
        "only {same} of {total} identical"
    );
}

/// Partial packets: batches of 1, 15, 16 and 17 shadow rays, and ranges ending inside a packet,
/// answer as `rtcOccluded1` exactly (on the sphere no ray lies in a triangle's plane).
#[test]
fn packet16_partial_packets() {
    let scene = raybench_testkit::scenes::generate("sphere:triangles=2000", 1).expect("generates");
    let ours =
        EmbreeScene::build(scene.mesh.clone(), &EmbreeParams::medium_packet16()).expect("builds");
    let [front, inside] = shadow_ray_sets(&scene, &ours, 2_000);
    for rays in [&front, &inside] {
        for n in [1, 15, 16, 17, rays.len()] {
            occlusion_packets_against_single_rays(&ours, &rays[..n], "sphere");
        }
    }
}
