//! Deciding whether two answers for the same ray agree: docs/validation.md, Validation classes
//! (the classes) and Comparison policy (why they are drawn this way).
//!
//! Every ray falls in exactly one [`Verdict`]. Hit/miss or different-triangle disagreements are
//! arbitrated by recomputing, in f64, where the ray meets the disputed triangle: near an edge it
//! is `EdgeAmbiguous` (Embree's fast mode and Möller–Trumbore leave cracks there by design), at
//! the ends of the ray interval it is `Boundary` (Embree promises nothing at `t_min`/`t_max`),
//! anything else is a `Mismatch` — a real bug in one of the two.

use crate::Hit;
use raybench_geom::{Ray, TriangleMesh, Vec3};
use serde::{Deserialize, Serialize};

/// How two answers relate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    BothMiss,
    /// Same triangle, bit-identical t (or both occluded).
    Exact,
    /// Same triangle, t within [`Tolerance`].
    WithinTolerance,
    /// Different triangles at the same t (shared edges, duplicates): decided by order in Embree.
    Tie,
    /// The disputed hit lies at `t_min` or `t_max`.
    Boundary,
    /// The ray passes within the tolerance of the disputed triangle's edge, or is parallel to it.
    EdgeAmbiguous,
    Mismatch,
}

/// Tolerances. `ulps` bounds the t difference in units in the last place; `position_eps`
/// (relative to the largest coordinate involved) bounds positional error, for t and for the
/// distance of a ray to a triangle edge.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    pub ulps: u32,
    pub position_eps: f64,
}

impl Default for Tolerance {
    /// 16 ulp is Embree's own `triangle_hit` tolerance (docs/validation.md, E10); 64 f32
    /// epsilons of the coordinate scale covers Möller–Trumbore's cancellation in `U`, `V` and
    /// `T` (docs/validation.md, Comparison policy).
    fn default() -> Self {
        Tolerance {
            ulps: 16,
            position_eps: 64.0 * f32::EPSILON as f64,
        }
    }
}

impl Tolerance {
    /// Largest acceptable |t_a - t_b| for a hit on a triangle with (unnormalised) `normal`,
    /// when the points involved have magnitude up to `scale`. A positional error `e` moves the
    /// hit along the ray by `e / |n̂·d|` in t, so grazing rays get a proportionally wider
    /// window (docs/validation.md, Validation classes: Möller–Trumbore loses accuracy as `den`
    /// goes to 0).
    pub fn t_tolerance(&self, ray: &Ray, t: f32, scale: f64, normal: Vec3) -> f64 {
        let ulp = ulp(t.abs()) as f64 * self.ulps as f64;
        let d = ray.dir().as_dvec3();
        let n = normal.as_dvec3();
        let along_normal = if n.length_squared() > 0.0 {
            n.normalize().dot(d).abs()
        } else {
            d.length()
        };
        let positional = if along_normal > 0.0 {
            self.position_eps * scale / along_normal
        } else {
            f64::INFINITY
        };
        ulp.max(positional)
    }
}

fn ulp(x: f32) -> f32 {
    if x.is_finite() {
        f32::from_bits(x.to_bits() + 1) - x
    } else {
        0.0
    }
}

fn hit_scale(ray: &Ray, t: f32) -> f64 {
    let o = ray.origin().as_dvec3().abs().max_element();
    let p = ray.at(t).as_dvec3().abs().max_element();
    o.max(p)
}

/// Classifies a closest-hit answer (`ours`) against a reference answer for the same ray.
pub fn classify(
    mesh: &TriangleMesh,
    ray: &Ray,
    ours: Option<Hit>,
    reference: Option<Hit>,
    tol: &Tolerance,
) -> Verdict {
    match (ours, reference) {
        (None, None) => Verdict::BothMiss,
        (Some(a), None) | (None, Some(a)) => dispute(mesh, ray, a.prim, tol),
        (Some(a), Some(b)) => {
            // Positional error comes from every coordinate involved: the origin, the hit points
            // and the triangles' vertices (a huge triangle passing near the origin rounds at
            // the scale of its far vertices, not of the hit point).
            let scale = hit_scale(ray, a.t)
                .max(hit_scale(ray, b.t))
                .max(triangle_scale(mesh, a.prim))
                .max(triangle_scale(mesh, b.prim));
            let t = a.t.max(b.t);
            let window = |prim: u32| match prim_normal(mesh, prim) {
                Some(n) => tol.t_tolerance(ray, t, scale, n),
                None => 0.0,
            };
            // The more grazing of the two triangles decides how uncertain t is.
            let close = ((a.t - b.t).abs() as f64) <= window(a.prim).max(window(b.prim));
            match (a.prim == b.prim, close) {
                (true, _) if a.t.to_bits() == b.t.to_bits() => Verdict::Exact,
                (true, true) => Verdict::WithinTolerance,
                (false, true) => Verdict::Tie,
                // The side with the farther hit did not report the nearer triangle: dispute it.
                (_, false) => dispute(mesh, ray, if a.t < b.t { a.prim } else { b.prim }, tol),
            }
        }
    }
}

