//! The checks of one structure on one case: every answer against brute force, the counted
//! walk against the timed one, any hit against closest hit, and the batch paths against the
//! single-ray path; and the refusal of a build over its memory limit.

use crate::Validator;
use crate::cases::Case;
use raybench_accel::classify::{Tolerance, Verdict, VerdictCounts, classify, classify_occlusion};
use raybench_accel::{Accel, BruteForce, BuildError, Counters};
use raybench_geom::{Ray, TriangleMesh};
use std::sync::Arc;

/// Checks one case; `Err` describes the first problem.
pub fn check_case<A: Accel>(
    case: &Case,
    params: &A::Params,
    validate: Validator<'_, A>,
) -> Result<VerdictCounts, String> {
    let mesh = case.mesh.clone();
    let accel =
        A::build(mesh.clone(), params).map_err(|e| format!("{}: build failed: {e}", case.name))?;
    validate(&accel, &mesh).map_err(|e| format!("{}: validate() after build: {e}", case.name))?;
    let oracle =
        BruteForce::build(mesh.clone(), &Default::default()).expect("brute force always builds");
    let tol = Tolerance::default();
    let mut counts = VerdictCounts::default();
    let oracle_hits = oracle.intersect_all(&case.rays);
    for ((i, ray), &expected) in case.rays.iter().enumerate().zip(&oracle_hits) {
        let fail = |what: &str| {
            format!(
                "{} (seed {:#x}) ray {i} {:08x?}: {what}",
                case.name,
                case.seed,
                ray.to_bits()
            )
        };
        let ours = accel.intersect(ray);
        let verdict = classify(&mesh, ray, ours, expected, &tol);
        counts.add(verdict);
        if verdict == Verdict::Mismatch {
            return Err(fail(&format!(
                "closest hit {ours:?}, brute force {expected:?}"
            )));
        }
        let mut c = Counters::default();
        if accel.intersect_counted(ray, &mut c) != ours {
            return Err(fail("intersect_counted differs from intersect"));
        }
        let occluded = accel.occluded(ray);
        if accel.occluded_counted(ray, &mut Counters::default()) != occluded {
            return Err(fail("occluded_counted differs from occluded"));
        }
        if occluded != ours.is_some() {
            return Err(fail(&format!(
                "occluded() = {occluded} but intersect() = {ours:?}"
            )));
        }
        // Brute force's any-hit answer is whether its closest-hit scan found a hit (the same
        // scan stopped at the first one), so the second scan is not run.
        let any = classify_occlusion(
            &mesh,
            ray,
            occluded,
            expected.is_some(),
            || (ours, expected),
            &tol,
        );
        if any == Verdict::Mismatch {
            return Err(fail("occluded() disagrees with brute force"));
        }
    }
    check_batch_path(&accel, case)?;
    Ok(counts)
}

/// The prepared batch path (what the harness times) must answer exactly as the single-ray path;
/// prepared as coherent (which a structure may trace in packets), it must agree with brute force
/// wherever it answers differently.
fn check_batch_path<A: Accel>(accel: &A, case: &Case) -> Result<(), String> {
    check_plain_batch_path(accel, case)?;
    check_coherent_batch_path(accel, case)
}

