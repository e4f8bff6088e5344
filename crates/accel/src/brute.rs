//! BruteForce: tests every triangle against every ray. O(N) per ray, no build, no cleverness —
//! which is the point: it is the oracle the other structures are checked against. Ties (equal
//! t) resolve to the lowest primitive index.

use crate::{Accel, BuildError, BuildStats, CounterSink, Counters, Hit, Memory, NoCount};
use raybench_geom::{MollerTriangle, Ray, TriHit, Triangle, TriangleMesh, TriangleTest};
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
        best = Some(Hit {
            t: h.t,
            prim: prim as u32,
            u: h.u,
            v: h.v,
        });
        if ANY_HIT {
            break;
        }
        r = r.with_t_max(h.t);
    }
    best
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
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.trace::<false, _>(ray, &mut NoCount)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.trace::<true, _>(ray, &mut NoCount).is_some()
    }

    fn intersect_counted(&self, ray: &Ray, c: &mut Counters) -> Option<Hit> {
        self.trace::<false, _>(ray, c)
    }

    fn occluded_counted(&self, ray: &Ray, c: &mut Counters) -> bool {
        self.trace::<true, _>(ray, c).is_some()
    }

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

#[cfg(test)]
mod tests {
    use super::*;
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
    fn usable_as_trait_object() {
        let dynamic = crate::build_dyn::<BruteForce>(two_layers(), &Default::default()).unwrap();
        assert_eq!(dynamic.name(), "bruteforce");
    }
}