/// Classifies an any-hit answer. Agreement needs no arbitration; a disagreement is arbitrated
/// through both sides' closest hits, which the caller computes only for disputed rays.
pub fn classify_occlusion(
    mesh: &TriangleMesh,
    ray: &Ray,
    ours: bool,
    reference: bool,
    closest_hits: impl FnOnce() -> (Option<Hit>, Option<Hit>),
    tol: &Tolerance,
) -> Verdict {
    match (ours, reference) {
        (false, false) => Verdict::BothMiss,
        (true, true) => Verdict::Exact,
        _ => {
            let (a, b) = closest_hits();
            match classify(mesh, ray, a, b, tol) {
                // The closest hits agree, yet the any-hit answers do not: a bug.
                Verdict::BothMiss | Verdict::Exact | Verdict::WithinTolerance | Verdict::Tie => {
                    Verdict::Mismatch
                }
                v => v,
            }
        }
    }
}

fn triangle_scale(mesh: &TriangleMesh, prim: u32) -> f64 {
    if prim as usize >= mesh.len() {
        return 0.0;
    }
    let t = mesh.triangle(prim as usize);
    t.v0.abs().max(t.v1.abs()).max(t.v2.abs()).max_element() as f64
}

fn prim_normal(mesh: &TriangleMesh, prim: u32) -> Option<Vec3> {
    ((prim as usize) < mesh.len()).then(|| mesh.triangle(prim as usize).geometric_normal())
}

/// One side hit `prim` and the other did not see it: decide whether that is excusable.
fn dispute(mesh: &TriangleMesh, ray: &Ray, prim: u32, tol: &Tolerance) -> Verdict {
    if prim as usize >= mesh.len() {
        return Verdict::Mismatch; // a primitive id that does not exist is never excusable
    }
    let tri = mesh.triangle(prim as usize);
    let Some(x) = tri.plane_crossing_f64(ray) else {
        return Verdict::EdgeAmbiguous; // parallel to the plane: grazing
    };
    let t_tol = tol.t_tolerance(ray, x.t as f32, x.scale, tri.geometric_normal());
    let near_t_min = (x.t - ray.t_min() as f64).abs() <= t_tol;
    let near_t_max = ray.t_max().is_finite() && (x.t - ray.t_max() as f64).abs() <= t_tol;
    if near_t_min || near_t_max {
        Verdict::Boundary
    } else if x.edge_distance.abs() <= tol.position_eps * x.scale {
        Verdict::EdgeAmbiguous
    } else {
        Verdict::Mismatch
    }
}

/// Rays per verdict.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct VerdictCounts {
    pub both_miss: u64,
    pub exact: u64,
    pub within_tolerance: u64,
    pub tie: u64,
    pub boundary: u64,
    pub edge_ambiguous: u64,
    pub mismatch: u64,
}

impl std::ops::AddAssign for VerdictCounts {
    fn add_assign(&mut self, o: VerdictCounts) {
        self.both_miss += o.both_miss;
        self.exact += o.exact;
        self.within_tolerance += o.within_tolerance;
        self.tie += o.tie;
        self.boundary += o.boundary;
        self.edge_ambiguous += o.edge_ambiguous;
        self.mismatch += o.mismatch;
    }
}

impl VerdictCounts {
    pub fn add(&mut self, v: Verdict) {
        *match v {
            Verdict::BothMiss => &mut self.both_miss,
            Verdict::Exact => &mut self.exact,
            Verdict::WithinTolerance => &mut self.within_tolerance,
            Verdict::Tie => &mut self.tie,
            Verdict::Boundary => &mut self.boundary,
            Verdict::EdgeAmbiguous => &mut self.edge_ambiguous,
            Verdict::Mismatch => &mut self.mismatch,
        } += 1;
    }

    pub fn total(&self) -> u64 {
        self.both_miss
            + self.exact
            + self.within_tolerance
            + self.tie
            + self.boundary
            + self.edge_ambiguous
            + self.mismatch
    }

