//! Embree against the brute-force oracle (Möller–Trumbore, the test Embree's fast mode uses),
//! for all four presets on two seeded scenes, closest hit and any hit; and the timed batch
//! path against the single-ray path.

mod common;

use common::{height_field, presets, random_triangles, workload};
use raybench_accel::classify::{Tolerance, Verdict, VerdictCounts, classify, classify_occlusion};
use raybench_accel::{Accel, BruteForce, BruteForceParams, Hit};
use raybench_embree::EmbreeScene;
use raybench_geom::{Ray, TriangleMesh};
use std::sync::Arc;

const RAYS: usize = 20_000;

/// The oracle's answers, computed once per scene and shared by the four presets.
struct Reference {
    hits: Vec<Option<Hit>>,
    occluded: Vec<bool>,
}

impl Reference {
    fn new(mesh: &Arc<TriangleMesh>, rays: &[Ray]) -> Reference {
        let brute = BruteForce::build(mesh.clone(), &BruteForceParams::default()).unwrap();
        Reference {
            hits: rays.iter().map(|r| brute.intersect(r)).collect(),
            occluded: rays.iter().map(|r| brute.occluded(r)).collect(),
        }
    }
}

/// Classifies every ray for closest and any hit; returns the counts and the mismatches,
/// described with the ray bits so they can be replayed.
fn classify_all(
    mesh: &TriangleMesh,
    rays: &[Ray],
    embree: &EmbreeScene,
    reference: &Reference,
) -> (VerdictCounts, VerdictCounts, Vec<String>) {
    let tol = Tolerance::default();
    let (mut closest, mut any) = (VerdictCounts::default(), VerdictCounts::default());
    let mut mismatches = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let ours = embree.intersect(ray);
        let theirs = reference.hits[i];
        let v = classify(mesh, ray, ours, theirs, &tol);
        closest.add(v);
        if v == Verdict::Mismatch {
            mismatches.push(format!(
                "closest ray {i} {:?}: embree {ours:?}, brute {theirs:?}",
                ray.to_bits()
            ));
        }
        let occluded = embree.occluded(ray);
        let v = classify_occlusion(
            mesh,
            ray,
            occluded,
            reference.occluded[i],
            || (ours, theirs),
            &tol,
        );
        any.add(v);
        if v == Verdict::Mismatch {
            mismatches.push(format!(
                "occluded ray {i} {:?}: embree {occluded}, brute {}",
                ray.to_bits(),
                reference.occluded[i]
            ));
        }
    }
    (closest, any, mismatches)
}

fn agree_with_brute_force(scene: &str, mesh: Arc<TriangleMesh>, ray_seed: u64) {
    let rays = workload(&mesh, ray_seed, RAYS);
    let reference = Reference::new(&mesh, &rays);
    for params in presets() {
        let embree = EmbreeScene::build(mesh.clone(), &params).unwrap();
        let (closest, any, mismatches) = classify_all(&mesh, &rays, &embree, &reference);
        println!("{scene} {}: closest {closest:?}", embree.name());
        println!("{scene} {}: occluded {any:?}", embree.name());
        assert!(
            mismatches.is_empty(),
            "{scene} {}: {} mismatches in {} rays, first: {:#?}",
            embree.name(),
            mismatches.len(),
            rays.len(),
            &mismatches[..mismatches.len().min(10)]
        );
        // Not vacuous: plenty of rays hit, and nearly all hits agree exactly or within
        // tolerance rather than through the excused classes.
        let reference_hits = reference.hits.iter().filter(|h| h.is_some()).count() as u64;
        assert!(
            reference_hits as usize > rays.len() / 10,
            "{scene}: too few hits"
        );
        let agreed = closest.exact + closest.within_tolerance;
        assert!(
            agreed * 100 >= reference_hits * 99,
            "{scene}: only {agreed} of {reference_hits} hits agree"
        );
        assert!(any.exact * 100 >= reference_hits * 99);
        assert_eq!(closest.total() as usize, rays.len());
    }
}

#[test]
fn random_triangles_agree_with_brute_force() {
    agree_with_brute_force("random-2000", random_triangles(0x5EED_0001, 2_000), 0xA11CE);
}

#[test]
fn height_field_agrees_with_brute_force() {
    agree_with_brute_force("heightfield-32", height_field(0x5EED_0002, 32), 0xB0B);
}

fn same_hit(a: Option<Hit>, b: Option<Hit>) -> bool {
    let bits = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
    bits(a) == bits(b)
}

/// The timed path (prepare outside timing, then trace in chunks at any offset) answers
/// exactly as the single-ray path, bit for bit, also from several threads at once.
#[test]
fn batch_path_matches_single_ray_path() {
    let mesh = random_triangles(0x5EED_0003, 2_000);
    let rays = workload(&mesh, 0xCAFE, 5_000);
    for params in presets() {
        let embree = EmbreeScene::build(mesh.clone(), &params).unwrap();
        let single: Vec<Option<Hit>> = rays.iter().map(|r| embree.intersect(r)).collect();
        let single_any: Vec<bool> = rays.iter().map(|r| embree.occluded(r)).collect();
        assert!(single.iter().filter(|h| h.is_some()).count() > rays.len() / 5);

        let prepared = embree.prepare_rays(&rays).unwrap();
        std::thread::scope(|s| {
            for chunk in [1000, 777, rays.len()] {
                let (embree, prepared, rays) = (&embree, &prepared, &rays);
                let (single, single_any) = (&single, &single_any);
                s.spawn(move || {
                    for first in (0..rays.len()).step_by(chunk) {
                        let len = chunk.min(rays.len() - first);
                        let mut hits = vec![None; len];
                        embree.intersect_prepared(rays, prepared, first, &mut hits);
                        let mut any = vec![false; len];
                        embree.occluded_prepared(rays, prepared, first, &mut any);
                        for k in 0..len {
                            let i = first + k;
                            assert!(same_hit(hits[k], single[i]), "ray {i}");
                            assert_eq!(any[k], single_any[i], "ray {i}");
                        }
                    }
                });
            }
        });
    }
}
