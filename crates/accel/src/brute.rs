//! BruteForce: tests every triangle against every ray (and every query point). O(N) per query,
//! no build, no cleverness — which is the point: it is the oracle the other structures are
//! checked against. Ties (equal t, or equal distance for closest-point queries) resolve to the
//! lowest primitive index.

use crate::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, Nearest, PointHit};
use raybench_geom::{MollerTriangle, Ray, TriHit, Triangle, TriangleMesh, TriangleTest, Vec3};
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug, Default, Serialize)]
pub struct BruteForceParams {
    pub triangle_test: TriangleTest,
}

#[derive(Debug)]
pub struct BruteForce {
    name: String,
    triangles: Triangles,
    /// The original vertices, for closest-point queries: `MollerTriangle` keeps edges, and
    /// `v0 - e1` does not always give back `v1` exactly.
    mesh: Arc<TriangleMesh>,
}

/// Triangles in the layout their test wants: Möller–Trumbore reads Embree's precomputed
/// `v0, e1, e2, Ng`; the watertight test reads the vertices.
#[derive(Debug)]
enum Triangles {
    Moller(Vec<MollerTriangle>),
    Vertices(Vec<Triangle>),
}

impl BruteForce {
    fn trace<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        match &self.triangles {
            Triangles::Moller(t) => scan::<ANY_HIT, _, _>(t, ray, c, |t, r| t.intersect(r)),
            Triangles::Vertices(t) => {
                scan::<ANY_HIT, _, _>(t, ray, c, |t, r| t.intersect_watertight(r))
            }
        }
    }
}

/// The one loop: every triangle, keeping the closest hit (the lowest index on equal t), or
/// stopping at the first hit for any-hit queries.
#[inline(always)]
fn scan<const ANY_HIT: bool, T, C: CounterSink>(
    tris: &[T],
    ray: &Ray,
    c: &mut C,
    test: impl Fn(&T, &Ray) -> Option<TriHit>,
) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut r = *ray;
    for (prim, tri) in tris.iter().enumerate() {
        c.prim_tests(1);
        let Some(h) = test(tri, &r) else { continue };
        if best.is_some_and(|b| h.t >= b.t) {
            continue; // equal t: keep the lower primitive index
        }
        best = Some(Hit::from_tri_hit(prim as u32, h));
        if ANY_HIT {
            break;
        }
        r = r.with_t_max(h.t);
    }
    best
}

/// The closest-point scan: every triangle's exact closest point, keeping the nearest within
/// the radius (the lowest index on equal distance, [`Nearest`]'s rule). One `prim_tests` per
/// point–triangle distance.
fn closest_point_scan<C: CounterSink>(
    mesh: &TriangleMesh,
    p: Vec3,
    max_radius: f32,
    c: &mut C,
) -> Option<PointHit> {
    let mut nearest = Nearest::within(p, max_radius)?;
    for (prim, tri) in mesh.triangles().enumerate() {
        c.prim_tests(1);
        nearest.test_triangle(p, prim as u32, &tri);
    }
    nearest.into_hit()
}

impl BruteForce {
    fn len(&self) -> usize {
        match &self.triangles {
            Triangles::Moller(t) => t.len(),
            Triangles::Vertices(t) => t.len(),
        }
    }
}

impl Accel for BruteForce {
    type Params = BruteForceParams;

