//! Packets of eight coherent rays, one ray per AVX2 lane: the packet pieces of
//! [`packet`](crate::packet) for CPUs without AVX-512F, which walk each block of sixteen rays
//! as two packets of eight (its low and high halves). The same layout ([`RayBlock`]), the same
//! loading ([`load`]: inverse directions divided when loaded), the same Möller–Trumbore test
//! lane for lane ([`Best8::test_tri4`]), the same split by octant ([`octant_groups`]).
//! AVX2 has sixteen vector registers and no mask registers: a set of lanes is a byte, turned
//! into a vector mask where a blend needs one ([`lanes_mask`]).
//!
//! Exactness: each lane computes what the single-ray Möller–Trumbore test computes for its ray,
//! operation for operation (the products and sums of [`Tri4::test`] in the same order, no
//! fused multiply-add), so each ray's hit, `t`, `u` and `v` are bit for bit the single-ray
//! test's and the sixteen-lane packet's. Only the order in which a walk meets triangles may
//! differ from its single-ray walk, so on an exact tie the reported triangle may be the other.
//!
//! The intrinsics are reached only through [`Avx2Packets`], which exists only after runtime
//! detection saw AVX2; the rest of the crate stays free of `unsafe`.
#![allow(unsafe_code)]

use crate::packet::RayBlock;
use crate::{NO_PRIM, Tri4, TriHit};
use std::arch::x86_64::*;

/// Rays in a packet: one per AVX2 lane, half a [`RayBlock`].
pub const LANES: usize = 8;

/// Proof that this CPU runs AVX2 and POPCNT (the only way to reach the 8-lane packet code;
/// the walks count lanes with POPCNT, which every AVX2 CPU has).
#[derive(Clone, Copy, Debug)]
pub struct Avx2Packets(());

impl Avx2Packets {
    pub fn detect() -> Option<Avx2Packets> {
        let avx2 = std::arch::is_x86_feature_detected!("avx2");
        let popcnt = std::arch::is_x86_feature_detected!("popcnt");
        (avx2 && popcnt).then_some(Avx2Packets(()))
    }
}

/// Up to eight rays in structure-of-arrays form.
#[derive(Debug)]
pub struct Packet8 {
    pub origin: [__m256; 3],
    pub dir: [__m256; 3],
    pub inv: [__m256; 3],
    pub t_min: __m256,
}

/// Each lane's closest hit so far.
#[derive(Debug)]
pub struct Best8 {
    pub t: __m256,
    pub u: __m256,
    pub v: __m256,
    pub prim: __m256i,
}

/// Half `half` (0: rays 0–7, 1: rays 8–15) of a block loaded into a packet, with its
/// closest-hit windows' far ends as the best hits so far.
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
pub fn load(block: &RayBlock, half: usize) -> (Packet8, Best8) {
    let rows = block.rows();
    // SAFETY: each row is 16 initialised f32s starting 64-byte aligned, so eight from lane
    // `8 * half` (half is 0 or 1, checked by the slice) are 32-byte aligned.
    let load = |row: usize| unsafe { _mm256_load_ps(rows[row][LANES * half..][..LANES].as_ptr()) };
    let dir = [load(3), load(4), load(5)];
    // `1 / d` correctly rounded, as `Ray::new` computes `inv_dir` (`±inf` for `±0`).
    let one = _mm256_set1_ps(1.0);
    let packet = Packet8 {
        origin: [load(0), load(1), load(2)],
        inv: dir.map(|d| _mm256_div_ps(one, d)),
        dir,
        t_min: load(6),
    };
    let best = Best8 {
        t: load(7),
        u: _mm256_setzero_ps(),
        v: _mm256_setzero_ps(),
        prim: _mm256_set1_epi32(NO_PRIM as i32),
    };
    (packet, best)
}

/// The lanes of the first `len` rays (at most eight), split by direction octant: calls
/// `walk(lanes, octant)` once per octant present, bit `a` of `octant` set when axis `a` points
/// down (`-0` too: its inverse is -inf).
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
pub fn octant_groups(p: &Packet8, len: usize, mut walk: impl FnMut(u8, u8)) {
    let zero = _mm256_setzero_ps();
    let down = p
        .inv
        .map(|inv| _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(inv, zero)) as u8);
    let mut left: u8 = if len >= LANES {
        u8::MAX
    } else {
        (1 << len) - 1
    };
    while left != 0 {
        let lane = left.trailing_zeros();
        let octant = (0..3).fold(0u8, |o, a| o | ((down[a] >> lane) & 1) << a);
        let lanes = (0..3).fold(left, |m, a| {
            m & if octant >> a & 1 == 1 {
                down[a]
            } else {
                !down[a]
            }
        });
        walk(lanes, octant);
        left &= !lanes;
    }
}

