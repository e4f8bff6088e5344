//! Four triangles side by side (structure of arrays) and the Möller–Trumbore test on all four
//! at once.
//!
//! The grid stores its triangles in packets of four in Embree's precomputed layout (`v0`,
//! `e1 = v0 - v1`, `e2 = v2 - v0`, `Ng = e2 × e1`), the idea of Embree's `Triangle4`, in the
//! order cells first reference them: a cell's references then mostly fall into a few
//! packets, and each packet is tested with the lanes the cell references (and the ray has not
//! tested yet) active — one 4-wide test instead of up to four scalar ones, with no per-cell
//! copy of a triangle.
//!
//! The lane arithmetic is [`raybench_geom::MollerTriangle::intersect`]'s, operation for
//! operation (the same products, sums and comparisons in the same order, no fused
//! multiply-add), so every lane answers bit for bit as the scalar test; a test below checks it.
//! Written as branch-free loops over `[f32; 4]`, which the compiler turns into SSE
//! instructions.

use raybench_geom::{MollerTriangle, Ray, TriHit};

/// Lanes per packet.
pub(crate) const LANES: usize = 4;

/// Marks an empty lane (its geometry is all zeros, which no ray hits: `Ng = 0`).
pub(crate) const EMPTY: u32 = u32::MAX;

/// Four triangles: per field, per axis, per lane; and each lane's mesh triangle id.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Packet {
    pub v0: [[f32; LANES]; 3],
    pub e1: [[f32; LANES]; 3],
    pub e2: [[f32; LANES]; 3],
    pub ng: [[f32; LANES]; 3],
    pub ids: [u32; LANES],
}

impl Packet {
    /// A packet of empty lanes.
    pub(crate) fn empty() -> Packet {
        Packet {
            ids: [EMPTY; LANES],
            ..Packet::default()
        }
    }

    /// Puts triangle `id` (`t`) into lane `l`.
    pub(crate) fn set(&mut self, l: usize, id: u32, t: &MollerTriangle) {
        for a in 0..3 {
            self.v0[a][l] = t.v0[a];
            self.e1[a][l] = t.e1[a];
            self.e2[a][l] = t.e2[a];
            self.ng[a][l] = t.ng[a];
        }
        self.ids[l] = id;
    }

    /// The triangle in lane `l`.
    pub(crate) fn get(&self, l: usize) -> MollerTriangle {
        let f = |x: &[[f32; LANES]; 3]| raybench_geom::Vec3::new(x[0][l], x[1][l], x[2][l]);
        MollerTriangle {
            v0: f(&self.v0),
            e1: f(&self.e1),
            e2: f(&self.e2),
            ng: f(&self.ng),
        }
    }

    /// Möller–Trumbore on all four lanes, with the hit interval `(ray.t_min, t_max]`: the
    /// lanes that hit, as bits of [`Hits::mask`], and their unscaled results. Branch-free, so
    /// the lanes run side by side; the one division per hit is left to [`Hits::get`].
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &Ray, t_max: f32) -> Hits {
        let o = ray.origin();
        let d = ray.dir();
        let t_min = ray.t_min();
        let mut hits = Hits::default();
        let mut ok = [false; LANES];
        #[allow(clippy::needless_range_loop)] // lane loops, written for the vectoriser
        for l in 0..LANES {
            let cx = self.v0[0][l] - o.x;
            let cy = self.v0[1][l] - o.y;
            let cz = self.v0[2][l] - o.z;
            // r = c × d (glam's order), den = Ng · d
            let rx = cy * d.z - d.y * cz;
            let ry = cz * d.x - d.z * cx;
            let rz = cx * d.y - d.x * cy;
            let den = self.ng[0][l] * d.x + self.ng[1][l] * d.y + self.ng[2][l] * d.z;
            // `if den < 0 { -x } else { x }` on the sign bit: exactly the scalar negation.
            let sign = den.to_bits() & 0x8000_0000;
            let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
            let ad = den.abs();
            let u = flip(rx * self.e2[0][l] + ry * self.e2[1][l] + rz * self.e2[2][l]);
            let v = flip(rx * self.e1[0][l] + ry * self.e1[1][l] + rz * self.e1[2][l]);
            let t = flip(self.ng[0][l] * cx + self.ng[1][l] * cy + self.ng[2][l] * cz);
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
            .fold(0, |m, (l, &b)| m | (b as u8) << l);
        hits
    }
}

/// What [`Packet::intersect`] found: a bit per hit lane and every lane's unscaled `t`, `u`, `v`
/// and `|den|`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hits {
    pub mask: u8,
    t: [f32; LANES],
    u: [f32; LANES],
    v: [f32; LANES],
    abs_den: [f32; LANES],
}

impl Hits {
    /// Lane `l`'s hit, scaled exactly as the scalar test scales it.
    #[inline(always)]
    pub(crate) fn get(&self, l: usize) -> TriHit {
        let inv = 1.0 / self.abs_den[l];
        TriHit {
            t: self.t[l] * inv,
            u: self.u[l] * inv,
            v: self.v[l] * inv,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::{Triangle, Vec3};

    struct Rng(u64);
    impl Rng {
        fn f(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn v(&mut self) -> Vec3 {
            Vec3::new(self.f(), self.f(), self.f())
        }
    }

    /// Every lane answers bit for bit as the scalar test, hits and misses, including rays
    /// through edges and vertices and with both signs of zero in the direction.
    #[test]
    fn lanes_match_the_scalar_test_bit_for_bit() {
        let mut rng = Rng(0x5eed_4444);
        let mut hits = 0;
        for case in 0..20_000 {
            let tris: Vec<Triangle> = (0..LANES)
                .map(|_| {
                    let c = rng.v();
                    Triangle::new(
                        c + (rng.v() - 0.5) * 0.5,
                        c + (rng.v() - 0.5) * 0.5,
                        c + (rng.v() - 0.5) * 0.5,
                    )
                })
                .collect();
            let mut p = Packet::empty();
            for (l, t) in tris.iter().enumerate() {
                p.set(l, l as u32, &MollerTriangle::new(t));
            }
            let target = match case % 3 {
                0 => tris[case % LANES].point_at(rng.f() * 0.5, rng.f() * 0.5),
                1 => tris[case % LANES].v1,
                _ => (tris[case % LANES].v0 + tris[case % LANES].v2) * 0.5,
            };
            let origin = rng.v() * 4.0 - 2.0;
            let mut dir = target - origin;
            if case % 7 == 0 {
                dir.x = if case % 2 == 0 { 0.0 } else { -0.0 };
            }
            let t_max = [f32::INFINITY, 1.0, 0.5][case % 3];
            let ray = Ray::new(origin, dir, [0.0, 0.1][case % 2], 10.0);
            let got = p.intersect(&ray, t_max);
            for (l, t) in tris.iter().enumerate() {
                let want = MollerTriangle::new(t)
                    .intersect(&ray.with_t_max(t_max))
                    .map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
                let have = (got.mask >> l & 1 != 0).then(|| {
                    let h = got.get(l);
                    (h.t.to_bits(), h.u.to_bits(), h.v.to_bits())
                });
                assert_eq!(have, want, "case {case} lane {l}");
                hits += want.is_some() as usize;
            }
            assert_eq!(p.get(1), MollerTriangle::new(&tris[1]));
        }
        assert!(hits > 5000, "{hits}");
        // Empty lanes never hit.
        let p = Packet::empty();
        let ray = Ray::infinite(Vec3::new(0.0, 0.0, -1.0), Vec3::Z);
        assert_eq!(p.intersect(&ray, f32::INFINITY).mask, 0);
    }
}
