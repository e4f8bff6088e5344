//! BruteForce: tests every triangle against every ray. O(N) per ray, no build, no cleverness —
//! which is the point: it is the oracle the other structures are checked against. Ties (equal
//! t) resolve to the lowest primitive index.

use crate::{Accel, BuildError, BuildStats, CounterSink, Counters, Hit, Memory, NoCount};
use raybench_geom::{Ray, Triangle, TriangleMesh, TriangleTest};
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug, Default, Serialize)]
pub struct BruteForceParams {
    pub triangle_test: TriangleTest,
}

#[derive(Debug)]
pub struct BruteForce {
    name: String,
    test: TriangleTest,
    triangles: Vec<Triangle>,
}

impl BruteForce {
    fn trace<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut r = *ray;
        for (prim, tri) in self.triangles.iter().enumerate() {
            c.prim_tests(1);
            let Some(h) = tri.intersect(&r, self.test) else {
                continue;
            };
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
}

impl Accel for BruteForce {
    type Params = BruteForceParams;

    fn build(mesh: Arc<TriangleMesh>, params: &BruteForceParams) -> Result<Self, BuildError> {
        let name = match params.triangle_test {
            TriangleTest::MollerTrumbore => "bruteforce",
            TriangleTest::Watertight => "bruteforce-watertight",
        };
        Ok(BruteForce {
            name: name.to_string(),
            test: params.triangle_test,
            triangles: mesh.triangles().collect(),
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
        let n = self.triangles.len() as f64;
        BuildStats {
            nodes: 0,
            leaves: 1,
            max_depth: 0,
            refs: self.triangles.len() as u64,
            // One leaf holding everything: every ray pays every test.
            sah_cost: Some(n * crate::SAH_INTERSECTION_COST),
            extra: Default::default(),
        }
    }

    fn memory(&self) -> Memory {
        Memory {
            primitives: std::mem::size_of_val(self.triangles.as_slice()) as u64,
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