/// The vector mask of the lanes in `lanes` (all bits set in those lanes, clear elsewhere).
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
#[inline]
pub fn lanes_mask(lanes: u8) -> __m256 {
    let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let set = _mm256_and_si256(_mm256_set1_epi32(i32::from(lanes)), bits);
    _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, bits))
}

/// The least of `v` over `lanes` (not empty).
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
#[inline]
pub fn reduce_min(lanes: u8, v: __m256) -> f32 {
    let v = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), v, lanes_mask(lanes));
    let m = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
    let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
    _mm_cvtss_f32(_mm_min_ss(m, _mm_movehdup_ps(m)))
}

/// The greatest of `v` over `lanes` (not empty).
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
#[inline]
pub fn reduce_max(lanes: u8, v: __m256) -> f32 {
    let v = _mm256_blendv_ps(_mm256_set1_ps(f32::NEG_INFINITY), v, lanes_mask(lanes));
    let m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
    let m = _mm_max_ps(m, _mm_movehl_ps(m, m));
    _mm_cvtss_f32(_mm_max_ss(m, _mm_movehdup_ps(m)))
}

/// The lanes set in `mask` (a compare's result), as a byte.
///
/// # Safety
///
/// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
#[target_feature(enable = "avx2")]
#[inline]
pub fn bits(mask: __m256) -> u8 {
    _mm256_movemask_ps(mask) as u8
}

impl Best8 {
    /// Each lane's hit as the single-ray walk reports it: the triangle's id ([`NO_PRIM`] for
    /// none) and the hit.
    ///
    /// # Safety
    ///
    /// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
    #[target_feature(enable = "avx2")]
    pub fn hits(&self) -> [(u32, TriHit); LANES] {
        let mut t = [0.0f32; LANES];
        let mut u = [0.0f32; LANES];
        let mut v = [0.0f32; LANES];
        let mut prim = [0u32; LANES];
        // SAFETY: each destination is 8 writable 4-byte values; `storeu` has no alignment
        // requirement.
        unsafe {
            _mm256_storeu_ps(t.as_mut_ptr(), self.t);
            _mm256_storeu_ps(u.as_mut_ptr(), self.u);
            _mm256_storeu_ps(v.as_mut_ptr(), self.v);
            _mm256_storeu_si256(prim.as_mut_ptr().cast(), self.prim);
        }
        std::array::from_fn(|l| {
            let hit = TriHit {
                t: t[l],
                u: u[l],
                v: v[l],
            };
            (prim[l], hit)
        })
    }

    /// The lanes whose best so far is a hit.
    ///
    /// # Safety
    ///
    /// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub fn hit_lanes(&self) -> u8 {
        let none = _mm256_cmpeq_epi32(self.prim, _mm256_set1_epi32(NO_PRIM as i32));
        !bits(_mm256_castsi256_ps(none))
    }

    /// Every triangle of `tri4` against the `active` lanes; a lane's hit replaces its best
    /// when `t_min < t <= best`, triangle after triangle in slot order. With many lanes active,
    /// one triangle an eight-lane pass; with few ([`PAIRED_RAYS`]), the (triangle, ray) pairs
    /// in one pass instead of four passes mostly idle. Both answer alike, bit for bit.
    ///
    /// # Safety
    ///
    /// AVX2 must be available: call it from code reached through an [`Avx2Packets`].
    #[target_feature(enable = "avx2")]
    pub fn test_tri4(&mut self, tri4: &Tri4, p: &Packet8, active: u8) {
        let ng4 = crate::packet::normals(tri4);
        if active.count_ones() <= PAIRED_RAYS {
            self.pairs(tri4, &ng4, p, active);
        } else {
            self.each_triangle(tri4, &ng4, p, active);
        }
    }

    /// Each triangle of `tri4` (normals `ng4`) against the `active` lanes, one an eight-lane
    /// pass.
    #[target_feature(enable = "avx2")]
    fn each_triangle(&mut self, tri4: &Tri4, ng4: &[[f32; 4]; 3], p: &Packet8, active: u8) {
        for lane in 0..4 {
            let id = tri4.ids[lane];
            if id == NO_PRIM {
                break;
            }
            let at = |v: &[[f32; 4]; 3]| [0, 1, 2].map(|a| _mm256_set1_ps(v[a][lane]));
            let tri = [at(&tri4.v0), at(&tri4.e1), at(&tri4.e2), at(ng4)];
            let ray = (&p.origin, &p.dir, p.t_min, self.t);
            let (hit, [t, u, v, abs_den]) = moller(&tri, ray, active);
            if hit == 0 {
                continue;
            }
            let m = lanes_mask(hit);
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), abs_den);
            self.t = _mm256_blendv_ps(self.t, _mm256_mul_ps(t, inv), m);
            self.u = _mm256_blendv_ps(self.u, _mm256_mul_ps(u, inv), m);
            self.v = _mm256_blendv_ps(self.v, _mm256_mul_ps(v, inv), m);
            let id = _mm256_castsi256_ps(_mm256_set1_epi32(id as i32));
            let prim = _mm256_blendv_ps(_mm256_castsi256_ps(self.prim), id, m);
            self.prim = _mm256_castps_si256(prim);
        }
    }
}

