//! Four triangles tested against one ray at once: the leaf primitive of the wide BVH and the
//! triangle store of the uniform grid.
//!
//! [`Tri4`] is the layout of Embree's `Triangle4`: four triangles side by side (structure of
//! arrays) with the edges precomputed (`v0`, `e1 = v0 - v1`, `e2 = v2 - v0`) and each lane's
//! mesh index alongside, in three cache lines (160 bytes, padded to 192 and aligned to 64). The
//! normal `e2 × e1` is recomputed per test rather than stored: nine lane-wise operations
//! instead of a fourth cache line (stored, it bought 2–3 % on camera rays for 28 % more memory:
//! docs/experiments.md, "each `Tri4`'s four normals stored"). Unused lanes hold the all-zero
//! triangle, whose zero determinant no ray passes, and the id [`NO_PRIM`].
//!
//! [`Tri4::test`] is [`MollerTriangle::intersect`] lane for lane: the same products, sums and
//! comparisons in the same order, no fused multiply-add, so every lane's hit, `t`, `u` and `v`
//! are bit-identical to the scalar test's (the tests below check it on seeded rays). It is
//! written as branch-free loops over `[f32; 4]`, which the compiler turns into SSE
//! instructions on the x86-64 baseline; the wide BVH's AVX2 and AVX-512 kernels read the same
//! layout with the same arithmetic.

use crate::{MollerTriangle, Ray, TriHit, Vec3};

/// Lanes in a [`Tri4`].
pub const LANES: usize = 4;

/// The id of an unused lane.
pub const NO_PRIM: u32 = u32::MAX;

/// Four triangles: `v0[axis][lane]`, `e1`, `e2` likewise, and each lane's mesh index.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Tri4 {
    pub v0: [[f32; LANES]; 3],
    pub e1: [[f32; LANES]; 3],
    pub e2: [[f32; LANES]; 3],
    pub ids: [u32; LANES],
}

const _: () = assert!(std::mem::size_of::<Tri4>() == 192);

impl Default for Tri4 {
    /// Four unused lanes.
    fn default() -> Tri4 {
        Tri4 {
            v0: [[0.0; LANES]; 3],
            e1: [[0.0; LANES]; 3],
            e2: [[0.0; LANES]; 3],
            ids: [NO_PRIM; LANES],
        }
    }
}

impl Tri4 {
    /// Packs up to four `(mesh index, triangle)`; missing lanes stay unused.
    pub fn pack(tris: &[(u32, MollerTriangle)]) -> Tri4 {
        assert!(tris.len() <= LANES, "a Tri4 holds at most four triangles");
        let mut p = Tri4::default();
        for (lane, (id, t)) in tris.iter().enumerate() {
            p.set_lane(lane, *id, t);
        }
        p
    }

    /// Puts triangle `id` (`t`) into `lane`.
    pub fn set_lane(&mut self, lane: usize, id: u32, t: &MollerTriangle) {
        for axis in 0..3 {
            self.v0[axis][lane] = t.v0[axis];
            self.e1[axis][lane] = t.e1[axis];
            self.e2[axis][lane] = t.e2[axis];
        }
        self.ids[lane] = id;
    }

    /// Lane `lane` as a scalar triangle, its normal computed as [`MollerTriangle::new`] does.
    pub fn lane(&self, lane: usize) -> MollerTriangle {
        let at = |v: &[[f32; LANES]; 3]| Vec3::new(v[0][lane], v[1][lane], v[2][lane]);
        let (e1, e2) = (at(&self.e1), at(&self.e2));
        MollerTriangle {
            v0: at(&self.v0),
            e1,
            e2,
            ng: e2.cross(e1),
        }
    }

