//! BruteForce: tests every triangle against every ray (and every query point). O(N) per query,
//! no build, no cleverness — which is the point: it is the oracle the other structures are
//! checked against. Ties (equal t, or equal distance for closest-point queries) resolve to the
//! lowest primitive index. Concessions to speed that change no answer and no counter: a ray
//! scan tests blocks of triangles without branches first (the same arithmetic: for Möller–
//! Trumbore the four-lane [`Tri4::test`], for the watertight test its candidate test) and runs
//! the scalar test that decides only on the triangles that passed; the closest-point scan skips
//! triangles whose boxes are clearly farther than the best so far.

use crate::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, Nearest, PointHit};
use raybench_geom::{
    MollerTriangle, Ray, Tri4, TriHit, Triangle, TriangleMesh, TriangleTest, Vec3, WatertightRay,
    box_distance_squared,
};
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
    /// The largest coordinate magnitude of the mesh (infinite when empty), which scales the
    /// closest-point scan's slack.
    extent: f32,
}

/// Triangles in the layout their test wants: Möller–Trumbore reads Embree's `v0, e1, e2` four
/// triangles to a [`Tri4`] (lane by lane, so the candidate test runs on four at once), in mesh
/// order, the last one's unused lanes empty; the watertight test reads the vertices.
#[derive(Debug)]
enum Triangles {
    Moller { tri4s: Vec<Tri4>, len: usize },
    Vertices(Vec<Triangle>),
}

/// Triangles a tile of [`BruteForce::intersect_all`] holds: 192 KB of `Tri4`s (144 KB of
/// vertices), which stay in a core's L2 while every ray is scanned over them. A multiple of
/// both scans' blocks, so each ray's blocks (and their windows) are the ones a scan of the
/// whole mesh has.
const TILE: usize = 4096;

impl BruteForce {
    fn trace<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        let mut s = Scan::new(ray);
        let first_hit = match &self.triangles {
            Triangles::Moller { tri4s, .. } => moller_blocks::<ANY_HIT>(tri4s, 0, &mut s),
            Triangles::Vertices(t) => {
                vertex_blocks::<ANY_HIT>(t, 0, &WatertightRay::new(ray), &mut s)
            }
        };
        // Counted as the one-by-one loop counts: every triangle, or up to the first hit.
        c.prim_tests(first_hit.map_or(self.len(), |prim| prim + 1) as u64);
        s.best
    }

    /// Every ray's closest hit, exactly as [`Accel::intersect`] answers it ray by ray (each
    /// ray meets the triangles in the same order, in the same blocks), scanned a tile of
    /// triangles at a time across all the rays: a mesh larger than the cache is then read
    /// from memory once a tile instead of once a ray. For oracles checking many rays.
    pub fn intersect_all(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        let mut scans: Vec<Scan> = rays.iter().map(Scan::new).collect();
        match &self.triangles {
            Triangles::Moller { tri4s, .. } => {
                for (k, tile) in tri4s.chunks(TILE / 4).enumerate() {
                    for s in &mut scans {
                        moller_blocks::<false>(tile, k * TILE / 4, s);
                    }
                }
            }
            Triangles::Vertices(t) => {
                let set_up: Vec<WatertightRay> = rays.iter().map(WatertightRay::new).collect();
                for (k, tile) in t.chunks(TILE).enumerate() {
                    for (s, w) in scans.iter_mut().zip(&set_up) {
                        vertex_blocks::<false>(tile, k * TILE, w, s);
                    }
                }
            }
        }
        scans.into_iter().map(|s| s.best).collect()
    }
}

/// One ray's scan in progress: its closest hit so far and its window narrowed to it.
#[derive(Clone, Copy)]
struct Scan {
    best: Option<Hit>,
    ray: Ray,
}

impl Scan {
    fn new(ray: &Ray) -> Scan {
        Scan {
            best: None,
            ray: *ray,
        }
    }

