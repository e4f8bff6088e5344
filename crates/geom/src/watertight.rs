//! The watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2(1), 2013): shear the
//! triangle into ray space (the largest direction axis becomes z), evaluate the 2D edge
//! functions, and redo them in f64 when one is exactly 0, so two triangles sharing an edge never
//! both miss a ray through it. Same depth semantics as the Möller test: `t_min < t <= t_max`.
//!
//! The axis permutation and the shear depend on the ray alone, so [`WatertightRay`] computes
//! them once; a scan over many triangles (brute force) tests each with the rest.

use crate::{Ray, TriHit, Triangle};
use glam::Vec3;

/// A ray set up for the watertight test.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: Vec3,
    /// The permuted axes: `kz` the direction's largest, `kx`, `ky` the others, swapped when
    /// the direction along `kz` is negative (so the edge functions keep their winding).
    k: [usize; 3],
    /// The shear `d[kx] / d[kz]`, `d[ky] / d[kz]` and the scale `1 / d[kz]`.
    s: [f32; 3],
    t_min: f32,
    t_max: f32,
}

impl WatertightRay {
    #[inline(always)]
    pub fn new(ray: &Ray) -> WatertightRay {
        let d = ray.dir();
        let kz = d.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        WatertightRay {
            origin: ray.origin(),
            k: [kx, ky, kz],
            s: [d[kx] * sz, d[ky] * sz, sz],
            t_min: ray.t_min(),
            t_max: ray.t_max(),
        }
    }

    /// The same set-up with the window of `ray` (the same ray, its window narrowed).
    #[inline(always)]
    pub fn with_window_of(&self, ray: &Ray) -> WatertightRay {
        WatertightRay {
            t_min: ray.t_min(),
            t_max: ray.t_max(),
            ..*self
        }
    }

    /// The triangle's vertices relative to the origin, sheared: `(x, y)` of each and its `z`
    /// (unscaled), in the order `a`, `b`, `c`.
    #[inline(always)]
    fn shear(&self, tri: &Triangle) -> [(f32, f32, f32); 3] {
        [
            self.shear_one(tri.v0),
            self.shear_one(tri.v1),
            self.shear_one(tri.v2),
        ]
    }

    #[inline(always)]
    fn shear_one(&self, v: Vec3) -> (f32, f32, f32) {
        let [kx, ky, kz] = self.k;
        let [sx, sy, _] = self.s;
        let p = v - self.origin;
        (p[kx] - sx * p[kz], p[ky] - sy * p[kz], p[kz])
    }