    /// Möller–Trumbore on all four lanes with the hit window `(ray.t_min, t_max]`: the lanes
    /// that hit, as bits of [`Tri4Hits::mask`], and every lane's unscaled results. The one
    /// division a hit needs is left to [`Tri4Hits::get`], so a caller that ignores some lanes
    /// pays nothing for them.
    #[inline(always)]
    pub fn test(&self, ray: &Ray, t_max: f32) -> Tri4Hits {
        let o = ray.origin();
        let d = ray.dir();
        let t_min = ray.t_min();
        let mut hits = Tri4Hits::default();
        let mut ok = [false; LANES];
        #[allow(clippy::needless_range_loop)] // lane loops, written for the vectoriser
        for l in 0..LANES {
            let cx = self.v0[0][l] - o.x;
            let cy = self.v0[1][l] - o.y;
            let cz = self.v0[2][l] - o.z;
            let (e1x, e1y, e1z) = (self.e1[0][l], self.e1[1][l], self.e1[2][l]);
            let (e2x, e2y, e2z) = (self.e2[0][l], self.e2[1][l], self.e2[2][l]);
            // ng = e2 × e1 and r = c × d, both in glam's order.
            let ngx = e2y * e1z - e1y * e2z;
            let ngy = e2z * e1x - e1z * e2x;
            let ngz = e2x * e1y - e1x * e2y;
            let rx = cy * d.z - d.y * cz;
            let ry = cz * d.x - d.z * cx;
            let rz = cx * d.y - d.x * cy;
            let den = ngx * d.x + ngy * d.y + ngz * d.z;
            // `if den < 0 { -x } else { x }` on the sign bit: exactly the scalar negation.
            let sign = den.to_bits() & 0x8000_0000;
            let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
            let ad = den.abs();
            let u = flip(rx * e2x + ry * e2y + rz * e2z);
            let v = flip(rx * e1x + ry * e1y + rz * e1z);
            let t = flip(ngx * cx + ngy * cy + ngz * cz);
            ok[l] = (den != 0.0)
                & (u >= 0.0)
                & (v >= 0.0)
                & (u + v <= ad)
                & (ad * t_min < t)
                & (t <= ad * t_max);
            hits.t[l] = t;
            hits.u[l] = u;
            hits.v[l] = v;
            hits.abs_den[l] = ad;
        }
        hits.mask = ok
            .iter()
            .enumerate()
            .fold(0, |m, (l, &b)| m | (b as u32) << l);
        hits
    }

    /// The nearest lane that hits within `(ray.t_min, t_max]` (the lowest lane on ties), if
    /// any.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(usize, TriHit)> {
        let hits = self.test(ray, t_max);
        (hits.mask != 0).then(|| hits.nearest(hits.mask))
    }
}

/// What [`Tri4::test`] found: a bit per lane that hits, and every lane's unscaled `t`, `u`,
/// `v` and `|den|`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tri4Hits {
    pub mask: u32,
    t: [f32; LANES],
    u: [f32; LANES],
    v: [f32; LANES],
    abs_den: [f32; LANES],
}

impl Tri4Hits {
    /// Lane `l`'s hit, scaled exactly as the scalar test scales it.
    #[inline(always)]
    pub fn get(&self, l: usize) -> TriHit {
        let inv = 1.0 / self.abs_den[l];
        TriHit {
            t: self.t[l] * inv,
            u: self.u[l] * inv,
            v: self.v[l] * inv,
        }
    }

    /// Of the lanes in `mask` (nonzero), the one with the smallest `t`, the lowest on ties.
    #[inline(always)]
    pub fn nearest(&self, mask: u32) -> (usize, TriHit) {
        let t = std::array::from_fn::<f32, LANES, _>(|l| self.t[l] * (1.0 / self.abs_den[l]));
        let best = nearest_lane(&t, mask);
        (best, self.get(best))
    }
}