    /// Keeps triangle `prim`'s hit `h` if it is nearer than the best so far (on equal t the
    /// lower index, met first, stays); whether it was kept.
    #[inline(always)]
    fn offer(&mut self, prim: usize, h: TriHit) -> bool {
        if self.best.is_some_and(|b| h.t >= b.t) {
            return false;
        }
        self.best = Some(Hit::from_tri_hit(prim as u32, h));
        self.ray = self.ray.with_t_max(h.t);
        true
    }
}

/// The one loop over the vertices (`tris`, the first of them triangle `first`): every
/// triangle, keeping the closest hit, or stopping at the first hit for any-hit queries (its
/// index returned). The watertight test decides every answer; its candidate test, which never
/// says no where the test would hit, is run first on blocks of triangles, so that the test
/// (whose branches a scan mispredicts) runs only where it can hit.
#[inline(always)]
fn vertex_blocks<const ANY_HIT: bool>(
    tris: &[Triangle],
    first: usize,
    w: &WatertightRay,
    s: &mut Scan,
) -> Option<usize> {
    const BLOCK: usize = 32;
    for (b, block) in tris.chunks(BLOCK).enumerate() {
        // Every triangle of the block against the window at its start: a later hit only
        // narrows it, so this never drops a triangle the test would hit.
        let window = w.with_window_of(&s.ray);
        let mut candidates = 0u32;
        for (i, tri) in block.iter().enumerate() {
            candidates |= (window.may_hit(tri) as u32) << i;
        }
        while candidates != 0 {
            let i = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let prim = first + b * BLOCK + i;
            if let Some(h) = w.with_window_of(&s.ray).intersect(&block[i])
                && s.offer(prim, h)
                && ANY_HIT
            {
                return Some(prim);
            }
        }
    }
    None
}

/// [`vertex_blocks`] for Möller–Trumbore over [`Tri4`]s (the first of them `Tri4` `first`):
/// blocks of eight `Tri4`s, each tested on its four lanes at once against the window at the
/// block's start ([`Tri4::test`], bit for bit the scalar test), then the scalar test on each
/// lane that hit, a lane rebuilt as the [`MollerTriangle`] it was packed from.
#[inline(always)]
fn moller_blocks<const ANY_HIT: bool>(tri4s: &[Tri4], first: usize, s: &mut Scan) -> Option<usize> {
    const BLOCK: usize = 8;
    for (b, block) in tri4s.chunks(BLOCK).enumerate() {
        let mut candidates = 0u32;
        for (k, tri4) in block.iter().enumerate() {
            candidates |= tri4.test(&s.ray, s.ray.t_max()).mask << (4 * k);
        }
        while candidates != 0 {
            let i = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let prim = (first + b * BLOCK) * 4 + i;
            if let Some(h) = block[i / 4].lane(i % 4).intersect(&s.ray)
                && s.offer(prim, h)
                && ANY_HIT
            {
                return Some(prim);
            }
        }
    }
    None
}

/// The closest-point scan: every triangle's exact closest point, keeping the nearest within
/// the radius (the lowest index on equal distance, [`Nearest`]'s rule). One `prim_tests` per
/// triangle, as if every distance were computed. A triangle whose box is clearly farther than
/// the best so far is skipped without its distance: farther by a relative 2^-10 and by 2^-20 of
/// the largest coordinate, which no rounding of the nearest point (computed in f64, rounded to
/// f32) comes near, so the oracle does not lean on the exact box rule the structures prune
/// with. A later triangle wins only by being nearer (ties go to the lower index), so a skipped
/// one could not have won.
fn closest_point_scan<C: CounterSink>(
    mesh: &TriangleMesh,
    extent: f32,
    p: Vec3,
    max_radius: f32,
    c: &mut C,
) -> Option<PointHit> {
    let mut nearest = Nearest::within(p, max_radius)?;
    let slack = (extent.max(p.abs().max_element()) as f64 * (-20f64).exp2()).powi(2);
    for prim in 0..mesh.len() {
        c.prim_tests(1);
        let tri = mesh.triangle(prim);
        let bound = nearest.bound_d2() as f64;
        if box_distance_squared(p, &tri.bounds()) as f64 > bound + bound / 1024.0 + slack {
            continue;
        }
        nearest.test_triangle(p, prim as u32, &tri);
    }
    nearest.into_hit()
}

