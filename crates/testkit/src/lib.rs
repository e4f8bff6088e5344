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
//! Every check holds the structure against [`raybench_accel::BruteForce`] on named, seeded scenes
//! and ray sets, classifying each ray with `raybench_accel::classify` and requiring zero
//! mismatches; the structure's own `validate()` runs after every build; the counted walk must give
//! the same answers as the timed walk; any-hit must agree with closest-hit. On failure the message
//! names the case, the seed and the exact ray bits.
#![forbid(unsafe_code)]

mod cases;
mod check;
mod lattice;
pub mod points;
mod rays;
mod shadow;

pub use cases::{Case, edge_cases, seeded_cases};
pub use check::{check_case, expect_too_large, packets_against_single_rays, valid_rays};
pub use lattice::{check_lattice, lattice_rays, lattice_scene};
/// The scene generators, for structure crates' tests (which depend on testkit, not on scenes).
pub use raybench_scenes as scenes;
pub use rays::{camera_ray_sets, centroid_rays, random_rays_in, refused_rays, seeded_rng};
pub use shadow::{occlusion_packets_against_single_rays, shadow_ray_sets};

use raybench_accel::Accel;
use raybench_accel::classify::VerdictCounts;
use raybench_geom::TriangleMesh;
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

/// [`conformance`], then the suite must have exercised hits: more than 10,000 rays with an
/// exact answer.
pub fn check_conformance<A: Accel>(
    params: &A::Params,
    validate: Validator<'_, A>,
) -> VerdictCounts {
    let counts = conformance::<A>(params, validate);
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
    counts
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

/// The mesh of a generated scene (`spec` as `raybench scene` takes it), panicking on a bad spec.
pub fn generated(spec: &str, seed: u64) -> Arc<TriangleMesh> {
    raybench_scenes::generate(spec, seed)
        .unwrap_or_else(|e| panic!("generating {spec}: {e}"))
        .mesh
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