    /// The watertight test: the hit's distance and the barycentrics of `v1` and `v2`.
    #[inline(always)]
    pub fn intersect(&self, tri: &Triangle) -> Option<TriHit> {
        let [(ax, ay, az), (bx, by, bz), (cx, cy, cz)] = self.shear(tri);
        let sz = self.s[2];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let edge = |px: f32, py: f32, qx: f32, qy: f32| {
                (px as f64 * qy as f64 - py as f64 * qx as f64) as f32
            };
            u = edge(cx, cy, bx, by);
            v = edge(ax, ay, cx, cy);
            w = edge(bx, by, ax, ay);
        }
        let negative = u < 0.0 || v < 0.0 || w < 0.0;
        let positive = u > 0.0 || v > 0.0 || w > 0.0;
        if negative && positive {
            return None;
        }
        let det = u + v + w;
        if !(det != 0.0) {
            return None;
        }
        let t = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
        let in_range = if det > 0.0 {
            det * self.t_min < t && t <= det * self.t_max
        } else {
            det * self.t_min > t && t >= det * self.t_max
        };
        if !in_range {
            return None;
        }
        let inv = 1.0 / det;
        Some(TriHit {
            t: t * inv,
            u: v * inv,
            v: w * inv,
        })
    }

    /// [`shear_one`](Self::shear_one)'s operations on the four lanes of one vertex
    /// (`vertex[axis][lane]`): `(v - origin)` read on the permuted axes, sheared.
    #[inline(always)]
    fn shear4(&self, vertex: &[[f32; 4]; 3]) -> [[f32; 4]; 3] {
        let [kx, ky, kz] = self.k;
        let [sx, sy, _] = self.s;
        let (ox, oy, oz) = (self.origin[kx], self.origin[ky], self.origin[kz]);
        let (vx, vy, vz) = (&vertex[kx], &vertex[ky], &vertex[kz]);
        let mut out = [[0.0f32; 4]; 3];
        for l in 0..4 {
            let pz = vz[l] - oz;
            out[0][l] = (vx[l] - ox) - sx * pz;
            out[1][l] = (vy[l] - oy) - sy * pz;
            out[2][l] = pz;
        }
        out
    }

    /// For each of the four lanes of `tris`, false only where [`intersect`](Self::intersect)
    /// misses that triangle (bit `l` of the result for lane `l`), computed without a branch:
    /// the same f32 shear, edge functions and depth test lane for lane, and true wherever an
    /// edge function is exactly 0 (where `intersect` redoes them in f64). A scan runs this
    /// first on blocks of triangles, and `intersect` only where it says true. Unused (zero)
    /// lanes may say true: the caller masks them.
    #[inline(always)]
    pub fn may_hit4(&self, tris: &Vertices4) -> u32 {
        let sz = self.s[2];
        let [a, b, c] = [
            self.shear4(&tris.v[0]),
            self.shear4(&tris.v[1]),
            self.shear4(&tris.v[2]),
        ];
        let mut may = [false; 4];
        #[allow(clippy::needless_range_loop)] // lane loops, written for the vectoriser
        for l in 0..4 {
            let (ax, ay, az) = (a[0][l], a[1][l], a[2][l]);
            let (bx, by, bz) = (b[0][l], b[1][l], b[2][l]);
            let (cx, cy, cz) = (c[0][l], c[1][l], c[2][l]);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let on_an_edge = (u == 0.0) | (v == 0.0) | (w == 0.0);
            let negative = (u < 0.0) | (v < 0.0) | (w < 0.0);
            let positive = (u > 0.0) | (v > 0.0) | (w > 0.0);
            let det = u + v + w;
            let t = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
            let front = (det > 0.0) & (det * self.t_min < t) & (t <= det * self.t_max);
            let back = (det < 0.0) & (det * self.t_min > t) & (t >= det * self.t_max);
            may[l] = on_an_edge | (!(negative & positive) & (front | back));
        }
        may.iter()
            .enumerate()
            .fold(0, |m, (l, &b)| m | (b as u32) << l)
    }
}

/// Four triangles' vertices lane by lane (`v[vertex][axis][lane]`), for the watertight
/// candidate test on four at once ([`WatertightRay::may_hit4`]); unused lanes are zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vertices4 {
    pub v: [[[f32; 4]; 3]; 3],
}

impl Vertices4 {
    /// Packs up to four triangles into lanes 0, 1, …
    pub fn pack(tris: &[Triangle]) -> Vertices4 {
        assert!(tris.len() <= 4, "a Vertices4 holds at most four triangles");
        let mut p = Vertices4::default();
        for (l, t) in tris.iter().enumerate() {
            for (j, vertex) in [t.v0, t.v1, t.v2].into_iter().enumerate() {
                for axis in 0..3 {
                    p.v[j][axis][l] = vertex[axis];
                }
            }
        }
        p
    }

