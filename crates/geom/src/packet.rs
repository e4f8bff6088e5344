//! Packets of sixteen coherent rays, one ray per AVX-512 lane: the pieces every packet walk
//! shares, whatever structure it walks (the wide BVH's `bvh8-packets`, the k-d tree's
//! `kd-packets`). A walk decides which nodes and leaves a packet visits; this module holds the
//! rays' layout ([`RayPackets`], made outside timing), their loading into registers
//! ([`load`]), the test of one [`Tri4`]'s triangles against the active lanes
//! ([`Best::test_tri4`]), the split of a packet into lanes of one direction octant
//! ([`octant_groups`]) and the answers' return ([`Best::hits`]).
//!
//! Exactness: each lane computes what the single-ray Möller–Trumbore test computes for its ray,
//! operation for operation (the products and sums of [`Tri4::test`] in the same order, no
//! fused multiply-add), so each ray's hit, `t`, `u` and `v` are bit for bit the single-ray
//! test's. Only the order in which a walk meets triangles may differ from its single-ray walk,
//! so on an exact tie (two triangles at the same `t`) the reported triangle may be the other.
//!
//! The intrinsics are reached only through [`Avx512Packets`], which exists only after runtime
//! detection saw AVX-512F; the rest of the crate stays free of `unsafe`.
#![allow(unsafe_code)]

use crate::{NO_PRIM, Ray, Tri4, TriHit};
use std::arch::x86_64::*;

/// Rays in a packet: one per AVX-512 lane.
pub const PACKET: usize = 16;

/// Proof that this CPU runs AVX-512F (the only way to reach the packet code).
#[derive(Clone, Copy, Debug)]
pub struct Avx512Packets(());

impl Avx512Packets {
    pub fn detect() -> Option<Avx512Packets> {
        std::arch::is_x86_feature_detected!("avx512f").then_some(Avx512Packets(()))
    }
}

/// Up to sixteen rays in structure-of-arrays form.
#[derive(Debug)]
pub struct Packet {
    pub origin: [__m512; 3],
    pub dir: [__m512; 3],
    pub inv: [__m512; 3],
    pub t_min: __m512,
}

/// Each lane's closest hit so far.
#[derive(Debug)]
pub struct Best {
    pub t: __m512,
    pub u: __m512,
    pub v: __m512,
    pub prim: __m512i,
}

/// Rays `16 k ..` of a coherent batch in structure-of-arrays form: rows `origin x, y, z`,
/// `dir x, y, z`, `t_min`, `t_max`, one lane per ray (lanes past the batch's end are copies of
/// its last ray, never reported). The inverse directions are not stored: [`load`] computes
/// them, three divisions a packet, so a ray is 32 bytes to read instead of 44, which made
/// `bvh8-packets` 2–5 % faster on the race suite's camera rays (1 % on the holdout's) and
/// 1–3 % on shadow rays (docs/experiments.md, "the inverse directions computed when a packet
/// is loaded").
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub struct RayBlock {
    rows: [[f32; PACKET]; 8],
}

impl RayBlock {
    /// The rows, for the 8-lane loader (`packet8`).
    pub(crate) fn rows(&self) -> &[[f32; PACKET]; 8] {
        &self.rows
    }
}

/// A coherent batch as blocks of [`PACKET`] rays.
#[derive(Clone, Debug)]
pub struct RayPackets {
    blocks: Vec<RayBlock>,
    len: usize,
}

impl RayPackets {
    pub fn new(rays: &[Ray]) -> RayPackets {
        let blocks = rays
            .chunks(PACKET)
            .map(|chunk| {
                let mut rows = [[0.0f32; PACKET]; 8];
                for lane in 0..PACKET {
                    let ray = &chunk[lane.min(chunk.len() - 1)];
                    let (o, d) = (ray.origin(), ray.dir());
                    for a in 0..3 {
                        rows[a][lane] = o[a];
                        rows[3 + a][lane] = d[a];
                    }
                    rows[6][lane] = ray.t_min();
                    rows[7][lane] = ray.t_max();
                }
                RayBlock { rows }
            })
            .collect();
        RayPackets {
            blocks,
            len: rays.len(),
        }
    }

    /// The blocks of rays `first .. first + len`, when `first` starts a block (the harness's
    /// chunks are multiples of [`PACKET`]); `None` otherwise, and the caller walks ray by ray.
    pub fn range(&self, first: usize, len: usize) -> Option<&[RayBlock]> {
        let end = first.checked_add(len)?;
        (first.is_multiple_of(PACKET) && end <= self.len)
            .then(|| &self.blocks[first / PACKET..end.div_ceil(PACKET)])
    }
}

