//! Closest-point conformance: every structure's `closest_point` against [`BruteForce`].
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
//! Each query falls in one class ([`PointVerdict`]), mirroring the ray classes of
//! ARCHITECTURE.md: both none; exact (same triangle, same bits); within tolerance (same triangle,
//! distance within tolerance); tie (different triangle, and a double-precision recomputation
//! says both triangles are equally far within tolerance); boundary (one answer, the other none,
//! and the distance found equals the radius within tolerance); mismatch (anything else: a bug).
//! Every answer is also checked on its own: the point lies on the triangle it names,
//! `distance == |point - p|`, `distance <= radius`, and the counted walk answers exactly like
//! the timed one.

use crate::cases::{SEED_EDGE, SEED_PLANE, SEED_SOUP, SEED_SPHERE};
use crate::rays::seeded_rng;
use crate::{Validator, mesh};
use rand_core::Rng;
use raybench_accel::{Accel, BruteForce, Counters, PointHit};
use raybench_geom::{Aabb, Triangle, TriangleMesh, Vec3, distance_to_triangle_f64};
use raybench_scenes::points::PointWorkload;
use std::ops::AddAssign;
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

/// How one query compared with brute force.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointVerdict {
    BothNone,
    Exact,
    WithinTolerance,
    Tie,
    Boundary,
    Mismatch,
}

/// How many queries fell in each class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointCounts {
    pub both_none: u64,
    pub exact: u64,
    pub within_tolerance: u64,
    pub tie: u64,
    pub boundary: u64,
    pub mismatch: u64,
}

impl PointCounts {
    pub fn add(&mut self, v: PointVerdict) {
        let slot = match v {
            PointVerdict::BothNone => &mut self.both_none,
            PointVerdict::Exact => &mut self.exact,
            PointVerdict::WithinTolerance => &mut self.within_tolerance,
            PointVerdict::Tie => &mut self.tie,
            PointVerdict::Boundary => &mut self.boundary,
            PointVerdict::Mismatch => &mut self.mismatch,
        };
        *slot += 1;
    }

    /// Queries that found a triangle and agreed with brute force.
    pub fn answered(&self) -> u64 {
        self.exact + self.within_tolerance + self.tie
    }
}

impl AddAssign for PointCounts {
    fn add_assign(&mut self, o: PointCounts) {
        self.both_none += o.both_none;
        self.exact += o.exact;
        self.within_tolerance += o.within_tolerance;
        self.tie += o.tie;
        self.boundary += o.boundary;
        self.mismatch += o.mismatch;
    }
}

fn unit(rng: &mut impl Rng) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

