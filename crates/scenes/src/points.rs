//! Closest-point workloads: where the query points of `points-near` and `points-volume` come
//! from. Each is a pure function of the mesh, a count and a seed, on its own `rand_pcg` stream
//! (like the ray workloads, so adding one never shifts another's numbers).
//!
//! * `points-near`: the signed-distance-field case. A triangle chosen with probability
//!   proportional to its area, a point uniform on it, then moved in a direction uniform on the
//!   sphere by a distance uniform in `[0, 1 %]` of the scene's diagonal ([`NEAR_OFFSET`]). Every
//!   point is therefore within 1 % of the diagonal of the surface, and queries stay close to
//!   it, where a structure must separate many nearly-equidistant triangles.
//! * `points-volume`: uniform in the scene's box enlarged by 10 % per side ([`VOLUME_MARGIN`]),
//!   the proximity-query and Hausdorff-distance case: many points far from any triangle.
//!
//! ## Radius
//! Both workloads query with an infinite radius ([`PointWorkload::default_radius`]): every
//! point of a non-empty mesh then has an answer, so every structure and Embree are checked on
//! the same, always-defined question, and the search's own shrinking bound does the pruning
//! (after the first leaf, the radius is the best distance found). A finite radius (a narrow
//! band) is a different question that the conformance suite checks separately.

use crate::rng::{self, range_f32, unit_f32};
use raybench_geom::{Aabb, TriangleMesh, Vec3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Largest offset of a `points-near` point from the surface, as a fraction of the diagonal.
pub const NEAR_OFFSET: f32 = 0.01;
/// Margin of the `points-volume` box per side, as a fraction of the scene box's extent.
pub const VOLUME_MARGIN: f32 = 0.1;

/// Stream tags (ASCII, like rng.rs's).
const NEAR_STREAM: u64 = u64::from_be_bytes(*b"wl-pnear");
const VOLUME_STREAM: u64 = u64::from_be_bytes(*b"wl-pvolu");

/// A closest-point workload.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PointWorkload {
    #[serde(rename = "points-near")]
    Near,
    #[serde(rename = "points-volume")]
    Volume,
}

/// A name that is not a point workload.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown point workload `{0}` (known: points-near, points-volume)")]
pub struct UnknownPointWorkload(pub String);

impl PointWorkload {
    pub const ALL: [PointWorkload; 2] = [PointWorkload::Near, PointWorkload::Volume];

    pub fn name(&self) -> &'static str {
        match self {
            PointWorkload::Near => "points-near",
            PointWorkload::Volume => "points-volume",
        }
    }

    pub fn description(&self) -> &'static str {
        match self {
            PointWorkload::Near => {
                "points within 1% of the scene diagonal of the surface (area-weighted triangle, uniform point, random offset): nearest triangle, infinite radius (the SDF case)"
            }
            PointWorkload::Volume => {
                "points uniform in the scene box enlarged by 10% per side: nearest triangle, infinite radius"
            }
        }
    }

    /// The search radius every structure is queried with: infinite (see the module
    /// documentation for why).
    pub fn default_radius(&self) -> f32 {
        f32::INFINITY
    }

    /// `n` query points for `mesh`, a pure function of the inputs. `points-near` on an empty
    /// mesh gives no points (there is no surface to be near); `points-volume` on an empty mesh
    /// uses the box `[-1, 1]³`, as the random ray workload does.
    pub fn generate(&self, mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
        match self {
            PointWorkload::Near => near_surface_points(mesh, n, seed),
            PointWorkload::Volume => volume_points(&mesh.bounds(), n, seed),
        }
    }
}

impl fmt::Display for PointWorkload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PointWorkload {
    type Err = UnknownPointWorkload;

    /// Case-insensitive workload name.
    fn from_str(s: &str) -> Result<PointWorkload, UnknownPointWorkload> {
        PointWorkload::ALL
            .into_iter()
            .find(|w| w.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownPointWorkload(s.to_owned()))
    }
}