    /// Lane `l` as a triangle.
    #[inline(always)]
    pub fn lane(&self, l: usize) -> Triangle {
        let [a, b, c] = self.v.map(|v| Vec3::new(v[0][l], v[1][l], v[2][l]));
        Triangle::new(a, b, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `may_hit4` is false only where `intersect` misses, and `intersect` through a set-up ray
    /// is `Triangle::intersect_watertight`, on the Möller test's random and edge cases. None of
    /// them needs `may_hit4`'s clause for an edge function of exactly 0 (a redo in f64 that
    /// turns mixed signs into one sign is rare: none in 400,000 rays aimed at random triangles'
    /// vertices); the slivers of the next test do.
    #[test]
    fn the_candidate_test_keeps_every_hit() {
        let cases = crate::triangle::tests::random_and_edge_cases();
        let (mut hits, mut rejected) = (0, 0);
        for (tri, ray) in &cases {
            let w = WatertightRay::new(ray);
            let hit = w.intersect(tri);
            let bits = |h: Option<TriHit>| h.map(|h| [h.t, h.u, h.v].map(f32::to_bits));
            assert_eq!(bits(hit), bits(tri.intersect_watertight(ray)));
            let may_hit = w.may_hit4(&Vertices4::pack(&[*tri])) & 1 != 0;
            assert!(may_hit || hit.is_none(), "{tri:?} {ray:?}");
            assert_eq!(Vertices4::pack(&[*tri]).lane(0), *tri);
            hits += hit.is_some() as usize;
            rejected += !may_hit as usize;
        }
        // Four triangles in one pack answer lane by lane as each alone.
        for group in cases.chunks_exact(4) {
            let tris: Vec<Triangle> = group.iter().map(|(t, _)| *t).collect();
            let w = WatertightRay::new(&group[0].1);
            let alone = tris.iter().enumerate().fold(0, |m, (l, t)| {
                m | (w.may_hit4(&Vertices4::pack(&[*t])) & 1) << l
            });
            assert_eq!(w.may_hit4(&Vertices4::pack(&tris)), alone);
        }
        // Both outcomes are common, and the candidate test rejects most misses.
        assert!(
            hits > 5_000 && rejected > (cases.len() - hits) * 9 / 10,
            "{hits} {rejected}"
        );
    }

    /// Slivers whose third vertex lies within a few ulps to a thousandth of their opposite edge,
    /// that edge crossing the ray: all three edge functions are about 0, one rounds or
    /// underflows to exactly 0 in f32, the f32 signs and depth say miss, and only the redo in
    /// f64 finds the hit. Here `may_hit4` keeps its candidates by its exact-zero clause alone
    /// (the test fails without it), one triangle or four at a time.
    #[test]
    fn slivers_through_the_ray_stay_candidates() {
        // Up to two ulps either way.
        fn nudge(x: f32, r: &mut crate::SplitMix64) -> f32 {
            let ulps = (r.unit() * 5.0) as i32 - 2;
            f32::from_bits(x.to_bits().wrapping_add_signed(ulps))
        }
        let mut rng = crate::SplitMix64::new(6);
        let mut tris = Vec::new();
        for i in 0..30_000 {
            let r = &mut rng;
            let (ax, ay) = (r.unit() * 2.0 - 1.0, r.unit() * 2.0 - 1.0);
            let k = 0.5 + r.unit() * 1.5;
            let near = [1e-3, 1e-6, 0.0][i % 3] * r.unit();
            let (bz, cz) = (1.0 + r.unit(), 1.0 + r.unit());
            tris.push(Triangle::new(
                Vec3::new(ax, ay, 1.0),
                Vec3::new(nudge(-ax * k, r), nudge(-ay * k, r), bz),
                Vec3::new(nudge(ax * near, r), nudge(ay * near, r), cz),
            ));
        }
        let ray = Ray::new(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY);
        let w = WatertightRay::new(&ray);
        let mut hits = 0;
        for four in tris.chunks_exact(4) {
            let may = w.may_hit4(&Vertices4::pack(four));
            for (l, tri) in four.iter().enumerate() {
                let hit = w.intersect(tri);
                assert!(may >> l & 1 != 0 || hit.is_none(), "{tri:?}");
                assert_eq!(w.may_hit4(&Vertices4::pack(&[*tri])) & 1, may >> l & 1);
                hits += hit.is_some() as usize;
            }
        }
        assert!(hits > 1_000, "{hits}");
    }
}