/// The blocks of a coherent batch in order, each with its rays and its outputs (fewer than
/// [`PACKET`] in the batch's last block), every block fetched two blocks before it is yielded:
/// a packet reads its whole block at once, and the hardware's stream prefetch stops at every
/// 4 KiB page (eight blocks), which left camera-ray packets waiting on their rays (measured:
/// see docs/experiments.md, "each packet's ray block fetched two packets ahead").
#[inline(always)]
pub fn each_block<'a, T>(
    blocks: &'a [RayBlock],
    rays: &'a [Ray],
    out: &'a mut [T],
) -> impl Iterator<Item = (&'a RayBlock, &'a [Ray], &'a mut [T])> {
    blocks
        .iter()
        .zip(rays.chunks(PACKET))
        .zip(out.chunks_mut(PACKET))
        .map(|((block, rays), out)| {
            crate::prefetch(std::ptr::from_ref(block).wrapping_add(2));
            (block, rays, out)
        })
}

/// A block loaded into a packet, with its closest-hit windows' far ends as the best hits so
/// far.
///
/// # Safety
///
/// AVX-512F must be available: call it from code reached through an [`Avx512Packets`].
#[target_feature(enable = "avx512f")]
pub fn load(block: &RayBlock) -> (Packet, Best) {
    // SAFETY: each row is 16 initialised f32s, 64-byte aligned (the block is aligned to 64
    // and every row is 64 bytes long).
    let load = |row: usize| unsafe { _mm512_load_ps(block.rows[row].as_ptr()) };
    let dir = [load(3), load(4), load(5)];
    // `1 / d` correctly rounded, as `Ray::new` computes `inv_dir` (`±inf` for `±0`); under the
    // same FPU mode (the harness sets one for every thread) the bits are the same.
    let one = _mm512_set1_ps(1.0);
    let packet = Packet {
        origin: [load(0), load(1), load(2)],
        inv: dir.map(|d| _mm512_div_ps(one, d)),
        dir,
        t_min: load(6),
    };
    let best = Best {
        t: load(7),
        u: _mm512_setzero_ps(),
        v: _mm512_setzero_ps(),
        prim: _mm512_set1_epi32(NO_PRIM as i32),
    };
    (packet, best)
}

