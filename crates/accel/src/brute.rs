//! BruteForce: tests every triangle against every ray (and every query point). O(N) per query,
//! no build, no cleverness — which is the point: it is the oracle the other structures are
//! checked against. Ties (equal t, or equal distance for closest-point queries) resolve to the
//! lowest primitive index. Concessions to speed that change no answer and no counter: a ray
//! scan tests blocks of triangles four at a time without branches first ([`Tri4::test`] for
//! Möller–Trumbore, [`WatertightRay::may_hit4`] for the watertight test) and runs the scalar
//! test that decides only on the triangles that passed; the closest-point scan skips triangles
//! whose boxes are clearly farther than the best so far.

use crate::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, Nearest, PointHit};
use raybench_geom::{
    MollerTriangle, Ray, Tri4, TriHit, Triangle, TriangleMesh, TriangleTest, Vec3, Vertices4,
    WatertightRay, box_distance_squared,
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
    /// Triangles in the mesh (the packs may end in unused lanes).
    len: usize,
    /// The original vertices, for closest-point queries: `MollerTriangle` keeps edges, and
    /// `v0 - e1` does not always give back `v1` exactly.
    mesh: Arc<TriangleMesh>,
    /// The largest coordinate magnitude of the mesh (infinite when empty), which scales the
    /// closest-point scan's slack.
    extent: f32,
}

/// Triangles four to a pack, lane by lane (so the candidate test runs on four at once), in
/// mesh order, the last pack's unused lanes empty, in the layout their test wants:
/// Möller–Trumbore reads Embree's `v0, e1, e2` ([`Tri4`]), the watertight test the vertices.
#[derive(Debug)]
enum Triangles {
    Moller(Vec<Tri4>),
    Vertices(Vec<Vertices4>),
}

/// Triangles a tile of [`BruteForce::intersect_all`] holds: 192 KB of `Tri4`s (144 KB of
/// vertices), which stay in a core's L2 while every ray is scanned over them. A multiple of
/// [`BLOCK`], so each ray's blocks (and their windows) are the ones a scan of the whole mesh
/// has.
const TILE: usize = 4096;

/// Triangles whose candidate tests run before any of them is decided: eight packs of four.
const BLOCK: usize = 32;

impl BruteForce {
    fn trace<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        let mut s = Scan::new(ray);
        let first_hit = match &self.triangles {
            Triangles::Moller(packs) => blocks::<ANY_HIT, _>(&Moller, packs, 0, self.len, &mut s),
            Triangles::Vertices(packs) => {
                let w = Watertight(WatertightRay::new(ray));
                blocks::<ANY_HIT, _>(&w, packs, 0, self.len, &mut s)
            }
        };
        // Counted as the one-by-one loop counts: every triangle, or up to the first hit.
        c.prim_tests(first_hit.map_or(self.len, |prim| prim + 1) as u64);
        s.best
    }

    /// Every ray's closest hit, exactly as [`Accel::intersect`] answers it ray by ray (each
    /// ray meets the triangles in the same order, in the same blocks), scanned a tile of
    /// triangles at a time across all the rays: a mesh larger than the cache is then read
    /// from memory once a tile instead of once a ray. For oracles checking many rays.
    pub fn intersect_all(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        let mut scans: Vec<Scan> = rays.iter().map(Scan::new).collect();
        match &self.triangles {
            Triangles::Moller(packs) => by_tiles(packs, self.len, &mut scans, |_| Moller),
            Triangles::Vertices(packs) => by_tiles(packs, self.len, &mut scans, |r| {
                Watertight(WatertightRay::new(r))
            }),
        }
        scans.into_iter().map(|s| s.best).collect()
    }
}