/// `points-volume`: uniform in `bounds` enlarged by [`VOLUME_MARGIN`] per side.
fn volume_points(bounds: &Aabb, n: usize, seed: u64) -> Vec<Vec3> {
    let region = if bounds.is_empty() {
        Aabb::new(Vec3::splat(-1.0), Vec3::ONE)
    } else {
        bounds.enlarged(VOLUME_MARGIN)
    };
    let mut rng = rng::stream(seed, VOLUME_STREAM);
    (0..n)
        .map(|_| {
            Vec3::new(
                range_f32(&mut rng, region.min.x, region.max.x),
                range_f32(&mut rng, region.min.y, region.max.y),
                range_f32(&mut rng, region.min.z, region.max.z),
            )
        })
        .collect()
}

/// `points-near`: see the module documentation.
fn near_surface_points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let Some(pick) = AreaSampler::new(mesh) else {
        return Vec::new();
    };
    let max_offset = NEAR_OFFSET * mesh.bounds().diagonal();
    let mut rng = rng::stream(seed, NEAR_STREAM);
    (0..n)
        .map(|_| {
            let tri = mesh.triangle(pick.sample(unit_f32(&mut rng)));
            // Uniform on the triangle (the square-root warp of the unit square).
            let s = unit_f32(&mut rng).sqrt();
            let t = unit_f32(&mut rng);
            let on = tri.point_at(s * (1.0 - t), s * t);
            let dir = rng::uniform_sphere(&mut rng);
            on + dir * (max_offset * unit_f32(&mut rng))
        })
        .collect()
}

/// Picks triangle indices with probability proportional to area (uniformly by index when
/// every triangle has zero area), by binary search in the f64 prefix sums of the areas.
struct AreaSampler {
    /// `cumulative[i]`: total area of triangles `0..=i`.
    cumulative: Vec<f64>,
}

impl AreaSampler {
    /// `None` for an empty mesh.
    fn new(mesh: &TriangleMesh) -> Option<AreaSampler> {
        if mesh.is_empty() {
            return None;
        }
        let mut total = 0.0;
        let mut cumulative: Vec<f64> = mesh
            .triangles()
            .map(|t| {
                total += t.area();
                total
            })
            .collect();
        if !(total > 0.0 && total.is_finite()) {
            cumulative = (1..=mesh.len()).map(|i| i as f64).collect();
        }
        Some(AreaSampler { cumulative })
    }