/// A batch prepared as coherent, traced whole and in chunks (the harness's rayon chunks start
/// at multiples of 256; odd starts and lengths are checked too). Where it answers differently
/// from the single-ray path, the answer must still agree with brute force, as the single-ray
/// path's must: a packet kernel may decide a ray along an edge differently (Embree's do). The
/// wide BVH's packet walk is held to more, bit-identical answers but for ties, in the bvh
/// crate's tests.
fn check_coherent_batch_path<A: Accel>(accel: &A, case: &Case) -> Result<(), String> {
    let rays = valid_rays(case);
    let prepared = accel
        .prepare_coherent_rays(&rays)
        .map_err(|e| format!("{}: prepare_coherent_rays: {e}", case.name))?;
    let oracle = BruteForce::build(case.mesh.clone(), &Default::default())
        .expect("brute force always builds");
    let tol = Tolerance::default();
    let n = rays.len();
    let splits = [
        (0, n),
        (0, n / 2),
        (16.min(n), n),
        (32.min(n), n.min(37)),
        (5.min(n), n),
    ];
    for (first, end) in splits {
        let mut hits = vec![None; end.saturating_sub(first)];
        accel.intersect_prepared(&rays, &prepared, first, &mut hits);
        let mut occ = vec![false; hits.len()];
        accel.occluded_prepared(&rays, &prepared, first, &mut occ);
        for (k, r) in rays[first..end].iter().enumerate() {
            let fail = |what: String| {
                format!(
                    "{}: coherent batch [{first}..{end}) on ray {:08x?}: {what}",
                    case.name,
                    r.to_bits()
                )
            };
            if hits[k] != accel.intersect(r) {
                let expected = oracle.intersect(r);
                if classify(&case.mesh, r, hits[k], expected, &tol) == Verdict::Mismatch {
                    return Err(fail(format!(
                        "closest hit {:?}, brute force {expected:?}",
                        hits[k]
                    )));
                }
            }
            if occ[k] != accel.occluded(r) {
                let any = classify_occlusion(
                    &case.mesh,
                    r,
                    occ[k],
                    oracle.occluded(r),
                    || (hits[k], oracle.intersect(r)),
                    &tol,
                );
                if any == Verdict::Mismatch {
                    return Err(fail(format!(
                        "occluded {} disagrees with brute force",
                        occ[k]
                    )));
                }
            }
        }
    }
    Ok(())
}

/// The case's rays that pass `Ray::check` (the batch paths take only checked rays, as the
/// harness gives them).
pub fn valid_rays(case: &Case) -> Vec<Ray> {
    case.rays
        .iter()
        .copied()
        .filter(|r| r.check().is_ok())
        .collect()
}

fn check_plain_batch_path<A: Accel>(accel: &A, case: &Case) -> Result<(), String> {
    let rays = valid_rays(case);
    let prepared = accel
        .prepare_rays(&rays)
        .map_err(|e| format!("{}: prepare_rays: {e}", case.name))?;
    let mut hits = vec![None; rays.len()];
    accel.intersect_prepared(&rays, &prepared, 0, &mut hits);
    let mut occ = vec![false; rays.len()];
    accel.occluded_prepared(&rays, &prepared, 0, &mut occ);
    for (i, r) in rays.iter().enumerate() {
        if hits[i] != accel.intersect(r) || occ[i] != accel.occluded(r) {
            return Err(format!(
                "{}: batch path differs from single-ray path on ray {:08x?}",
                case.name,
                r.to_bits()
            ));
        }
    }
    Ok(())
}

/// Panics unless building `A` on `mesh` with `params` is refused with
/// [`BuildError::TooLarge`] naming a need above the limit: an error, never an abort.
pub fn expect_too_large<A: Accel>(mesh: &Arc<TriangleMesh>, params: &A::Params) {
    match A::build(mesh.clone(), params) {
        Err(BuildError::TooLarge {
            needed_bytes,
            limit_bytes,
        }) => assert!(needed_bytes > limit_bytes, "{params:?}"),
        other => panic!(
            "{params:?}: expected TooLarge, got {:?}",
            other.map(|a| a.name().to_owned())
        ),
    }
}

/// Traces `rays` as one coherent batch (`prepare_coherent_rays`, then `intersect_prepared`) and
/// checks every answer against the single-ray path: identical, or a different triangle at the
/// same distance (a packet walk may meet a leaf's triangles in another order). For packet
/// walks held to their single-ray walk's arithmetic. Returns (identical hits, ties).
pub fn packets_against_single_rays<A: Accel>(
    accel: &A,
    mesh: &TriangleMesh,
    rays: &[Ray],
    what: &str,
) -> (usize, usize) {
    let prepared = accel.prepare_coherent_rays(rays).expect("rays are valid");
    let mut packets = vec![None; rays.len()];
    accel.intersect_prepared(rays, &prepared, 0, &mut packets);
    let (mut hits, mut ties) = (0, 0);
    for (ray, packet) in rays.iter().zip(&packets) {
        let single = accel.intersect(ray);
        if *packet == single {
            hits += single.is_some() as usize;
            continue;
        }
        let tie = packet.zip(single).is_some_and(|(a, b)| a.prim != b.prim)
            && classify(mesh, ray, *packet, single, &Tolerance::default()) == Verdict::Tie;
        assert!(
            tie,
            "{what}: {ray:?}: packets {packet:?}, single ray {single:?}"
        );
        ties += 1;
    }
    (hits, ties)
}