    /// Rays in the two classes that are explained but not agreement.
    pub fn ambiguous(&self) -> u64 {
        self.boundary + self.edge_ambiguous
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::{Triangle, Vec3};

    fn quad() -> TriangleMesh {
        // Unit square at z = 0 split along its diagonal, plus a far triangle at z = -5.
        let a = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0));
        let b = Triangle::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        let far = Triangle::new(
            Vec3::new(-9.0, -9.0, -5.0),
            Vec3::new(9.0, -9.0, -5.0),
            Vec3::new(0.0, 9.0, -5.0),
        );
        TriangleMesh::from_triangles(&[a, b, far]).unwrap().0
    }

    fn down(x: f32, y: f32) -> Ray {
        Ray::infinite(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0))
    }

    fn hit(t: f32, prim: u32) -> Option<Hit> {
        Some(Hit {
            t,
            prim,
            u: 0.0,
            v: 0.0,
        })
    }

    #[test]
    fn agreement_classes() {
        let m = quad();
        let tol = Tolerance::default();
        let r = down(0.7, 0.2);
        assert_eq!(classify(&m, &r, None, None, &tol), Verdict::BothMiss);
        assert_eq!(
            classify(&m, &r, hit(1.0, 0), hit(1.0, 0), &tol),
            Verdict::Exact
        );
        assert_eq!(
            classify(&m, &r, hit(1.0, 0), hit(1.0000001, 0), &tol),
            Verdict::WithinTolerance
        );
        assert_eq!(
            classify(&m, &down(0.5, 0.5), hit(1.0, 0), hit(1.0, 1), &tol),
            Verdict::Tie
        );
    }

    #[test]
    fn grazing_rays_get_a_wider_t_window() {
        let m = quad();
        let tol = Tolerance::default();
        // Nearly parallel to the plane: |n̂·d| = 1e-3, so a 1e-4 shift in t is within the
        // positional uncertainty; head-on, the same shift is a mismatch.
        let grazing = Ray::infinite(Vec3::new(-0.3, 0.2, 1e-3), Vec3::new(1.0, 0.0, -1e-3));
        assert_eq!(
            classify(&m, &grazing, hit(1.0, 0), hit(1.0001, 0), &tol),
            Verdict::WithinTolerance
        );
        let head_on = down(0.7, 0.2);
        assert_eq!(
            classify(&m, &head_on, hit(1.0, 0), hit(1.0001, 0), &tol),
            Verdict::Mismatch
        );
    }

    #[test]
    fn huge_triangles_widen_the_window_even_near_the_origin() {
        // A triangle with vertices 50 units out passes 0.2 below the origin: its plane is
        // rounded at the scale of 50, so two answers 2e-5 apart in t agree. The same difference
        // on the unit quad is a mismatch.
        let huge = Triangle::new(
            Vec3::new(-50.0, -50.0, 0.0),
            Vec3::new(50.0, -50.0, 0.0),
            Vec3::new(0.0, 50.0, 0.0),
        );
        let m = TriangleMesh::from_triangles(&[huge]).unwrap().0;
        let tol = Tolerance::default();
        let r = Ray::infinite(Vec3::new(0.0, 0.0, 0.2), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(
            classify(&m, &r, hit(0.2, 0), hit(0.20002, 0), &tol),
            Verdict::WithinTolerance
        );
        let r = Ray::infinite(Vec3::new(0.7, 0.2, 0.2), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(
            classify(&quad(), &r, hit(0.2, 0), hit(0.20002, 0), &tol),
            Verdict::Mismatch
        );
    }

    #[test]
    fn clear_disagreements_are_mismatches() {
        let m = quad();
        let tol = Tolerance::default();
        // Well inside triangle 0: missing it, or reporting the far triangle instead, is a bug.
        let r = down(0.7, 0.2);
        assert_eq!(classify(&m, &r, None, hit(1.0, 0), &tol), Verdict::Mismatch);
        assert_eq!(
            classify(&m, &r, hit(6.0, 2), hit(1.0, 0), &tol),
            Verdict::Mismatch
        );
        assert_eq!(
            classify(&m, &r, hit(1.0, 0), hit(1.5, 0), &tol),
            Verdict::Mismatch
        );
        assert_eq!(classify(&m, &r, hit(1.0, 7), None, &tol), Verdict::Mismatch);
    }

    #[test]
    fn edge_and_boundary_disagreements_are_explained() {
        let m = quad();
        let tol = Tolerance::default();
        // On the outer edge x = 1 (a silhouette): one side may hit and the other miss.
        assert_eq!(
            classify(&m, &down(1.0, 0.3), hit(1.0, 0), None, &tol),
            Verdict::EdgeAmbiguous
        );
        // The hit lies exactly at t_max.
        let r = Ray::new(
            Vec3::new(0.7, 0.2, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            0.0,
            1.0,
        );
        assert_eq!(classify(&m, &r, hit(1.0, 0), None, &tol), Verdict::Boundary);
        // Origin on the surface, t_min = 0.
        let r = Ray::infinite(Vec3::new(0.7, 0.2, 0.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(classify(&m, &r, None, hit(0.0, 0), &tol), Verdict::Boundary);
    }

    #[test]
    fn occlusion_disagreement_is_arbitrated_by_closest_hits() {
        let m = quad();
        let tol = Tolerance::default();
        let r = down(0.7, 0.2);
        let v = classify_occlusion(&m, &r, false, true, || (None, hit(1.0, 0)), &tol);
        assert_eq!(v, Verdict::Mismatch);
        let e = down(1.0, 0.3);
        let v = classify_occlusion(&m, &e, true, false, || (hit(1.0, 0), None), &tol);
        assert_eq!(v, Verdict::EdgeAmbiguous);
        assert_eq!(
            classify_occlusion(&m, &r, true, true, || unreachable!(), &tol),
            Verdict::Exact
        );
    }

    #[test]
    fn counts_sum_to_total() {
        let mut c = VerdictCounts::default();
        for v in [
            Verdict::BothMiss,
            Verdict::Exact,
            Verdict::Tie,
            Verdict::Mismatch,
            Verdict::Boundary,
        ] {
            c.add(v);
        }
        assert_eq!(c.total(), 5);
        assert_eq!((c.mismatch, c.ambiguous()), (1, 1));
    }
}
