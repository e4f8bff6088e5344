//! raybench-testkit: the conformance suite every structure runs, written once.
//!
//! A structure crate calls it from a test in a few lines:
//!
//! ```text
//! #[test]
//! fn conforms() {
//!     raybench_testkit::conformance::<MyAccel>(&MyParams::default(), &|a, mesh| a.validate(mesh));
//! }
//! ```
//!
//! Every check compares the structure with [`BruteForce`] on named, seeded scenes and ray sets,
//! classifying each ray with `raybench_accel::classify` and requiring zero mismatches; the
//! structure's own `validate()` runs after every build; the counted walk must give the same
//! answers as the timed walk; any-hit must agree with closest-hit. On failure the message names
//! the case, the seed and the exact ray bits.
#![forbid(unsafe_code)]

mod cases;
pub mod points;
mod rays;

pub use cases::{Case, edge_cases, lattice_scene, seeded_cases};
/// The scene generators, for structure crates' tests (which depend on testkit, not on scenes).
pub use raybench_scenes as scenes;
pub use rays::{centroid_rays, lattice_rays, random_rays_in, seeded_rng};

use raybench_accel::classify::{Tolerance, Verdict, VerdictCounts, classify, classify_occlusion};
use raybench_accel::{Accel, BruteForce, Counters};
use raybench_geom::{Ray, TriangleMesh};
use std::sync::Arc;

/// A structure-specific invariant check (`validate()`), run after every build.
pub type Validator<'a, A> = &'a dyn Fn(&A, &TriangleMesh) -> Result<(), String>;

/// No structure-specific invariants (for wrappers such as Embree).
pub fn no_validation<A>(_: &A, _: &TriangleMesh) -> Result<(), String> {
    Ok(())
}

/// Runs every case (seeded scenes and edge cases) and panics with details on the first failure.
/// Returns the verdict counts over all cases so callers can print or check them.
pub fn conformance<A: Accel>(params: &A::Params, validate: Validator<'_, A>) -> VerdictCounts {
    let mut total = VerdictCounts::default();
    for case in seeded_cases().into_iter().chain(edge_cases()) {
        let counts = check_case::<A>(&case, params, validate).unwrap_or_else(|e| panic!("{e}"));
        total += counts;
    }
    eprintln!("conformance: {total:?}");
    total
}

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
    for (i, ray) in case.rays.iter().enumerate() {
        let fail = |what: &str| {
            format!(
                "{} (seed {:#x}) ray {i} {:08x?}: {what}",
                case.name,
                case.seed,
                ray.to_bits()
            )
        };
        let ours = accel.intersect(ray);
        let expected = oracle.intersect(ray);
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
        let any = classify_occlusion(
            &mesh,
            ray,
            occluded,
            oracle.occluded(ray),
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

/// Builds a mesh from positions and indices for a case, panicking on meshes tests should never
/// produce (too many vertices).
pub fn mesh(positions: Vec<raybench_geom::Vec3>, indices: Vec<[u32; 3]>) -> Arc<TriangleMesh> {
    Arc::new(
        TriangleMesh::new(positions, indices)
            .expect("test mesh fits 32-bit indices")
            .0,
    )
}

/// The real scenes of `../shared/scenes` (relative to the repository), when the folder exists.
pub fn shared_scenes_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes")
}

/// Conformance on every real OBJ scene present: build, `validate()`, and a few hundred seeded
/// random and triangle-aimed rays against brute force (few rays: brute force on 331k triangles
/// is slow). Prints plainly, and returns 0, when the folder is absent; otherwise returns how
/// many scenes were checked.
pub fn conformance_on_shared_scenes<A: Accel>(
    params: &A::Params,
    validate: Validator<'_, A>,
) -> usize {
    let Some(files) = shared_obj_files("real-scene conformance check") else {
        return 0;
    };
    for path in &files {
        let scene = raybench_scenes::load_obj(path).unwrap_or_else(|e| panic!("{e}"));
        let seed = 0x5eed_0005;
        let mut rays = random_rays_in(&scene.mesh.bounds().enlarged(0.05), 150, seed);
        rays.extend(centroid_rays(&scene.mesh, 150, seed));
        let case = Case {
            name: path.display().to_string(),
            seed,
            mesh: scene.mesh,
            rays,
        };
        let counts = check_case::<A>(&case, params, validate).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            counts.exact + counts.within_tolerance > 0,
            "{}: no hits checked",
            case.name
        );
    }
    files.len()
}

/// The `.obj` files of [`shared_scenes_dir`], sorted; `None` — after saying plainly on stderr
/// that `check` did not run — when the folder is absent (a fresh clone without ../shared).
pub fn shared_obj_files(check: &str) -> Option<Vec<std::path::PathBuf>> {
    let dir = shared_scenes_dir();
    let Ok(entries) = std::fs::read_dir(&dir) else {
        eprintln!(
            "NOT RUN: {} is absent, so the {check} did not run",
            dir.display()
        );
        return None;
    };
    let mut files: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "obj"))
        .collect();
    files.sort();
    Some(files)
}