/// Active rays up to which [`Best8::test_tri4`] tests (triangle, ray) pairs: two rays against
/// the four triangles fill the eight lanes of one pass.
const PAIRED_RAYS: u32 = 2;

impl Best8 {
    /// [`Best8::test_tri4`] for one or two `active` lanes: each pair (triangle `k`, ray `j`) in
    /// SIMD lane `4 j + k` of one pass, with the operations of the one-triangle pass, so each
    /// pair's edge tests, `t`, `u` and `v` have its bits. The pass screens with each ray's best
    /// before the `Tri4`; the pairs left are then taken in the one-triangle passes' order (a
    /// ray's triangles in slot order) against the best as those passes would leave it, in
    /// scalar: the same IEEE operations, so the same answers, ties included.
    #[target_feature(enable = "avx2")]
    fn pairs(&mut self, tri4: &Tri4, ng4: &[[f32; 4]; 3], p: &Packet8, active: u8) {
        if active == 0 {
            return;
        }
        let first = active.trailing_zeros() as i32;
        let rest = active & (active - 1);
        let second = if rest == 0 {
            first
        } else {
            rest.trailing_zeros() as i32
        };
        let which = _mm256_setr_epi32(first, first, first, first, second, second, second, second);
        let of = |v: __m256| _mm256_permutevar8x32_ps(v, which);
        let (origin, dir) = (p.origin.map(of), p.dir.map(of));
        let four = |v: &[[f32; 4]; 3]| {
            [0, 1, 2].map(|a| {
                // SAFETY: each row is four initialised f32s; `loadu` has no alignment
                // requirement.
                let x = unsafe { _mm_loadu_ps(v[a].as_ptr()) };
                _mm256_set_m128(x, x)
            })
        };
        let tri = [four(&tri4.v0), four(&tri4.e1), four(&tri4.e2), four(ng4)];
        let slots = tri4.ids.iter().take_while(|&&id| id != NO_PRIM).count();
        let triangles = ((1u32 << slots) - 1) * 0x11;
        let pairs = (if rest == 0 { 0x0F } else { 0xFF } & triangles) as u8;
        let ray = (&origin, &dir, of(p.t_min), of(self.t));
        let (mut hit, quad) = moller(&tri, ray, pairs);
        if hit == 0 {
            return;
        }
        let mut raw = [[0f32; LANES]; 4];
        let mut best = [0f32; LANES];
        // SAFETY: each destination is 8 writable f32s; `storeu` has no alignment requirement.
        unsafe {
            for (row, x) in raw.iter_mut().zip(quad) {
                _mm256_storeu_ps(row.as_mut_ptr(), x);
            }
            _mm256_storeu_ps(best.as_mut_ptr(), self.t);
        }
        let [t, u, v, abs_den] = raw;
        while hit != 0 {
            let pair = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            let l = if pair < 4 { first } else { second } as usize;
            if t[pair] <= abs_den[pair] * best[l] {
                let inv = 1.0 / abs_den[pair];
                best[l] = t[pair] * inv;
                let m = lanes_mask(1 << l);
                self.t = _mm256_blendv_ps(self.t, _mm256_set1_ps(best[l]), m);
                self.u = _mm256_blendv_ps(self.u, _mm256_set1_ps(u[pair] * inv), m);
                self.v = _mm256_blendv_ps(self.v, _mm256_set1_ps(v[pair] * inv), m);
                let id = _mm256_castsi256_ps(_mm256_set1_epi32(tri4.ids[pair % 4] as i32));
                let prim = _mm256_blendv_ps(_mm256_castsi256_ps(self.prim), id, m);
                self.prim = _mm256_castps_si256(prim);
            }
        }
    }
}