/// Every scan over `packs` (the whole mesh, `len` triangles) a tile at a time, each ray with
/// the test `test_for` sets up for it (a few operations a tile of 4,096 triangles).
fn by_tiles<T: PackTest>(
    packs: &[T::Pack],
    len: usize,
    scans: &mut [Scan],
    test_for: impl Fn(&Ray) -> T,
) {
    for (k, tile) in packs.chunks(TILE / 4).enumerate() {
        for s in scans.iter_mut() {
            blocks::<false, _>(&test_for(&s.ray), tile, k * TILE, len, s);
        }
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

/// A triangle test over packs of four triangles: a candidate test of a pack's four lanes that
/// never says no where the deciding test would hit, and the deciding test on one lane.
trait PackTest {
    type Pack;
    fn candidates(&self, pack: &Self::Pack, ray: &Ray) -> u32;
    fn decide(&self, pack: &Self::Pack, lane: usize, ray: &Ray) -> Option<TriHit>;
}

/// Möller–Trumbore: the candidates are [`Tri4::test`]'s hits (bit for bit the scalar test on
/// each lane), the deciding test the scalar test on the lane rebuilt as the
/// [`MollerTriangle`] it was packed from.
struct Moller;

impl PackTest for Moller {
    type Pack = Tri4;

    #[inline(always)]
    fn candidates(&self, pack: &Tri4, ray: &Ray) -> u32 {
        pack.test(ray, ray.t_max()).mask
    }

    #[inline(always)]
    fn decide(&self, pack: &Tri4, lane: usize, ray: &Ray) -> Option<TriHit> {
        pack.lane(lane).intersect(ray)
    }
}

/// The watertight test, the ray set up once, its window taken from the scan's.
struct Watertight(WatertightRay);

impl PackTest for Watertight {
    type Pack = Vertices4;

    #[inline(always)]
    fn candidates(&self, pack: &Vertices4, ray: &Ray) -> u32 {
        self.0.with_window_of(ray).may_hit4(pack)
    }

    #[inline(always)]
    fn decide(&self, pack: &Vertices4, lane: usize, ray: &Ray) -> Option<TriHit> {
        self.0.with_window_of(ray).intersect(&pack.lane(lane))
    }
}

/// The one loop: every triangle of `packs` (four to a pack, the first of them triangle
/// `first`, the mesh's `len` in all), keeping the closest hit, or stopping at the first hit for
/// any-hit queries (its index returned). The deciding test decides every answer; the candidate
/// test is run first on a block's packs, so that the deciding test (whose branches a scan
/// mispredicts) runs only where it can hit.
#[inline(always)]
fn blocks<const ANY_HIT: bool, T: PackTest>(
    test: &T,
    packs: &[T::Pack],
    first: usize,
    len: usize,
    s: &mut Scan,
) -> Option<usize> {
    for (b, block) in packs.chunks(BLOCK / 4).enumerate() {
        let start = first + b * BLOCK;
        // Every triangle of the block against the window at its start: a later hit only
        // narrows it, so this never drops a triangle the deciding test would hit. The last
        // block's unused lanes are masked off.
        let mut candidates = 0u32;
        for (k, pack) in block.iter().enumerate() {
            candidates |= test.candidates(pack, &s.ray) << (4 * k);
        }
        if len - start < BLOCK {
            candidates &= (1 << (len - start)) - 1;
        }
        while candidates != 0 {
            let i = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            if let Some(h) = test.decide(&block[i / 4], i % 4, &s.ray)
                && s.offer(start + i, h)
                && ANY_HIT
            {
                return Some(start + i);
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

impl Accel for BruteForce {
    type Params = BruteForceParams;

    fn build(mesh: Arc<TriangleMesh>, params: &BruteForceParams) -> Result<Self, BuildError> {
        let name = match params.triangle_test {
            TriangleTest::MollerTrumbore => "bruteforce",
            TriangleTest::Watertight => "bruteforce-watertight",
        };
        let tris: Vec<Triangle> = mesh.triangles().collect();
        let triangles = match params.triangle_test {
            TriangleTest::MollerTrumbore => Triangles::Moller(
                tris.chunks(4)
                    .enumerate()
                    .map(|(k, four)| {
                        let mut pack = Tri4::default();
                        for (l, t) in four.iter().enumerate() {
                            pack.set_lane(l, (4 * k + l) as u32, &MollerTriangle::new(t));
                        }
                        pack
                    })
                    .collect(),
            ),
            TriangleTest::Watertight => {
                Triangles::Vertices(tris.chunks(4).map(Vertices4::pack).collect())
            }
        };
        let b = mesh.bounds();
        let extent = b.min.abs().max(b.max.abs()).max_element();
        Ok(BruteForce {
            name: name.to_string(),
            triangles,
            len: tris.len(),
            mesh,
            extent,
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    crate::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        let n = self.len as f64;
        BuildStats {
            nodes: 0,
            leaves: 1,
            max_depth: 0,
            refs: self.len as u64,
            // One leaf holding everything: every ray pays every test.
            sah_cost: Some(n * crate::SAH_INTERSECTION_COST),
            extra: Default::default(),
        }
    }

    fn memory(&self) -> Memory {
        let bytes = match &self.triangles {
            Triangles::Moller(packs) => std::mem::size_of_val(packs.as_slice()),
            Triangles::Vertices(packs) => std::mem::size_of_val(packs.as_slice()),
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
mod tests;