impl BruteForce {
    fn len(&self) -> usize {
        match &self.triangles {
            Triangles::Moller { len, .. } => *len,
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
                let tris: Vec<(u32, MollerTriangle)> = mesh
                    .triangles()
                    .enumerate()
                    .map(|(i, t)| (i as u32, MollerTriangle::new(&t)))
                    .collect();
                Triangles::Moller {
                    tri4s: tris.chunks(4).map(Tri4::pack).collect(),
                    len: tris.len(),
                }
            }
            TriangleTest::Watertight => Triangles::Vertices(mesh.triangles().collect()),
        };
        let b = mesh.bounds();
        let extent = b.min.abs().max(b.max.abs()).max_element();
        Ok(BruteForce {
            name: name.to_string(),
            triangles,
            mesh,
            extent,
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
            Triangles::Moller { tri4s, .. } => std::mem::size_of_val(tri4s.as_slice()),
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
        closest_point_scan(&self.mesh, self.extent, p, max_radius, c)
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

    /// The scan in blocks (the branch-free test first) answers and counts as a plain loop over
    /// every triangle with the Möller test: closest hit (ties to the lower index, layered and
    /// repeated triangles), any hit, and `prim_tests` up to the first hit, on a soup whose
    /// last block is partial.
    #[test]
    fn the_blocked_scan_answers_and_counts_as_one_triangle_at_a_time() {
        let mut rng = raybench_geom::SplitMix64::new(0x2545_f491_4f6c_dd1d);
        let mut next = move || rng.unit();
        let mut v = || Vec3::new(next(), next(), next());
        let mut tris: Vec<Triangle> = (0..1_000)
            .map(|_| {
                let c = v() * 4.0;
                Triangle::new(c + v() - Vec3::splat(0.5), c + v(), c - v())
            })
            .collect();
        // A repeated triangle in a later block: equal t, the earlier index must win.
        tris.push(tris[7]);
        tris.extend_from_within(40..45);
        let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
        let bf = BruteForce::build(mesh.clone(), &Default::default()).unwrap();
        let moller: Vec<_> = mesh.triangles().map(|t| MollerTriangle::new(&t)).collect();
        let (mut hit, mut missed) = (0, 0);
        for i in 0..2_000 {
            let o = v() * 6.0 - Vec3::ONE;
            let d = if i % 2 == 0 {
                v() - Vec3::splat(0.5)
            } else {
                moller[i % 1_000].v0 - o
            };
            let t_max = if i % 5 == 0 { 2.0 } else { f32::INFINITY };
            let ray = Ray::new(o, d, 0.0, t_max);
            // The plain loop: every triangle in order, the window shrinking at each hit.
            let (mut best, mut r, mut first_hit) = (None::<Hit>, ray, None);
            for (prim, m) in moller.iter().enumerate() {
                if let Some(h) = m.intersect(&r) {
                    first_hit.get_or_insert(prim as u64 + 1);
                    if !best.is_some_and(|b| h.t >= b.t) {
                        best = Some(Hit::from_tri_hit(prim as u32, h));
                        r = r.with_t_max(h.t);
                    }
                }
            }
            let mut c = Counters::default();
            assert_eq!(bf.intersect_counted(&ray, &mut c), best, "ray {i}");
            assert_eq!(c.prim_tests, moller.len() as u64);
            let mut c = Counters::default();
            assert_eq!(bf.occluded_counted(&ray, &mut c), best.is_some(), "ray {i}");
            assert_eq!(
                c.prim_tests,
                first_hit.unwrap_or(moller.len() as u64),
                "ray {i}"
            );
            if best.is_some() {
                hit += 1
            } else {
                missed += 1
            }
        }
        assert!(hit > 500 && missed > 500, "{hit} hits, {missed} misses");
    }

    /// `intersect_all` answers every ray as `intersect` does, for both triangle tests, on a
    /// mesh of three tiles (the last partial) with triangles repeated across a tile boundary
    /// (ties, the earlier index winning) and windows ending short of some hits.
    #[test]
    fn every_ray_at_once_answers_as_ray_by_ray() {
        let mut rng = raybench_geom::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut next = move || rng.unit();
        let mut v = || Vec3::new(next(), next(), next());
        let mut tris: Vec<Triangle> = (0..2 * TILE + 900)
            .map(|_| {
                let c = v() * 8.0;
                Triangle::new(c + v() - Vec3::splat(0.5), c + v(), c - v())
            })
            .collect();
        tris.extend_from_within(TILE - 20..TILE + 20);
        let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
        let rays: Vec<Ray> = (0..600)
            .map(|i| {
                let o = v() * 10.0 - Vec3::ONE;
                let d = if i % 2 == 0 {
                    v() - Vec3::splat(0.5)
                } else {
                    mesh.triangle(TILE - 20 + i % 40).centroid() - o
                };
                Ray::new(o, d, 0.0, if i % 3 == 0 { 0.9 } else { f32::INFINITY })
            })
            .collect();
        for triangle_test in [TriangleTest::MollerTrumbore, TriangleTest::Watertight] {
            let bf = BruteForce::build(mesh.clone(), &BruteForceParams { triangle_test }).unwrap();
            let one_by_one: Vec<_> = rays.iter().map(|r| bf.intersect(r)).collect();
            assert_eq!(bf.intersect_all(&rays), one_by_one, "{triangle_test:?}");
            let hits: Vec<u32> = one_by_one.iter().flatten().map(|h| h.prim).collect();
            assert!(hits.len() > 200, "{triangle_test:?}: {} hits", hits.len());
            // Rays aimed at the repeated triangles hit the first copy, before the boundary.
            assert!(
                hits.iter()
                    .any(|&p| (TILE as u32 - 20..TILE as u32).contains(&p))
            );
            assert!(hits.iter().all(|&p| p < 2 * TILE as u32 + 900));
        }
    }

    /// The closest-point scan with its box skip answers as testing every triangle does, at
    /// three scales (unit, tiny and far from the origin), for points near the triangles and
    /// far from them, at an infinite radius and a small one, with repeated triangles (ties).
    #[test]
    fn the_closest_point_scan_answers_as_testing_every_triangle() {
        let mut rng = raybench_geom::SplitMix64::new(0x853c_49e6_748f_ea9b);
        let mut next = move || rng.unit();
        let mut found_some = false;
        for (scale, offset) in [(1.0, 0.0), (1e-15, 0.0), (1.0, 1e6)] {
            let mut v = || Vec3::new(next(), next(), next());
            let at = |x: Vec3| x * scale + Vec3::splat(offset);
            let mut tris: Vec<Triangle> = (0..600)
                .map(|_| {
                    let c = v() * 8.0;
                    Triangle::new(at(c), at(c + v()), at(c - v()))
                })
                .collect();
            tris.extend_from_within(10..20);
            let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
            let bf = BruteForce::build(mesh.clone(), &Default::default()).unwrap();
            for i in 0..400 {
                let p = if i % 2 == 0 {
                    mesh.triangle(i % tris.len()).v1 + (v() - Vec3::splat(0.5)) * scale * 0.01
                } else {
                    at(v() * 12.0 - Vec3::splat(2.0))
                };
                for radius in [f32::INFINITY, 0.5 * scale] {
                    let mut every = Nearest::within(p, radius).unwrap();
                    let mut distances = 0;
                    for (prim, tri) in mesh.triangles().enumerate() {
                        every.test_triangle(p, prim as u32, &tri);
                        distances += 1;
                    }
                    let mut c = Counters::default();
                    let got = bf.closest_point_counted(p, radius, &mut c);
                    assert_eq!(got, every.into_hit(), "scale {scale}, point {i}, {radius}");
                    assert_eq!(c.prim_tests, distances);
                    found_some |= got.is_some();
                }
            }
        }
        assert!(found_some);
    }

    #[test]
    fn usable_as_trait_object() {
        let dynamic = crate::build_dyn::<BruteForce>(two_layers(), &Default::default()).unwrap();
        assert_eq!(dynamic.name(), "bruteforce");
    }
}
