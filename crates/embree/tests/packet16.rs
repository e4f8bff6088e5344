//! `embree-medium-packet16` against `embree-medium` ray for ray: coherent closest-hit batches
//! traced through `rtcIntersect16` give the answers of `rtcIntersect1` on camera rays, in ranges
//! that start on and off a packet boundary; where one differs it is a tie (another triangle at the
//! same `t`) or an answer brute force agrees with, never a mismatch. Any hit: `rtcOccluded16`
//! (`coherent_occluded16`, off in the preset) against `rtcOccluded1` on shadow rays, and the
//! in-plane ray that keeps it off (docs/validation.md, E11).

use raybench_accel::classify::{Tolerance, Verdict, classify, classify_occlusion};
use raybench_accel::{Accel, BruteForce, Hit};
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_testkit::{camera_ray_sets, occlusion_packets_against_single_rays, shadow_ray_sets};

const SCENES: [&str; 5] = [
    "teapot-in-stadium",
    "city",
    "soup:triangles=20000",
    "hair",
    "sphere:triangles=5000",
];

#[test]
fn packet16_closest_hits_answer_as_embree_medium() {
    let (mut same, mut ties, mut total) = (0usize, 0usize, 0usize);
    for spec in SCENES {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let ours = EmbreeScene::build(scene.mesh.clone(), &EmbreeParams::medium_packet16())
            .expect("builds");
        let reference =
            EmbreeScene::build(scene.mesh.clone(), &EmbreeParams::medium()).expect("builds");
        let oracle = BruteForce::build(scene.mesh.clone(), &Default::default()).expect("builds");
        for rays in camera_ray_sets(&scene, 4_000) {
            let prepared = ours.prepare_coherent_rays(&rays).expect("valid rays");
            for first in [0, 16, 5] {
                let mut out: Vec<Option<Hit>> = vec![None; rays.len() - first];
                ours.intersect_prepared(&rays, &prepared, first, &mut out);
                for (r, o) in rays[first..].iter().zip(&out) {
                    total += 1;
                    let expected = reference.intersect(r);
                    if *o == expected {
                        same += 1;
                        continue;
                    }
                    let tol = Tolerance::default();
                    let tie = o.zip(expected).is_some_and(|(a, b)| a.prim != b.prim)
                        && classify(&scene.mesh, r, *o, expected, &tol) == Verdict::Tie;
                    ties += tie as usize;
                    let v = classify(&scene.mesh, r, *o, oracle.intersect(r), &tol);
                    assert_ne!(
                        v,
                        Verdict::Mismatch,
                        "{r:?}: {o:?}, rtcIntersect1 {expected:?}"
                    );
                }
            }
        }
    }
    // Ties come from the city seen from inside (pairs of coincident faces), as in the wide
    // BVH's packet test; 28 of 148,174 rays differed otherwise when measured (an edge decided
    // the other way, t within tolerance), each one agreeing with brute force.
    eprintln!("rtcIntersect16: {same} of {total} identical to rtcIntersect1, {ties} ties");
    assert!(total > 50_000, "{total} rays");
    assert!(
        (total - same - ties) * 1000 < total,
        "{} of {total} differ other than by a tie",
        total - same - ties
    );
}

/// `rtcOccluded16` on shadow rays (rays starting on surfaces, towards one light): no ray of
/// these scenes lies in a triangle's plane, and every answer is `rtcOccluded1`'s. Partial packets
/// and ranges starting off a packet boundary are checked by the testkit helper.
#[test]
fn occluded16_answers_shadow_rays_as_embree_medium() {
    let params = EmbreeParams {
        coherent_occluded16: true,
        ..EmbreeParams::medium_packet16()
    };
    assert_eq!(params.name(), "embree-medium-packet16-occluded16");
    let (mut rays_seen, mut occluded) = (0, 0);
    for spec in SCENES {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let ours = EmbreeScene::build(scene.mesh.clone(), &params).expect("builds");
        for rays in shadow_ray_sets(&scene, &ours, 4_000) {
            occluded += occlusion_packets_against_single_rays(&ours, &rays, spec);
            rays_seen += rays.len();
        }
        for n in [1, 15, 17] {
            let rays = &shadow_ray_sets(&scene, &ours, 200)[0];
            occlusion_packets_against_single_rays(&ours, &rays[..n.min(rays.len())], spec);
        }
    }
    eprintln!("rtcOccluded16: {rays_seen} shadow rays, {occluded} occluded");
    assert!(occluded > 5_000 && rays_seen - occluded > 5_000);
}

/// Why `coherent_occluded16` is off: on the edge case of triangles along axis planes, traced as
/// one coherent batch, `rtcOccluded16` reports some rays occluded that `rtcOccluded1` and brute
/// force do not (rays running in a triangle's plane; it depends on the packet's other lanes: a
/// packet of sixteen copies of such a ray is not occluded). Measured with Debian's Embree 3.13.5;
/// if this starts failing, Embree changed and E11 should be revisited. The preset sends the same
/// batch through `rtcOccluded1` and answers as brute force.
#[test]
fn occluded16_reports_in_plane_rays_that_rtc_occluded1_does_not() {
    let case = raybench_testkit::edge_cases()
        .into_iter()
        .find(|c| c.name == "edges-and-planes-grid")
        .expect("the testkit has the case");
    let rays = raybench_testkit::valid_rays(&case);
    let oracle = BruteForce::build(case.mesh.clone(), &Default::default()).expect("builds");
    let traced = |params: EmbreeParams| {
        let scene = EmbreeScene::build(case.mesh.clone(), &params).expect("builds");
        let prepared = scene.prepare_coherent_rays(&rays).expect("valid rays");
        let mut out = vec![false; rays.len()];
        scene.occluded_prepared(&rays, &prepared, 0, &mut out);
        out
    };
    let with16 = traced(EmbreeParams {
        coherent_occluded16: true,
        ..EmbreeParams::medium_packet16()
    });
    let preset = traced(EmbreeParams::medium_packet16());
    let single = EmbreeScene::build(case.mesh.clone(), &EmbreeParams::medium()).expect("builds");
    let mut wrong = 0;
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(
            preset[i],
            single.occluded(r),
            "the preset is rtcOccluded1: {r:?}"
        );
        if with16[i] != single.occluded(r) {
            let v = classify_occlusion(
                &case.mesh,
                r,
                with16[i],
                oracle.occluded(r),
                || (single.intersect(r), oracle.intersect(r)),
                &Tolerance::default(),
            );
            wrong += (v == Verdict::Mismatch) as usize;
        }
    }
    eprintln!(
        "rtcOccluded16: {wrong} mismatches against brute force in {} rays",
        rays.len()
    );
    assert!(wrong > 0, "rtcOccluded16 now agrees: revisit E11");
}
