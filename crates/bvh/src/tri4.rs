//! Four triangles tested against one ray at once: the leaf primitive of the wide BVH.
//!
//! Embree's fast BVHs store leaves as `Triangle4`: four triangles in structure-of-arrays form
//! with the edges precomputed and the triangle ids alongside, so one SIMD Möller–Trumbore test
//! answers for all four and a leaf of up to four triangles costs about one scalar test.
//! [`Tri4`] is that layout in three cache lines: `v0`, the edges and the ids (160 bytes, padded
//! to 192 and aligned to 64). The normal `e2 × e1` is recomputed per test rather than stored —
//! nine lane-wise operations instead of a fourth cache line — and a hit's triangle id is read
//! from the lines already loaded, not from a separate array. [`Tri4::intersect`] is
//! [`MollerTriangle::intersect`] lane for lane: the same operations in the same order (no fused
//! multiply-add), so every lane's hit, `t`, `u` and `v` are bit-identical to the scalar test's;
//! the unit tests below check it on seeded rays. Unused lanes hold an all-zero triangle, whose
//! zero determinant no ray can pass, and the id [`NO_PRIM`].

use crate::simd::F4;
use raybench_geom::{MollerTriangle, Ray, TriHit};

/// Marks an unused lane.
pub const NO_PRIM: u32 = u32::MAX;

/// Four triangles, SoA: `v0[axis][lane]`, `e1 = v0 - v1`, `e2 = v2 - v0`, and each lane's
/// mesh index.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Tri4 {
    pub v0: [[f32; 4]; 3],
    pub e1: [[f32; 4]; 3],
    pub e2: [[f32; 4]; 3],
    pub ids: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Tri4>() == 192);

impl Default for Tri4 {
    fn default() -> Tri4 {
        Tri4 {
            v0: [[0.0; 4]; 3],
            e1: [[0.0; 4]; 3],
            e2: [[0.0; 4]; 3],
            ids: [NO_PRIM; 4],
        }
    }
}