/// The lanes of the first `len` rays, split by direction octant: calls `walk(lanes, octant)`
/// once per octant present, bit `a` of `octant` set when axis `a` points down (`-0` too: its
/// inverse is -inf). A walk that orders children by the direction's signs needs one octant.
///
/// # Safety
///
/// AVX-512F must be available: call it from code reached through an [`Avx512Packets`].
#[target_feature(enable = "avx512f")]
pub fn octant_groups(p: &Packet, len: usize, mut walk: impl FnMut(u16, u8)) {
    let zero = _mm512_setzero_ps();
    let down = p.inv.map(|inv| _mm512_cmp_ps_mask::<_CMP_LT_OQ>(inv, zero));
    let mut left: u16 = if len >= PACKET {
        u16::MAX
    } else {
        (1 << len) - 1
    };
    while left != 0 {
        let lane = left.trailing_zeros();
        let octant = (0..3).fold(0u8, |o, a| o | (((down[a] >> lane) & 1) as u8) << a);
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

impl Best {
    /// Each lane's hit as the single-ray walk reports it: the triangle's id ([`NO_PRIM`] for
    /// none) and the hit.
    ///
    /// # Safety
    ///
    /// AVX-512F must be available: call it from code reached through an [`Avx512Packets`].
    #[target_feature(enable = "avx512f")]
    pub fn hits(&self) -> [(u32, TriHit); PACKET] {
        let mut t = [0.0f32; PACKET];
        let mut u = [0.0f32; PACKET];
        let mut v = [0.0f32; PACKET];
        let mut prim = [0u32; PACKET];
        // SAFETY: each destination is 16 writable 4-byte values; `storeu` has no alignment
        // requirement.
        unsafe {
            _mm512_storeu_ps(t.as_mut_ptr(), self.t);
            _mm512_storeu_ps(u.as_mut_ptr(), self.u);
            _mm512_storeu_ps(v.as_mut_ptr(), self.v);
            _mm512_storeu_si512(prim.as_mut_ptr().cast(), self.prim);
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

    /// Every triangle of `tri4` against the `active` lanes; a lane's hit replaces its best when
    /// `t_min < t <= best`, triangle after triangle in slot order. With many lanes active, one
    /// triangle a sixteen-lane pass; with few ([`PAIRED_RAYS`]), the (triangle, ray) pairs in
    /// one pass instead of four passes mostly idle (measured: see docs/experiments.md,
    /// "(triangle, ray) pairs tested in one pass"). Both answer alike, bit for bit.
    ///
    /// # Safety
    ///
    /// AVX-512F must be available: call it from code reached through an [`Avx512Packets`].
    #[target_feature(enable = "avx512f")]
    pub fn test_tri4(&mut self, tri4: &Tri4, p: &Packet, active: u16) {
        // The four normals `e2 × e1` in one pass (the same operations as `cross`, so the same
        // bits), broadcast per triangle below.
        let ng4 = normals(tri4);
        if active.count_ones() <= PAIRED_RAYS {
            self.pairs(tri4, &ng4, p, active);
        } else {
            self.each_triangle(tri4, &ng4, p, active);
        }
    }

    /// Each triangle of `tri4` (normals `ng4`) against the `active` lanes, one a sixteen-lane
    /// pass.
    #[target_feature(enable = "avx512f")]
    fn each_triangle(&mut self, tri4: &Tri4, ng4: &[[f32; 4]; 3], p: &Packet, active: u16) {
        for lane in 0..4 {
            let id = tri4.ids[lane];
            if id == NO_PRIM {
                break;
            }
            let at = |v: &[[f32; 4]; 3]| [0, 1, 2].map(|a| _mm512_set1_ps(v[a][lane]));
            let tri = [at(&tri4.v0), at(&tri4.e1), at(&tri4.e2), at(ng4)];
            let ray = (&p.origin, &p.dir, p.t_min, self.t);
            let (hit, [t, u, v, abs_den]) = moller(&tri, ray, active);
            if hit == 0 {
                continue;
            }
            let inv = _mm512_div_ps(_mm512_set1_ps(1.0), abs_den);
            self.t = _mm512_mask_mov_ps(self.t, hit, _mm512_mul_ps(t, inv));
            self.u = _mm512_mask_mov_ps(self.u, hit, _mm512_mul_ps(u, inv));
            self.v = _mm512_mask_mov_ps(self.v, hit, _mm512_mul_ps(v, inv));
            self.prim = _mm512_mask_mov_epi32(self.prim, hit, _mm512_set1_epi32(id as i32));
        }
    }
}

/// Active rays up to which [`Best::test_tri4`] tests (triangle, ray) pairs: four rays against
/// the four triangles fill the sixteen lanes of one pass. Up to eight (two passes) was 2–6 %
/// slower on camera rays (measured: see docs/experiments.md, "(triangle, ray) pairs tested in
/// one pass").
const PAIRED_RAYS: u32 = 4;

impl Best {
    /// [`Best::test_tri4`] for few `active` lanes: each pair (triangle `k`, ray `j` of four) in
    /// SIMD lane `4 j + k` of one pass, with the operations of the one-triangle pass
    /// ([`Best::each_triangle`]), so each pair's edge tests, `t`, `u` and `v` have its bits. The
    /// pass screens with each ray's best before the `Tri4`; the pairs left are then taken in the
    /// one-triangle passes' order (a ray's triangles in slot order) against the best as those
    /// passes would leave it, in scalar: the same IEEE operations, so the same answers, ties
    /// included. Mostly no pair is left: a ray hits few of the triangles it meets.
    #[target_feature(enable = "avx512f")]
    fn pairs(&mut self, tri4: &Tri4, ng4: &[[f32; 4]; 3], p: &Packet, active: u16) {
        let rays = active.count_ones();
        let iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let packed = _mm512_maskz_compress_epi32(active, iota);
        let mut number = [0u32; PACKET];
        // SAFETY: `number` is 16 writable 4-byte values; `storeu` has no alignment requirement.
        unsafe { _mm512_storeu_si512(number.as_mut_ptr().cast(), packed) };
        let four = |v: &[[f32; 4]; 3]| {
            // SAFETY: each row is four initialised f32s; `loadu` has no alignment requirement.
            [0, 1, 2].map(|a| _mm512_broadcast_f32x4(unsafe { _mm_loadu_ps(v[a].as_ptr()) }))
        };
        let tri = [four(&tri4.v0), four(&tri4.e1), four(&tri4.e2), four(ng4)];
        let slots = tri4.ids.iter().take_while(|&&id| id != NO_PRIM).count();
        let triangles = ((1u32 << slots) - 1) * 0x1111;
        let ray_of = _mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
        for pass in 0..rays.div_ceil(4) {
            let first = 4 * pass;
            let which = _mm512_add_epi32(ray_of, _mm512_set1_epi32(first as i32));
            let lane = _mm512_permutexvar_epi32(which, packed);
            let of = |v: __m512| _mm512_permutexvar_ps(lane, v);
            let (origin, dir) = (p.origin.map(of), p.dir.map(of));
            let in_pass = (rays - first).min(4);
            let pairs = (((1u32 << (4 * in_pass)) - 1) & triangles) as u16;
            let (mut hit, quad) = moller(&tri, (&origin, &dir, of(p.t_min), of(self.t)), pairs);
            if hit == 0 {
                continue;
            }
            // The pairs that may hit, in the order of the one-triangle passes for each ray (its
            // triangles in slot order), each against the ray's best as those passes leave it,
            // in scalar: the same IEEE operations as their lanes, so the same bits.
            let mut raw = [[0f32; PACKET]; 4];
            let mut best = [0f32; PACKET];
            // SAFETY: each destination is 16 writable f32s; `storeu` has no alignment
            // requirement.
            unsafe {
                for (row, x) in raw.iter_mut().zip(quad) {
                    _mm512_storeu_ps(row.as_mut_ptr(), x);
                }
                _mm512_storeu_ps(best.as_mut_ptr(), self.t);
            }
            let [t, u, v, abs_den] = raw;
            while hit != 0 {
                let pair = hit.trailing_zeros() as usize;
                hit &= hit - 1;
                let l = number[first as usize + pair / 4] as usize;
                if t[pair] <= abs_den[pair] * best[l] {
                    let inv = 1.0 / abs_den[pair];
                    best[l] = t[pair] * inv;
                    let m = 1u16 << l;
                    self.t = _mm512_mask_mov_ps(self.t, m, _mm512_set1_ps(best[l]));
                    self.u = _mm512_mask_mov_ps(self.u, m, _mm512_set1_ps(u[pair] * inv));
                    self.v = _mm512_mask_mov_ps(self.v, m, _mm512_set1_ps(v[pair] * inv));
                    let id = _mm512_set1_epi32(tri4.ids[pair % 4] as i32);
                    self.prim = _mm512_mask_mov_epi32(self.prim, m, id);
                }
            }
        }
    }
}

/// The Möller–Trumbore test of [`Tri4::test`], lane for lane: triangles `tri` (`v0`, `e1`,
/// `e2` and the normal `e2 × e1`, per axis) against rays `(origin, dir, t_min, best)` in the
/// lanes `lanes`. Returns the lanes that hit with `t_min < t <= best`, and `t`, `u`, `v` (each
/// still times `|den|`) and `|den|`; no lane when the edge tests leave none, with the values
/// then unset. Both passes of [`Best::test_tri4`] run it, so their bits agree.
#[target_feature(enable = "avx512f")]
#[inline]
fn moller(
    tri: &[[__m512; 3]; 4],
    (origin, dir, t_min, best): (&[__m512; 3], &[__m512; 3], __m512, __m512),
    lanes: u16,
) -> (u16, [__m512; 4]) {
    let [v0, e1, e2, ng] = tri;
    let zero = _mm512_setzero_ps();
    let c = [0, 1, 2].map(|a| _mm512_sub_ps(v0[a], origin[a]));
    let rr = cross(&c, dir);
    let den = dot(ng, dir);
    let abs_den = _mm512_abs_ps(den);
    let u = flip(dot(&rr, e2), den);
    let v = flip(dot(&rr, e1), den);
    let mut hit = _mm512_mask_cmp_ps_mask::<_CMP_NEQ_UQ>(lanes, den, zero);
    hit = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(hit, u, zero);
    hit = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(hit, v, zero);
    hit = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(hit, _mm512_add_ps(u, v), abs_den);
    if hit == 0 {
        return (0, [zero; 4]);
    }
    let t = flip(dot(ng, &c), den);
    hit = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(hit, _mm512_mul_ps(abs_den, t_min), t);
    hit = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(hit, t, _mm512_mul_ps(abs_den, best));
    (hit, [t, u, v, abs_den])
}

/// `a × b` lane-wise in glam's order, as [`Tri4::test`].
#[target_feature(enable = "avx512f")]
#[inline]
fn cross(a: &[__m512; 3], b: &[__m512; 3]) -> [__m512; 3] {
    [
        _mm512_sub_ps(_mm512_mul_ps(a[1], b[2]), _mm512_mul_ps(b[1], a[2])),
        _mm512_sub_ps(_mm512_mul_ps(a[2], b[0]), _mm512_mul_ps(b[2], a[0])),
        _mm512_sub_ps(_mm512_mul_ps(a[0], b[1]), _mm512_mul_ps(b[0], a[1])),
    ]
}

/// `a · b` lane-wise in glam's order, `(ax bx + ay by) + az bz`.
#[target_feature(enable = "avx512f")]
#[inline]
fn dot(a: &[__m512; 3], b: &[__m512; 3]) -> __m512 {
    _mm512_add_ps(
        _mm512_add_ps(_mm512_mul_ps(a[0], b[0]), _mm512_mul_ps(a[1], b[1])),
        _mm512_mul_ps(a[2], b[2]),
    )
}

/// `x` negated in the lanes where `by` has its sign bit set (`-0` counts as negative).
#[target_feature(enable = "avx512f")]
#[inline]
fn flip(x: __m512, by: __m512) -> __m512 {
    let sign = _mm512_and_si512(_mm512_castps_si512(by), _mm512_set1_epi32(i32::MIN));
    _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(x), sign))
}

/// `e2 × e1` of a `Tri4`'s four triangles, per axis, in glam's order.
#[inline(always)]
pub(crate) fn normals(t: &Tri4) -> [[f32; 4]; 3] {
    let (e1, e2) = (&t.e1, &t.e2);
    [
        std::array::from_fn(|l| e2[1][l] * e1[2][l] - e1[1][l] * e2[2][l]),
        std::array::from_fn(|l| e2[2][l] * e1[0][l] - e1[2][l] * e2[0][l]),
        std::array::from_fn(|l| e2[0][l] * e1[1][l] - e1[0][l] * e2[1][l]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crate::{MollerTriangle, Triangle, Vec3};

    /// The pair test that [`Best::test_tri4`] takes when few lanes are active leaves every
    /// lane's best exactly as the one-triangle passes do: hit, `t`, `u` and `v` bit for bit and
    /// the same triangle on ties (a triangle repeated in a later slot), over random `Tri4`s with
    /// one to four triangles met one after another, windows that earlier hits shrink (within
    /// a `Tri4` too), and active sets of every size.
    #[test]
    fn paired_lanes_answer_as_one_triangle_a_pass() {
        if Avx512Packets::detect().is_none() {
            eprintln!("no AVX-512F on this CPU: no packet is ever tested here");
            return;
        }
        let mut rng = SplitMix64::new(5);
        let (mut paired, mut hits) = (0, 0);
        for case in 0..400 {
            let near = |rng: &mut SplitMix64| rng.point_in(Vec3::splat(-1.0), Vec3::splat(1.0));
            let tri4s: Vec<Tri4> = (0..3)
                .map(|k| {
                    let count = 1 + (case + k) % 4;
                    let mut tris: Vec<(u32, MollerTriangle)> = (0..count)
                        .map(|i| {
                            let t = Triangle::new(near(&mut rng), near(&mut rng), near(&mut rng));
                            ((10 * k + i) as u32, MollerTriangle::new(&t))
                        })
                        .collect();
                    if count > 1 && case % 3 == 0 {
                        // An exact tie: the first triangle again under another id.
                        tris[count - 1].1 = tris[0].1;
                    }
                    Tri4::pack(&tris)
                })
                .collect();
            let rays: Vec<Ray> = (0..PACKET)
                .map(|_| {
                    let origin = near(&mut rng) * 0.3 + Vec3::new(0.0, 0.0, 4.0);
                    let dir = near(&mut rng) - origin;
                    Ray::new(origin, dir, 0.0, rng.range(0.5, 1.2))
                })
                .collect();
            let block = &RayPackets::new(&rays).blocks[0];
            let active = (rng.next_u64() as u16) >> (case % 16);
            let answers = |whole: bool| {
                // SAFETY: AVX-512F was detected above.
                unsafe {
                    let (p, mut best) = load(block);
                    for tri4 in &tri4s {
                        if whole {
                            best.test_tri4(tri4, &p, active);
                        } else {
                            best.each_triangle(tri4, &normals(tri4), &p, active);
                        }
                    }
                    best.hits()
                        .map(|(prim, h)| (prim, [h.t, h.u, h.v].map(f32::to_bits)))
                }
            };
            let (plain, whole) = (answers(false), answers(true));
            assert_eq!(plain, whole, "case {case}, lanes {active:016b}");
            paired += (active.count_ones() <= PAIRED_RAYS) as usize;
            hits += plain.iter().filter(|(prim, _)| *prim != NO_PRIM).count();
        }
        // Enough of both kinds for the comparison to mean something.
        assert!(paired > 100 && hits > 150, "paired {paired}, hits {hits}");
    }

    /// The loader's inverse directions are `Ray::inv_dir`'s, bit for bit, with zeros of both
    /// signs, subnormals and extremes among the components: a lane whose inverse differed by
    /// one ulp could enter a box its single-ray walk misses.
    #[test]
    fn loaded_inverse_directions_are_the_rays_own() {
        if Avx512Packets::detect().is_none() {
            eprintln!("no AVX-512F on this CPU: no packet is ever loaded here");
            return;
        }
        let c = [
            1.0,
            -1.0,
            0.0,
            -0.0,
            1e-40,
            -1e-39,
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            3.0e38,
            -0.3,
            7.0e-20,
            f32::MAX,
            1.0 / 3.0,
        ];
        let n = c.len();
        let rays: Vec<Ray> = (0..3 * n + 1)
            .map(|i| {
                let dir = Vec3::new(c[i % n], c[(5 * i + 1) % n], c[(7 * i + 2) % n]);
                Ray::new(Vec3::ZERO, dir, 0.0, 1.0)
            })
            .collect();
        let packets = RayPackets::new(&rays);
        let blocks = packets.range(0, rays.len()).expect("the whole batch");
        assert_eq!(blocks.len(), rays.len().div_ceil(PACKET));
        for (b, block) in blocks.iter().enumerate() {
            // SAFETY: AVX-512F was detected above.
            let (packet, _) = unsafe { load(block) };
            for (axis, inv) in packet.inv.iter().enumerate() {
                let mut lanes = [0.0f32; PACKET];
                // SAFETY: AVX-512F was detected; `lanes` holds sixteen f32s.
                unsafe { _mm512_storeu_ps(lanes.as_mut_ptr(), *inv) };
                for (lane, got) in lanes.iter().enumerate() {
                    let ray = &rays[(PACKET * b + lane).min(rays.len() - 1)];
                    let want = ray.inv_dir()[axis];
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "ray {} axis {axis}: dir {:?}, loaded {got:e}, inv_dir {want:e}",
                        PACKET * b + lane,
                        ray.dir()
                    );
                }
            }
        }
    }

    /// [`each_block`] yields every block once, in order, with its own rays and outputs: a whole
    /// block sixteen of each, the last block of a batch that does not fill it only the rest.
    #[test]
    fn each_block_pairs_blocks_with_their_rays_and_outputs() {
        for len in [1, PACKET - 1, PACKET, PACKET + 1, 5 * PACKET + 3] {
            let rays: Vec<Ray> = (0..len)
                .map(|i| Ray::new(Vec3::new(i as f32, 0.0, 0.0), Vec3::Z, 0.0, 1.0))
                .collect();
            let packets = RayPackets::new(&rays);
            let blocks = packets.range(0, len).expect("the whole batch");
            let mut out = vec![usize::MAX; len];
            let mut yielded = 0;
            for (b, (block, block_rays, block_out)) in
                each_block(blocks, &rays, &mut out).enumerate()
            {
                assert!(std::ptr::eq(block, &blocks[b]), "len {len}: block {b}");
                let want = PACKET.min(len - PACKET * b);
                assert_eq!(
                    (block_rays.len(), block_out.len()),
                    (want, want),
                    "len {len}"
                );
                for (lane, (ray, o)) in block_rays.iter().zip(block_out.iter_mut()).enumerate() {
                    // Each ray is its block's row 0 lane: the block was made from these rays.
                    assert_eq!(
                        ray.origin().x,
                        block.rows()[0][lane],
                        "len {len}: block {b}"
                    );
                    *o = ray.origin().x as usize;
                }
                yielded += 1;
            }
            assert_eq!(yielded, blocks.len(), "len {len}");
            assert_eq!(out, (0..len).collect::<Vec<_>>(), "len {len}");
        }
    }
}