/// The Möller–Trumbore test of [`Tri4::test`], lane for lane (the sixteen-lane packet's
/// `moller` on eight lanes): triangles `tri` (`v0`, `e1`, `e2` and the normal `e2 × e1`, per
/// axis) against rays `(origin, dir, t_min, best)` in the lanes `lanes`. Returns the lanes that
/// hit with `t_min < t <= best`, and `t`, `u`, `v` (each still times `|den|`) and `|den|`.
#[target_feature(enable = "avx2")]
#[inline]
fn moller(
    tri: &[[__m256; 3]; 4],
    (origin, dir, t_min, best): (&[__m256; 3], &[__m256; 3], __m256, __m256),
    lanes: u8,
) -> (u8, [__m256; 4]) {
    let [v0, e1, e2, ng] = tri;
    let zero = _mm256_setzero_ps();
    let c = [0, 1, 2].map(|a| _mm256_sub_ps(v0[a], origin[a]));
    let rr = cross(&c, dir);
    let den = dot(ng, dir);
    let sign = _mm256_and_ps(den, _mm256_set1_ps(-0.0));
    let abs_den = _mm256_xor_ps(den, sign);
    let u = _mm256_xor_ps(dot(&rr, e2), sign);
    let v = _mm256_xor_ps(dot(&rr, e1), sign);
    let mut ok = _mm256_cmp_ps::<_CMP_NEQ_UQ>(den, zero);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GE_OQ>(u, zero));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GE_OQ>(v, zero));
    ok = _mm256_and_ps(
        ok,
        _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_add_ps(u, v), abs_den),
    );
    if bits(ok) & lanes == 0 {
        return (0, [zero; 4]);
    }
    let t = _mm256_xor_ps(dot(ng, &c), sign);
    ok = _mm256_and_ps(
        ok,
        _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_mul_ps(abs_den, t_min), t),
    );
    ok = _mm256_and_ps(
        ok,
        _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_mul_ps(abs_den, best)),
    );
    (bits(ok) & lanes, [t, u, v, abs_den])
}

/// `a × b` lane-wise in glam's order, as [`Tri4::test`].
#[target_feature(enable = "avx2")]
#[inline]
fn cross(a: &[__m256; 3], b: &[__m256; 3]) -> [__m256; 3] {
    [
        _mm256_sub_ps(_mm256_mul_ps(a[1], b[2]), _mm256_mul_ps(b[1], a[2])),
        _mm256_sub_ps(_mm256_mul_ps(a[2], b[0]), _mm256_mul_ps(b[2], a[0])),
        _mm256_sub_ps(_mm256_mul_ps(a[0], b[1]), _mm256_mul_ps(b[0], a[1])),
    ]
}