fn unit_vector(rng: &mut impl Rng) -> Vec3 {
    let z = 2.0 * unit(rng) - 1.0;
    let phi = std::f32::consts::TAU * unit(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` points uniform in `bounds`.
pub fn points_in_box(bounds: &Aabb, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = seeded_rng(seed);
    let e = bounds.extent();
    (0..n)
        .map(|_| bounds.min + Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) * e)
        .collect()
}

/// `n` points near the surface: a random triangle (uniform by index), a random point on it,
/// moved in a random direction by up to `max_offset`. Empty for an empty mesh.
pub fn points_near_surface(mesh: &TriangleMesh, n: usize, max_offset: f32, seed: u64) -> Vec<Vec3> {
    if mesh.is_empty() {
        return Vec::new();
    }
    let mut rng = seeded_rng(seed);
    (0..n)
        .map(|_| {
            let prim = (rng.next_u64() % mesh.len() as u64) as usize;
            let (mut u, mut v) = (unit(&mut rng), unit(&mut rng));
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let on = mesh.triangle(prim).point_at(u, v);
            on + unit_vector(&mut rng) * (max_offset * unit(&mut rng))
        })
        .collect()
}

/// Points exactly on the surface features of the first `max_tris` triangles: every vertex
/// (exactly representable), every edge midpoint and the centroid (on the surface up to rounding).
pub fn surface_feature_points(mesh: &TriangleMesh, max_tris: usize) -> Vec<Vec3> {
    mesh.triangles()
        .take(max_tris)
        .flat_map(|t| {
            [
                t.v0,
                t.v1,
                t.v2,
                (t.v0 + t.v1) * 0.5,
                (t.v1 + t.v2) * 0.5,
                (t.v2 + t.v0) * 0.5,
                t.centroid(),
            ]
        })
        .collect()
}

/// Exact distance from `p` to `tri` in f64 (geom's validation reference, a different route
/// from the `closest_point_on_triangle` every structure uses).
pub fn exact_distance(p: Vec3, tri: &Triangle) -> f64 {
    distance_to_triangle_f64(p, tri)
}

/// Absolute distance tolerance for queries at `p` on `mesh` (shared with the harness: see
/// [`raybench_accel::classify_points::point_tolerance`]).
pub fn tolerance(mesh_bounds: &Aabb, p: Vec3) -> f64 {
    raybench_accel::classify_points::point_tolerance(mesh_bounds, p)
}

/// The checks one answer must pass on its own, whatever brute force says.
fn check_answer(
    mesh: &TriangleMesh,
    p: Vec3,
    radius: f32,
    h: &PointHit,
    tol: f64,
) -> Result<(), String> {
    if h.prim as usize >= mesh.len() {
        return Err(format!(
            "prim {} out of range ({} triangles)",
            h.prim,
            mesh.len()
        ));
    }
    let tri = mesh.triangle(h.prim as usize);
    let off_triangle = exact_distance(h.point, &tri);
    if off_triangle > tol {
        return Err(format!(
            "point {} is {off_triangle:e} away from triangle {}",
            h.point, h.prim
        ));
    }
    let measured = (h.point.as_dvec3() - p.as_dvec3()).length();
    if (h.distance as f64 - measured).abs() > tol {
        return Err(format!(
            "distance {} but |point - p| = {measured}",
            h.distance
        ));
    }
    if h.distance as f64 > radius as f64 + tol {
        return Err(format!(
            "distance {} beyond the radius {radius}",
            h.distance
        ));
    }
    Ok(())
}

/// Classifies `ours` against brute force's `expected` (see the module documentation; the
/// rule itself is [`raybench_accel::classify_points::classify_point`], which the harness uses
/// against Embree).
pub fn classify_point(
    mesh: &TriangleMesh,
    p: Vec3,
    radius: f32,
    ours: Option<PointHit>,
    expected: Option<PointHit>,
    tol: f64,
) -> PointVerdict {
    use raybench_accel::classify::Verdict;
    match raybench_accel::classify_points::classify_point(mesh, p, radius, ours, expected, tol) {
        Verdict::BothMiss => PointVerdict::BothNone,
        Verdict::Exact => PointVerdict::Exact,
        Verdict::WithinTolerance => PointVerdict::WithinTolerance,
        Verdict::Tie => PointVerdict::Tie,
        Verdict::Boundary => PointVerdict::Boundary,
        Verdict::EdgeAmbiguous | Verdict::Mismatch => PointVerdict::Mismatch,
    }
}

/// Compares `accel.closest_point` and `closest_point_counted` with brute force on every point
/// at `radius`. `Err` names the first failing point (with its bits, to replay it).
pub fn check_points(
    accel: &dyn Accel,
    mesh: &Arc<TriangleMesh>,
    points: &[Vec3],
    radius: f32,
) -> Result<PointCounts, String> {
    let oracle = BruteForce::build(mesh.clone(), &Default::default())
        .map_err(|e| format!("brute force failed to build: {e}"))?;
    let bounds = mesh.bounds();
    let mut counts = PointCounts::default();
    for (i, &p) in points.iter().enumerate() {
        let fail = |what: String| {
            format!(
                "{}: point {i} {p} (bits {:08x?}), radius {radius}: {what}",
                accel.name(),
                p.to_array().map(f32::to_bits)
            )
        };
        let tol = tolerance(&bounds, p);
        let ours = accel.closest_point(p, radius);
        let counted = accel.closest_point_counted(p, radius, &mut Counters::default());
        if counted != ours {
            return Err(fail(format!(
                "closest_point_counted {counted:?} but closest_point {ours:?}"
            )));
        }
        if let Some(h) = &ours {
            check_answer(mesh, p, radius, h, tol).map_err(fail)?;
        }
        let expected = oracle.closest_point(p, radius);
        let verdict = classify_point(mesh, p, radius, ours, expected, tol);
        if verdict == PointVerdict::Mismatch {
            return Err(fail(format!("{ours:?}, brute force {expected:?}")));
        }
        counts.add(verdict);
    }
    Ok(counts)
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

fn generated(spec: &str, seed: u64) -> Arc<TriangleMesh> {
    raybench_scenes::generate(spec, seed)
        .unwrap_or_else(|e| panic!("generating {spec}: {e}"))
        .mesh
}

/// Points near the surface and points in the box enlarged by 10 %, `n` of each.
fn mixed_points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let b = mesh.bounds();
    let mut points = points_near_surface(mesh, n, 0.01 * b.diagonal(), seed ^ SEED_POINTS_NEAR);
    points.extend(points_in_box(
        &b.enlarged(0.1),
        n,
        seed ^ SEED_POINTS_VOLUME,
    ));
    points
}

fn from_tris(tris: &[Triangle]) -> Arc<TriangleMesh> {
    Arc::new(
        TriangleMesh::from_triangles(tris)
            .expect("small test mesh")
            .0,
    )
}

const INF: f32 = f32::INFINITY;

/// Every point case: seeded procedural scenes, then the edge cases.
pub fn point_cases() -> Vec<PointCase> {
    let mut cases = seeded_point_cases();
    cases.extend(edge_point_cases());
    cases
}

/// Seeded scenes with near-surface and volume points, at an infinite radius and at a finite
/// one that leaves many points without an answer.
pub fn seeded_point_cases() -> Vec<PointCase> {
    let soup = generated("soup:triangles=3000", SEED_SOUP);
    let sphere = generated("sphere:triangles=2000", SEED_SPHERE);
    let plane = generated("plane:quads=16", SEED_PLANE);
    let small = |m: &TriangleMesh| 0.02 * m.bounds().diagonal();
    let inside = points_in_box(
        &Aabb::new(Vec3::splat(-0.3), Vec3::splat(0.3)),
        500,
        SEED_SPHERE,
    );
    vec![
        PointCase::new(
            "soup",
            SEED_SOUP,
            soup.clone(),
            mixed_points(&soup, 1500, SEED_SOUP),
            &[INF, small(&soup)],
        ),
        PointCase::new(
            "sphere",
            SEED_SPHERE,
            sphere.clone(),
            mixed_points(&sphere, 1000, SEED_SPHERE),
            &[INF, small(&sphere)],
        ),
        PointCase::new("sphere-from-inside", SEED_SPHERE, sphere, inside, &[INF]),
        PointCase::new(
            "plane",
            SEED_PLANE,
            plane.clone(),
            mixed_points(&plane, 1000, SEED_PLANE),
            &[INF, small(&plane)],
        ),
        // Shared vertices and edges of the plane's grid: ties between up to six triangles.
        PointCase::new(
            "plane-features",
            SEED_PLANE,
            plane.clone(),
            surface_feature_points(&plane, 200),
            &[INF, 0.0],
        ),
    ]
}

/// The edge cases of the point suite (ARCHITECTURE.md, "Examples to follow", 3).
pub fn edge_point_cases() -> Vec<PointCase> {
    let s = SEED_EDGE;
    let unit_box = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let mut cases = vec![PointCase::new(
        "empty-mesh",
        s,
        mesh(vec![], vec![]),
        points_in_box(&unit_box, 50, s),
        &[INF, 1.0, 0.0],
    )];

    let one = from_tris(&[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)]);
    let mut points = surface_feature_points(&one, 1);
    points.extend([
        Vec3::new(0.25, 0.25, 0.0), // exactly on the face
        Vec3::new(0.25, 0.25, 1.0), // above the face
        Vec3::new(2.0, 2.0, 0.0),   // in the plane, beyond the hypotenuse
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1e6, -3e5, 7e5), // far outside
    ]);
    points.extend(points_in_box(&unit_box.enlarged(1.0), 300, s));
    // Radius 0 (only points on the triangle), a finite radius, one that excludes everything
    // the box points could reach, and the inclusive boundary itself (|(0.25,0.25,1)| = 1).
    cases.push(PointCase::new(
        "one-triangle",
        s,
        one,
        points,
        &[INF, 0.0, 0.5, 1.0, 1e-6],
    ));

    let a = Vec3::new(0.5, -0.25, 2.0);
    let lone_point = from_tris(&[Triangle::new(a, a, a)]);
    let around = points_in_box(&Aabb::new(a - 1.0, a + 1.0), 200, s);
    let mut pts = around.clone();
    pts.push(a);
    cases.push(PointCase::new(
        "single-point-triangle",
        s,
        lone_point,
        pts,
        &[INF, 0.0, 0.75],
    ));

    let collinear = from_tris(&[Triangle::new(
        Vec3::ZERO,
        Vec3::new(2.0, 1.0, 0.5),
        Vec3::new(1.0, 0.5, 0.25),
    )]);
    cases.push(PointCase::new(
        "single-collinear-triangle",
        s,
        collinear.clone(),
        mixed_points(&collinear, 200, s),
        &[INF, 0.1],
    ));

    cases.push(one_centroid_case());

    let same = from_tris(&vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 200]);
    cases.push(PointCase::new(
        "identical-triangles",
        s,
        same.clone(),
        mixed_points(&same, 300, s),
        &[INF],
    ));

    let flat = flat_soup(500, s);
    cases.push(PointCase::new(
        "flat-scene",
        s,
        flat.clone(),
        mixed_points(&flat, 500, s),
        &[INF, 0.05],
    ));

    let far = soup_mesh(1000, s, Vec3::splat(1e5));
    cases.push(PointCase::new(
        "offset-1e5",
        s,
        far.clone(),
        mixed_points(&far, 500, s),
        &[INF, 0.1],
    ));

    let mixed = zero_area_mixed(s);
    let mut pts = mixed_points(&mixed, 500, s);
    pts.extend(
        surface_feature_points(&mixed, mixed.len())
            .into_iter()
            .step_by(7),
    );
    cases.push(PointCase::new(
        "zero-area-mixed",
        s,
        mixed,
        pts,
        &[INF, 0.02],
    ));

    // Radius so small relative to the query points that nothing qualifies.
    let soup = soup_mesh(300, s, Vec3::ZERO);
    let beyond = points_in_box(&Aabb::new(Vec3::splat(3.0), Vec3::splat(4.0)), 200, s);
    cases.push(PointCase::new(
        "radius-excludes-everything",
        s,
        soup,
        beyond,
        &[1.0, 0.0],
    ));
    cases
}

/// Concentric triangles sharing one centroid (degenerate input for every splitting rule), with
/// the centroid itself among the points.
fn one_centroid_case() -> PointCase {
    let tris = crate::cases::concentric_triangles();
    let m = from_tris(&tris);
    let mut points = mixed_points(&m, 500, SEED_EDGE);
    points.push(Vec3::ZERO);
    PointCase::new("one-centroid", SEED_EDGE, m, points, &[INF, 0.05])
}

fn soup_tris(n: usize, seed: u64, offset: Vec3) -> Vec<Triangle> {
    let mut rng = seeded_rng(seed);
    (0..n)
        .map(|_| {
            let c = Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) + offset;
            let mut v =
                || c + (Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5) * 0.2;
            Triangle::new(v(), v(), v())
        })
        .collect()
}

fn soup_mesh(n: usize, seed: u64, offset: Vec3) -> Arc<TriangleMesh> {
    from_tris(&soup_tris(n, seed, offset))
}

fn flat_soup(n: usize, seed: u64) -> Arc<TriangleMesh> {
    let flatten = |v: Vec3| v * Vec3::new(1.0, 1.0, 0.0);
    let tris: Vec<Triangle> = soup_tris(n, seed, Vec3::ZERO)
        .into_iter()
        .map(|t| Triangle::new(flatten(t.v0), flatten(t.v1), flatten(t.v2)))
        .collect();
    from_tris(&tris)
}

/// A soup with collinear and single-point triangles mixed in: they have points, so they count.
fn zero_area_mixed(seed: u64) -> Arc<TriangleMesh> {
    let mut tris = soup_tris(500, seed, Vec3::ZERO);
    for t in tris.clone().iter().take(200) {
        tris.push(Triangle::new(t.v0, t.v1, t.v0 * 0.5 + t.v1 * 0.5));
        tris.push(Triangle::new(t.v2 + 0.05, t.v2 + 0.05, t.v2 + 0.05));
    }
    from_tris(&tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generators_are_deterministic_and_where_they_say() {
        let m = generated("sphere:triangles=500", SEED_SPHERE);
        let a = points_near_surface(&m, 200, 0.01, 7);
        assert_eq!(a, points_near_surface(&m, 200, 0.01, 7));
        assert_ne!(a, points_near_surface(&m, 200, 0.01, 8));
        for p in &a {
            let d = m
                .triangles()
                .map(|t| exact_distance(*p, &t))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= 0.01 + 1e-6, "{p} is {d} from the surface");
        }
        let b = Aabb::new(Vec3::splat(-2.0), Vec3::new(1.0, 2.0, 3.0));
        assert!(points_in_box(&b, 500, 3).iter().all(|p| b.contains(*p)));
        assert!(points_near_surface(&mesh(vec![], vec![]), 10, 1.0, 1).is_empty());
    }

    /// The oracle checked against itself: every class the checker can produce, and a planted
    /// wrong answer that it must reject.
    #[test]
    fn brute_force_conforms_and_a_wrong_answer_is_caught() {
        let counts = point_conformance::<BruteForce>(&Default::default(), &crate::no_validation);
        assert_eq!(counts.mismatch, 0);
        assert!(
            counts.both_none > 100,
            "the finite radii leave points unanswered: {counts:?}"
        );
        let m = from_tris(&[
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::Z, Vec3::Z + Vec3::X, Vec3::Z + Vec3::Y),
        ]);
        let p = Vec3::new(0.2, 0.2, 0.1);
        let right = BruteForce::build(m.clone(), &Default::default())
            .unwrap()
            .closest_point(p, INF);
        assert_eq!(right.map(|h| h.prim), Some(0));
        let wrong = Some(PointHit {
            prim: 1,
            point: Vec3::new(0.2, 0.2, 1.0),
            distance: 0.9,
        });
        let tol = tolerance(&m.bounds(), p);
        assert_eq!(
            classify_point(&m, p, INF, wrong, right, tol),
            PointVerdict::Mismatch
        );
        assert_eq!(
            classify_point(&m, p, INF, None, right, tol),
            PointVerdict::Mismatch
        );
        assert_eq!(
            classify_point(&m, p, 0.1, None, right, tol),
            PointVerdict::Boundary
        );
        // Answers that are wrong on their own: a point off its triangle, a distance that is
        // not |point - p|, a distance beyond the radius.
        let h = right.unwrap();
        let off = PointHit {
            point: Vec3::new(0.2, 0.2, 0.01),
            ..h
        };
        assert!(check_answer(&m, p, INF, &off, tol).is_err());
        let misreported = PointHit {
            distance: 0.05,
            ..h
        };
        assert!(check_answer(&m, p, INF, &misreported, tol).is_err());
        assert!(check_answer(&m, p, 0.05, &h, tol).is_err());
        assert!(check_answer(&m, p, INF, &h, tol).is_ok());
        let twin = from_tris(&[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 2]);
        let other = right.map(|h| PointHit { prim: 1, ..h });
        assert_eq!(
            classify_point(&twin, p, INF, other, right, tol),
            PointVerdict::Tie
        );
    }
}
