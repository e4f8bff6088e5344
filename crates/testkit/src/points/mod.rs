//! Closest-point conformance: every structure's `closest_point` against
//! [`raybench_accel::BruteForce`].
//!
//! A structure crate calls it from a test in a few lines:
//!
//! ```text
//! #[test]
//! fn point_queries_conform() {
//!     raybench_testkit::points::point_conformance::<MyAccel>(&MyParams::default(), &|a, m| a.validate(m));
//! }
//! ```
//!
//! Each query falls in one class ([`PointVerdict`]), mirroring the ray classes (docs/validation.md,
//! Validation classes): both none; exact (same triangle, same bits); within tolerance (same
//! triangle, distance within tolerance); tie (different triangle, and a double-precision
//! recomputation says both triangles are equally far within tolerance); boundary (one answer, the
//! other none, and the distance found equals the radius within tolerance); mismatch (anything else:
//! a bug). Every answer is also checked on its own: the point lies on the triangle it names,
//! `distance == |point - p|`, `distance <= radius`, and the counted walk answers exactly like the
//! timed one.

mod cases;
mod check;
mod generate;

pub use cases::{edge_point_cases, point_cases, seeded_point_cases};
pub use check::{
    PointCounts, PointVerdict, check_points, check_points_at_radii, classify_point, counted_work,
    exact_distance, tolerance,
};
pub use generate::{points_in_box, points_near_surface, points_on_planes, surface_feature_points};

use crate::Validator;
use raybench_accel::Accel;
use raybench_geom::{TriangleMesh, Vec3};
use raybench_scenes::points::PointWorkload;
use std::sync::Arc;

/// Named seeds of the point cases (the mesh seeds are shared with the ray cases).
pub const SEED_POINTS_NEAR: u64 = 0x5eed_7001;
pub const SEED_POINTS_VOLUME: u64 = 0x5eed_7002;

/// Tolerance in f32 ulps (see [`raybench_accel::classify_points::POINT_TOLERANCE_ULPS`]).
pub const TOLERANCE_ULPS: f64 = raybench_accel::classify_points::POINT_TOLERANCE_ULPS;

/// A mesh, the query points and the radii to ask them with.
#[derive(Clone, Debug)]
pub struct PointCase {
    pub name: String,
    pub seed: u64,
    pub mesh: Arc<TriangleMesh>,
    pub points: Vec<Vec3>,
    /// Every point is queried with every radius (`f32::INFINITY` included where it makes sense).
    pub radii: Vec<f32>,
}

impl PointCase {
    fn new(
        name: &str,
        seed: u64,
        mesh: Arc<TriangleMesh>,
        points: Vec<Vec3>,
        radii: &[f32],
    ) -> Self {
        PointCase {
            name: name.to_string(),
            seed,
            mesh,
            points,
            radii: radii.to_vec(),
        }
    }
}

/// Runs every point case and panics with details on the first failure; returns the counts.
pub fn point_conformance<A: Accel>(params: &A::Params, validate: Validator<'_, A>) -> PointCounts {
    let mut total = PointCounts::default();
    for case in point_cases() {
        total += check_point_case::<A>(&case, params, validate).unwrap_or_else(|e| panic!("{e}"));
    }
    eprintln!("point conformance: {total:?}");
    assert!(
        total.answered() > 1000,
        "too few answered queries: {total:?}"
    );
    total
}

/// Builds the structure on one case, validates it and checks every point at every radius.
pub fn check_point_case<A: Accel>(
    case: &PointCase,
    params: &A::Params,
    validate: Validator<'_, A>,
) -> Result<PointCounts, String> {
    let accel = A::build(case.mesh.clone(), params)
        .map_err(|e| format!("{}: build failed: {e}", case.name))?;
    validate(&accel, &case.mesh)
        .map_err(|e| format!("{}: validate() after build: {e}", case.name))?;
    let mut counts = PointCounts::default();
    for &radius in &case.radii {
        counts += check_points(&accel, &case.mesh, &case.points, radius)
            .map_err(|e| format!("{} (seed {:#x}): {e}", case.name, case.seed))?;
    }
    Ok(counts)
}

/// Named seed of the real-scene point check.
pub const SEED_POINTS_SHARED: u64 = 0x5eed_7005;

/// Point conformance on every real OBJ scene present (../shared/scenes): build, `validate()`,
/// then the first `near` points of the `points-near` workload and `volume` of `points-volume`
/// (the benchmarked distributions), at an infinite radius and at 0.5 % of the diagonal,
/// against brute force (which scans every triangle per point, so keep the counts small).
/// Prints plainly, and returns 0, when the folder is absent; otherwise returns how many scenes
/// were checked.
pub fn point_conformance_on_shared_scenes<A: Accel>(
    params: &A::Params,
    validate: Validator<'_, A>,
    near: usize,
    volume: usize,
) -> usize {
    let Some(files) = crate::shared_obj_files("real-scene point check") else {
        return 0;
    };
    for path in &files {
        let mesh = raybench_scenes::load_obj(path)
            .unwrap_or_else(|e| panic!("{e}"))
            .mesh;
        let b = mesh.bounds();
        let seed = SEED_POINTS_SHARED;
        let mut points = PointWorkload::Near.generate(&mesh, near, seed);
        points.extend(PointWorkload::Volume.generate(&mesh, volume, seed));
        let case = PointCase {
            name: path.display().to_string(),
            seed,
            mesh,
            points,
            radii: vec![f32::INFINITY, 0.005 * b.diagonal()],
        };
        let counts =
            check_point_case::<A>(&case, params, validate).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            counts.answered() >= (near + volume) as u64,
            "{}: {counts:?}",
            case.name
        );
    }
    files.len()
}