/// `a · b` lane-wise in glam's order, `(ax bx + ay by) + az bz`.
#[target_feature(enable = "avx2")]
#[inline]
fn dot(a: &[__m256; 3], b: &[__m256; 3]) -> __m256 {
    _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
        _mm256_mul_ps(a[2], b[2]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packet::{PACKET, RayPackets};
    use crate::rng::SplitMix64;
    use crate::{MollerTriangle, Ray, Triangle, Vec3};

    /// Each lane of both halves of a block ends with the single-ray test's answer, bit for bit:
    /// its triangles met one after another (each alone in a `Tri4`, so each is tested against
    /// the best the earlier ones left), over random `Tri4`s of one to four triangles, exact
    /// ties (a triangle repeated under another id), windows that earlier hits shrink, and
    /// active sets of every size (so both the paired and the one-triangle passes); the inverse
    /// directions are `Ray::inv_dir`'s.
    #[test]
    fn eight_lanes_answer_as_the_single_ray_test() {
        if Avx2Packets::detect().is_none() {
            eprintln!("no AVX2 on this CPU: no eight-lane packet is ever tested here");
            return;
        }
        let mut rng = SplitMix64::new(8);
        let (mut checked, mut hits, mut paired_hits) = (0, 0, 0);
        for case in 0..400 {
            let near = |rng: &mut SplitMix64| rng.point_in(Vec3::splat(-1.0), Vec3::splat(1.0));
            let groups: Vec<Vec<(u32, MollerTriangle)>> = (0..3)
                .map(|k| {
                    let count = 1 + (case + k) % 4;
                    let mut tris: Vec<(u32, MollerTriangle)> = (0..count)
                        .map(|i| {
                            let t = Triangle::new(near(&mut rng), near(&mut rng), near(&mut rng));
                            ((10 * k + i) as u32, MollerTriangle::new(&t))
                        })
                        .collect();
                    if count > 1 && case % 3 == 0 {
                        tris[count - 1].1 = tris[0].1;
                    }
                    tris
                })
                .collect();
            let tri4s: Vec<Tri4> = groups.iter().map(|g| Tri4::pack(g)).collect();
            let rays: Vec<Ray> = (0..PACKET)
                .map(|lane| {
                    let origin = near(&mut rng) * 0.3 + Vec3::new(0.0, 0.0, 4.0);
                    let mut dir = near(&mut rng) - origin;
                    if lane % 5 == 0 {
                        dir.x = if lane % 2 == 0 { 0.0 } else { -0.0 };
                    }
                    Ray::new(origin, dir, 0.0, rng.range(0.5, 1.2))
                })
                .collect();
            let packets = RayPackets::new(&rays);
            let block = &packets.range(0, PACKET).expect("one block")[0];
            for half in 0..2 {
                let active = (rng.next_u64() as u8) >> (case % 8);
                // SAFETY: AVX2 was detected above.
                let got = unsafe {
                    let (p, mut best) = load(block, half);
                    let mut inv = [[0.0f32; LANES]; 3];
                    for (row, v) in inv.iter_mut().zip(p.inv) {
                        _mm256_storeu_ps(row.as_mut_ptr(), v);
                    }
                    for (lane, ray) in rays[LANES * half..][..LANES].iter().enumerate() {
                        let want = ray.inv_dir().to_array().map(f32::to_bits);
                        assert_eq!([0, 1, 2].map(|a| inv[a][lane].to_bits()), want);
                    }
                    for tri4 in &tri4s {
                        best.test_tri4(tri4, &p, active);
                    }
                    best.hits()
                };
                for (lane, &(prim, h)) in got.iter().enumerate() {
                    let ray = &rays[LANES * half + lane];
                    let mut want = (NO_PRIM, [ray.t_max(), 0.0, 0.0]);
                    if active >> lane & 1 == 1 {
                        for &(id, tri) in groups.iter().flatten() {
                            if let Some((_, h)) = Tri4::pack(&[(id, tri)]).intersect(ray, want.1[0])
                            {
                                want = (id, [h.t, h.u, h.v]);
                            }
                        }
                    }
                    let bits = |x: [f32; 3]| x.map(f32::to_bits);
                    assert_eq!(
                        (prim, bits([h.t, h.u, h.v])),
                        (want.0, bits(want.1)),
                        "case {case}, half {half}, lane {lane}, active {active:08b}"
                    );
                    checked += 1;
                    hits += usize::from(prim != NO_PRIM);
                    if active.count_ones() <= PAIRED_RAYS {
                        paired_hits += usize::from(prim != NO_PRIM);
                    }
                }
            }
        }
        // Enough hits for the comparison to mean something.
        assert!(
            checked == 400 * PACKET && hits > 200 && paired_hits > 30,
            "{hits} hits, {paired_hits} by the paired test"
        );
    }

    /// The lane reductions and masks agree with scalar folds over the lanes they name.
    #[test]
    fn reductions_take_only_the_named_lanes() {
        if Avx2Packets::detect().is_none() {
            eprintln!("no AVX2 on this CPU: nothing to reduce");
            return;
        }
        let mut rng = SplitMix64::new(9);
        for _ in 0..2_000 {
            let x: [f32; LANES] = std::array::from_fn(|_| rng.range(-5.0, 5.0));
            let lanes = (rng.next_u64() as u8).max(1);
            let named = (0..LANES).filter(|l| lanes >> l & 1 == 1).map(|l| x[l]);
            let (lo, hi) = (
                named.clone().fold(f32::INFINITY, f32::min),
                named.fold(f32::NEG_INFINITY, f32::max),
            );
            // SAFETY: AVX2 was detected above; `x` holds eight f32s.
            unsafe {
                let v = _mm256_loadu_ps(x.as_ptr());
                assert_eq!((reduce_min(lanes, v), reduce_max(lanes, v)), (lo, hi));
                assert_eq!(bits(lanes_mask(lanes)), lanes);
            }
        }
    }
}