/// The lane of `bits` (a nonzero lane mask) with the smallest `t`, the lowest lane on ties:
/// how a packet test picks its hit among lanes.
#[inline(always)]
pub(crate) fn nearest_lane(t: &[f32], mut bits: u32) -> usize {
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

/// The ray splatted across four lanes, made once per ray.
pub(crate) struct Ray4 {
    /// Also the SSE node test's splatted origin.
    pub(crate) origin: [F4; 3],
    dir: [F4; 3],
    t_min: F4,
}

impl Ray4 {
    pub(crate) fn new(ray: &Ray) -> Ray4 {
        Ray4 {
            origin: ray.origin().to_array().map(F4::splat),
            dir: ray.dir().to_array().map(F4::splat),
            t_min: F4::splat(ray.t_min()),
        }
    }
}

/// `a · b` in glam's order, `(ax bx + ay by) + az bz`, lane-wise.
#[inline(always)]
fn dot(a: &[F4; 3], b: &[F4; 3]) -> F4 {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

/// `a × b` in glam's order, lane-wise.
#[inline(always)]
fn cross(a: &[F4; 3], b: &[F4; 3]) -> [F4; 3] {
    [
        a[1].mul(b[2]).sub(b[1].mul(a[2])),
        a[2].mul(b[0]).sub(b[2].mul(a[0])),
        a[0].mul(b[1]).sub(b[0].mul(a[1])),
    ]
}

#[inline(always)]
fn load3(v: &[[f32; 4]; 3]) -> [F4; 3] {
    [F4::load(&v[0]), F4::load(&v[1]), F4::load(&v[2])]
}

impl Tri4 {
    /// Packs up to four `(mesh index, triangle)`; missing lanes stay empty (never hit).
    pub fn pack(tris: &[(u32, MollerTriangle)]) -> Tri4 {
        assert!(tris.len() <= 4, "a Tri4 holds at most four triangles");
        let mut p = Tri4::default();
        for (lane, (id, t)) in tris.iter().enumerate() {
            p.set_lane(lane, *id, t);
        }
        p
    }

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
        let at = |v: &[[f32; 4]; 3]| raybench_geom::Vec3::new(v[0][lane], v[1][lane], v[2][lane]);
        let (e1, e2) = (at(&self.e1), at(&self.e2));
        MollerTriangle {
            v0: at(&self.v0),
            e1,
            e2,
            ng: e2.cross(e1),
        }
    }

    /// All four lanes against `ray` with the hit window `(t_min, t_max]`: the nearest lane hit
    /// (lowest lane on ties), if any.
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &Ray4, t_max: f32) -> Option<(usize, TriHit)> {
        let c = [
            F4::load(&self.v0[0]).sub(ray.origin[0]),
            F4::load(&self.v0[1]).sub(ray.origin[1]),
            F4::load(&self.v0[2]).sub(ray.origin[2]),
        ];
        let r = cross(&c, &ray.dir);
        let (e1, e2) = (load3(&self.e1), load3(&self.e2));
        let ng = cross(&e2, &e1);
        let den = dot(&ng, &ray.dir);
        let abs_den = den.abs();
        let u = dot(&r, &e2).flip_by_sign(den);
        let v = dot(&r, &e1).flip_by_sign(den);
        let zero = F4::splat(0.0);
        let inside = den
            .ne(zero)
            .and(u.ge(zero))
            .and(v.ge(zero))
            .and(u.add(v).le(abs_den));
        if inside.bits() == 0 {
            return None;
        }
        let t = dot(&ng, &c).flip_by_sign(den);
        let in_window = abs_den
            .mul(ray.t_min)
            .lt(t)
            .and(t.le(abs_den.mul(F4::splat(t_max))));
        let mask = inside.and(in_window).bits();
        if mask == 0 {
            return None;
        }
        let inv = F4::splat(1.0).div(abs_den);
        let (t, u, v) = (
            t.mul(inv).to_array(),
            u.mul(inv).to_array(),
            v.mul(inv).to_array(),
        );
        let best = nearest_lane(&t, mask);
        Some((
            best,
            TriHit {
                t: t[best],
                u: u[best],
                v: v[best],
            },
        ))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use raybench_geom::{Triangle, Vec3};

    /// A small deterministic generator (SplitMix64), so the test needs no dependency.
    pub(crate) struct Rng(pub u64);
    impl Rng {
        pub(crate) fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
        pub(crate) fn point(&mut self, scale: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * (2.0 * scale) - scale
        }
    }

    /// Every lane answers exactly as the scalar test, bit for bit, and the packet's answer is
    /// the nearest lane's; rays include axis-parallel ones and short windows.
    #[test]
    fn lanes_are_bit_identical_to_the_scalar_test() {
        let mut rng = Rng(0x7411);
        let mut hits = 0;
        for case in 0..20_000 {
            let count = 1 + case % 4;
            let tris: Vec<MollerTriangle> = (0..count)
                .map(|k| {
                    let v0 = rng.point(1.0);
                    // Every eighth triangle is degenerate (collinear), which must never hit.
                    let v2 = if (case + k) % 8 == 0 {
                        v0 * 2.0
                    } else {
                        rng.point(1.0)
                    };
                    MollerTriangle::new(&Triangle::new(v0, rng.point(1.0), v2))
                })
                .collect();
            let ids: Vec<(u32, MollerTriangle)> = tris
                .iter()
                .enumerate()
                .map(|(i, t)| (i as u32, *t))
                .collect();
            let packet = Tri4::pack(&ids);
            let origin = rng.point(3.0);
            // Aim near a point of one of the triangles (barycentric weights slightly beyond
            // [0, 1], so edges are crossed from both sides).
            let t = Triangle::new(
                tris[case % count].v0,
                tris[case % count].v0 - tris[case % count].e1,
                tris[case % count].v0 + tris[case % count].e2,
            );
            let (a, b) = (rng.next() * 1.2 - 0.1, rng.next() * 1.2 - 0.1);
            let mut dir = t.point_at(a, b * (1.0 - a)) - origin;
            if case % 5 == 0 {
                dir[case % 3] = if case % 2 == 0 { 0.0 } else { -0.0 };
            }
            let t_max = if case % 7 == 0 { 1.5 } else { f32::INFINITY };
            let ray = Ray::new(origin, dir, 0.01, t_max);
            let scalar = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| t.intersect(&ray).map(|h| (i, h)))
                .fold(None::<(usize, TriHit)>, |best, (i, h)| match best {
                    Some((_, b)) if b.t <= h.t => best,
                    _ => Some((i, h)),
                });
            let simd = packet.intersect(&Ray4::new(&ray), ray.t_max());
            let bits = |x: Option<(usize, TriHit)>| {
                x.map(|(i, h)| (i, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
            };
            assert_eq!(bits(simd), bits(scalar), "case {case}: {ray:?}");
            hits += simd.is_some() as usize;
            for (lane, tri) in tris.iter().enumerate() {
                assert_eq!(packet.lane(lane), *tri);
                assert_eq!(packet.ids[lane], lane as u32);
            }
        }
        assert!(
            hits > 2_000,
            "only {hits} of 20000 rays hit: the test proves little"
        );
    }

    #[test]
    fn empty_lanes_never_hit() {
        let packet = Tri4::pack(&[]);
        for dir in [Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 1.0, 1.0)] {
            let ray = Ray::new(Vec3::ZERO - dir, dir, 0.0, f32::INFINITY);
            assert!(packet.intersect(&Ray4::new(&ray), f32::INFINITY).is_none());
        }
    }
}