    /// The triangle whose slice of the total holds `u * total`, for `u` in `[0, 1)`.
    fn sample(&self, u: f32) -> usize {
        let total = self.cumulative[self.cumulative.len() - 1];
        let target = u as f64 * total;
        // First triangle whose running total exceeds the target: zero-area triangles (an
        // empty slice) are never picked.
        self.cumulative
            .partition_point(|&c| c <= target)
            .min(self.cumulative.len() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::{Triangle, closest_point_on_triangle};

    fn sphere() -> std::sync::Arc<TriangleMesh> {
        crate::generate("sphere:triangles=800", 3).unwrap().mesh
    }

    fn distance_to_mesh(mesh: &TriangleMesh, p: Vec3) -> f32 {
        mesh.triangles()
            .map(|t| closest_point_on_triangle(p, &t).distance(p))
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_errors() {
        for w in PointWorkload::ALL {
            assert_eq!(w.name().parse::<PointWorkload>(), Ok(w));
            assert_eq!(w.to_string().to_uppercase().parse::<PointWorkload>(), Ok(w));
            assert_eq!(w.default_radius(), f32::INFINITY);
        }
        let err = "points-far".parse::<PointWorkload>().unwrap_err();
        assert!(err.to_string().contains("points-near"), "{err}");
    }

    #[test]
    fn generation_is_deterministic_and_seeded() {
        let mesh = sphere();
        for w in PointWorkload::ALL {
            let a = w.generate(&mesh, 500, 11);
            assert_eq!(a.len(), 500);
            assert_eq!(a, w.generate(&mesh, 500, 11), "{w}");
            assert_ne!(a, w.generate(&mesh, 500, 12), "{w}");
            // A prefix does not depend on how many points were asked for.
            assert_eq!(a[..100], w.generate(&mesh, 100, 11)[..], "{w}");
        }
        assert_ne!(
            PointWorkload::Near.generate(&mesh, 10, 5),
            PointWorkload::Volume.generate(&mesh, 10, 5),
        );
    }

    #[test]
    fn near_points_are_within_the_offset_of_the_surface() {
        let mesh = sphere();
        let bound = NEAR_OFFSET * mesh.bounds().diagonal();
        let points = PointWorkload::Near.generate(&mesh, 2000, 7);
        let mut farthest = 0.0f32;
        for p in &points {
            let d = distance_to_mesh(&mesh, *p);
            assert!(
                d <= bound * (1.0 + 1e-5),
                "{p} is {d} from the surface, bound {bound}"
            );
            farthest = farthest.max(d);
        }
        // The offsets really spread over the band (not all on the surface).
        assert!(farthest > 0.5 * bound, "farthest {farthest} of {bound}");
    }

    #[test]
    fn near_points_follow_area() {
        // One big and one tiny triangle far apart: almost every point is near the big one.
        let big = Triangle::new(
            Vec3::ZERO,
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 10.0, 0.0),
        );
        let tiny = Triangle::new(
            Vec3::new(0.0, 0.0, 50.0),
            Vec3::new(0.1, 0.0, 50.0),
            Vec3::new(0.0, 0.1, 50.0),
        );
        let point = Triangle::new(Vec3::splat(-30.0), Vec3::splat(-30.0), Vec3::splat(-30.0));
        let (mesh, _) = TriangleMesh::from_triangles(&[tiny, point, big]).unwrap();
        let points = PointWorkload::Near.generate(&mesh, 2000, 1);
        let near_big = points.iter().filter(|p| p.z.abs() < 10.0).count();
        let near_point = points.iter().filter(|p| p.x < -20.0).count();
        assert_eq!(near_point, 0, "zero-area triangles have no area to sample");
        // Expected share of the tiny triangle: 0.005 / 50.005 = 1e-4, so 0.2 points of 2000.
        assert!(near_big >= 1995, "{near_big} of 2000 near the big triangle");
    }

    #[test]
    fn volume_points_fill_the_enlarged_box() {
        let mesh = sphere();
        let b = mesh.bounds();
        let region = b.enlarged(VOLUME_MARGIN);
        let points = PointWorkload::Volume.generate(&mesh, 4000, 3);
        assert!(points.iter().all(|p| region.contains(*p)));
        // Some land in the margin, outside the scene box itself.
        let outside = points.iter().filter(|p| !b.contains(**p)).count();
        assert!(outside > 400, "{outside} of 4000 in the margin");
    }

    #[test]
    fn empty_and_degenerate_meshes() {
        let (empty, _) = TriangleMesh::new(vec![], vec![]).unwrap();
        assert!(PointWorkload::Near.generate(&empty, 10, 1).is_empty());
        let unit = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let volume = PointWorkload::Volume.generate(&empty, 100, 1);
        assert!(volume.len() == 100 && volume.iter().all(|p| unit.contains(*p)));
        // Only zero-area triangles: points are still near them (picked uniformly by index).
        let a = Vec3::new(1.0, 2.0, 3.0);
        let (dots, _) = TriangleMesh::from_triangles(&[Triangle::new(a, a, a)]).unwrap();
        let points = PointWorkload::Near.generate(&dots, 50, 1);
        assert_eq!(points.len(), 50);
        assert!(points.iter().all(|p| p.is_finite()));
    }
}