/// The lane of `bits` (a nonzero lane mask) with the smallest `t`, the lowest lane on ties: how
/// every four- or eight-lane test picks its hit among lanes.
#[inline(always)]
pub fn nearest_lane(t: &[f32], mut bits: u32) -> usize {
    let mut best = bits.trailing_zeros() as usize;
    bits &= bits - 1;
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if t[i] < t[best] {
            best = i;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Triangle;
    use crate::rng::SplitMix64;

    fn point(rng: &mut SplitMix64, scale: f32) -> Vec3 {
        rng.signed_vec() * scale
    }

    /// Every lane answers exactly as the scalar test, bit for bit, hits and misses, and
    /// `intersect` picks the nearest lane (the first on ties); rays include axis-parallel ones
    /// with both signs of zero, short windows and degenerate triangles.
    #[test]
    fn lanes_are_bit_identical_to_the_scalar_test() {
        let mut rng = SplitMix64::new(0x7411);
        let mut hits = 0;
        for case in 0..20_000 {
            let count = 1 + case % LANES;
            let tris: Vec<MollerTriangle> = (0..count)
                .map(|k| {
                    let v0 = point(&mut rng, 1.0);
                    // Every eighth triangle is degenerate (collinear), which must never hit.
                    let v2 = if (case + k) % 8 == 0 {
                        v0 * 2.0
                    } else {
                        point(&mut rng, 1.0)
                    };
                    MollerTriangle::new(&Triangle::new(v0, point(&mut rng, 1.0), v2))
                })
                .collect();
            let ids: Vec<(u32, MollerTriangle)> = tris
                .iter()
                .enumerate()
                .map(|(i, t)| (i as u32, *t))
                .collect();
            let packed = Tri4::pack(&ids);
            let origin = point(&mut rng, 3.0);
            // Aim near a point of one of the triangles (barycentric weights slightly beyond
            // [0, 1], so edges are crossed from both sides).
            let aim = tris[case % count];
            let target = Triangle::new(aim.v0, aim.v0 - aim.e1, aim.v0 + aim.e2);
            let (a, b) = (rng.unit() * 1.2 - 0.1, rng.unit() * 1.2 - 0.1);
            let mut dir = target.point_at(a, b * (1.0 - a)) - origin;
            if case % 5 == 0 {
                dir[case % 3] = if case % 2 == 0 { 0.0 } else { -0.0 };
            }
            let t_max = [f32::INFINITY, 1.5, 0.5][case % 3];
            let ray = Ray::new(origin, dir, [0.01, 0.0][case % 2], 10.0);
            let lanes = packed.test(&ray, t_max);
            let bits = |h: TriHit| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits());
            let mut scalar: Option<(usize, TriHit)> = None;
            for (l, t) in tris.iter().enumerate() {
                let want = t.intersect(&ray.with_t_max(t_max));
                let have = (lanes.mask >> l & 1 != 0).then(|| lanes.get(l));
                assert_eq!(have.map(bits), want.map(bits), "case {case} lane {l}");
                if let Some(h) = want
                    && scalar.is_none_or(|(_, b)| h.t < b.t)
                {
                    scalar = Some((l, h));
                }
                assert_eq!(packed.lane(l), *t);
                assert_eq!(packed.ids[l], l as u32);
            }
            let nearest = packed.intersect(&ray, t_max);
            assert_eq!(
                nearest.map(|(l, h)| (l, bits(h))),
                scalar.map(|(l, h)| (l, bits(h))),
                "case {case}"
            );
            assert_eq!(lanes.mask >> count, 0, "case {case}: an unused lane hit");
            hits += nearest.is_some() as usize;
        }
        assert!(
            hits > 2_000,
            "only {hits} of 20000 rays hit: the test proves little"
        );
    }

    /// On the scalar test's edge cases (rays through vertices and edges, zero and non-finite
    /// directions, windows ending at the plane, a degenerate triangle), a triangle in lane 0
    /// hits exactly where the scalar test does, and the three unused lanes never hit.
    #[test]
    fn one_lane_answers_the_edge_cases_as_the_scalar_test() {
        let cases = crate::triangle::tests::random_and_edge_cases();
        let mut hits = 0;
        for (tri, ray) in &cases {
            let m = MollerTriangle::new(tri);
            let want = m.intersect(ray);
            let have = Tri4::pack(&[(0, m)]).test(ray, ray.t_max());
            let bits = |h: TriHit| [h.t, h.u, h.v].map(f32::to_bits);
            assert_eq!(have.mask >> 1, 0, "an unused lane hit: {tri:?} {ray:?}");
            assert_eq!(
                (have.mask == 1).then(|| bits(have.get(0))),
                want.map(bits),
                "{tri:?} {ray:?}"
            );
            hits += want.is_some() as usize;
        }
        assert!(hits > 2_000 && hits < cases.len() / 2, "{hits} hits");
    }

    #[test]
    fn unused_lanes_never_hit() {
        let empty = Tri4::default();
        for dir in [Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 1.0, 1.0)] {
            let ray = Ray::new(Vec3::ZERO - dir, dir, 0.0, f32::INFINITY);
            assert_eq!(empty.test(&ray, f32::INFINITY).mask, 0);
            assert!(empty.intersect(&ray, f32::INFINITY).is_none());
        }
    }

    #[test]
    fn the_nearest_lane_is_the_first_on_ties() {
        assert_eq!(nearest_lane(&[3.0, 1.0, 1.0, 2.0], 0b1111), 1);
        assert_eq!(nearest_lane(&[3.0, 1.0, 1.0, 2.0], 0b1101), 2);
        assert_eq!(nearest_lane(&[3.0, 1.0, 1.0, 2.0], 0b1000), 3);
    }
}