    fn build(mesh: Arc<TriangleMesh>, params: &BruteForceParams) -> Result<Self, BuildError> {
        let name = match params.triangle_test {
            TriangleTest::MollerTrumbore => "bruteforce",
            TriangleTest::Watertight => "bruteforce-watertight",
        };
        let triangles = match params.triangle_test {
            TriangleTest::MollerTrumbore => {
                Triangles::Moller(mesh.triangles().map(|t| MollerTriangle::new(&t)).collect())
            }
            TriangleTest::Watertight => Triangles::Vertices(mesh.triangles().collect()),
        };
        Ok(BruteForce {
            name: name.to_string(),
            triangles,
            mesh,
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    crate::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        let n = self.len() as f64;
        BuildStats {
            nodes: 0,
            leaves: 1,
            max_depth: 0,
            refs: self.len() as u64,
            // One leaf holding everything: every ray pays every test.
            sah_cost: Some(n * crate::SAH_INTERSECTION_COST),
            extra: Default::default(),
        }
    }

    fn memory(&self) -> Memory {
        let bytes = match &self.triangles {
            Triangles::Moller(t) => std::mem::size_of_val(t.as_slice()),
            Triangles::Vertices(t) => std::mem::size_of_val(t.as_slice()),
        };
        Memory {
            primitives: bytes as u64,
            ..Memory::default()
        }
    }
}

impl crate::Walk for BruteForce {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        closest_point_scan(&self.mesh, p, max_radius, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Counters;
    use raybench_geom::Vec3;

    fn two_layers() -> Arc<TriangleMesh> {
        // Two identical triangles at z = 0 (a tie) and one at z = -1.
        let t = |z: f32| {
            Triangle::new(
                Vec3::new(0.0, 0.0, z),
                Vec3::new(1.0, 0.0, z),
                Vec3::new(0.0, 1.0, z),
            )
        };
        Arc::new(
            TriangleMesh::from_triangles(&[t(-1.0), t(0.0), t(0.0)])
                .unwrap()
                .0,
        )
    }

    #[test]
    fn closest_hit_and_lowest_prim_on_ties() {
        let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
        let r = Ray::infinite(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let h = bf.intersect(&r).unwrap();
        assert_eq!((h.t, h.prim), (1.0, 1));
        let mut c = Counters::default();
        assert_eq!(bf.intersect_counted(&r, &mut c), Some(h));
        assert_eq!(c.prim_tests, 3);
        assert!(bf.occluded(&r));
        let mut c = Counters::default();
        assert!(bf.occluded_counted(&r, &mut c));
        assert_eq!(c.prim_tests, 1, "any hit stops at the first hit");
    }

    #[test]
    fn empty_mesh_misses() {
        let (mesh, _) = TriangleMesh::new(vec![], vec![]).unwrap();
        let bf = BruteForce::build(Arc::new(mesh), &Default::default()).unwrap();
        let r = Ray::infinite(Vec3::ZERO, Vec3::X);
        assert_eq!(bf.intersect(&r), None);
        assert!(!bf.occluded(&r));
    }

    #[test]
    fn closest_point_is_nearest_with_lowest_prim_on_ties() {
        let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
        let p = Vec3::new(0.2, 0.2, 1.0);
        let h = bf.closest_point(p, f32::INFINITY).unwrap();
        assert_eq!((h.prim, h.distance), (1, 1.0));
        // Face region: the barycentric weights are rounded, the point is not exactly (0.2, 0.2).
        assert!(
            h.point.distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6,
            "{}",
            h.point
        );
        let mut c = Counters::default();
        assert_eq!(bf.closest_point_counted(p, f32::INFINITY, &mut c), Some(h));
        assert_eq!(c.prim_tests, 3, "one distance test per triangle");
        // Below both layers: the z = -1 triangle (prim 0) is nearer.
        let below = bf.closest_point(Vec3::new(0.2, 0.2, -1.5), f32::INFINITY);
        assert_eq!(below.map(|h| (h.prim, h.distance)), Some((0, 0.5)));
    }

    #[test]
    fn closest_point_radius_is_inclusive() {
        let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
        let p = Vec3::new(0.2, 0.2, 1.0);
        assert_eq!(bf.closest_point(p, 1.0).map(|h| h.prim), Some(1));
        assert_eq!(bf.closest_point(p, 0.999), None);
        let on_surface = Vec3::new(0.0, 0.0, 0.0);
        assert_eq!(bf.closest_point(on_surface, 0.0).map(|h| h.prim), Some(1));
    }

    #[test]
    fn closest_point_rejects_bad_queries_without_panicking() {
        let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
        let mut c = Counters::default();
        for (p, r) in [
            (Vec3::new(f32::NAN, 0.0, 0.0), f32::INFINITY),
            (Vec3::new(0.0, f32::INFINITY, 0.0), f32::INFINITY),
            (Vec3::new(0.0, 0.0, 1e19), f32::INFINITY),
            (Vec3::ZERO, -1.0),
            (Vec3::ZERO, f32::NAN),
        ] {
            assert_eq!(bf.closest_point(p, r), None, "{p} {r}");
            assert_eq!(bf.closest_point_counted(p, r, &mut c), None, "{p} {r}");
        }
        assert_eq!(c.prim_tests, 0, "rejected before any test");
    }

    #[test]
    fn closest_point_on_zero_area_triangle_and_empty_mesh() {
        let a = Vec3::new(1.0, 2.0, 3.0);
        let point = Triangle::new(a, a, a);
        let segment = Triangle::new(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::X);
        let mesh = TriangleMesh::from_triangles(&[point, segment]).unwrap().0;
        let bf = BruteForce::build(Arc::new(mesh), &Default::default()).unwrap();
        let h = bf
            .closest_point(Vec3::new(1.0, 2.0, 4.0), f32::INFINITY)
            .unwrap();
        assert_eq!((h.prim, h.point, h.distance), (0, a, 1.0));
        let h = bf
            .closest_point(Vec3::new(1.5, -2.0, 0.0), f32::INFINITY)
            .unwrap();
        assert_eq!(
            (h.prim, h.point, h.distance),
            (1, Vec3::new(1.5, 0.0, 0.0), 2.0)
        );

        let (empty, _) = TriangleMesh::new(vec![], vec![]).unwrap();
        let bf = BruteForce::build(Arc::new(empty), &Default::default()).unwrap();
        assert_eq!(bf.closest_point(Vec3::ZERO, f32::INFINITY), None);
    }

    #[test]
    fn usable_as_trait_object() {
        let dynamic = crate::build_dyn::<BruteForce>(two_layers(), &Default::default()).unwrap();
        assert_eq!(dynamic.name(), "bruteforce");
    }
}
