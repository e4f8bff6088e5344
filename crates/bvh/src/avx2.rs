//! The AVX2 kernels of the wide BVHs, chosen at run time: the 8-wide node test in one pass of
//! 8-lane arithmetic per axis, and leaves tested two packets a pass.
//!
//! The SSE kernel ([`crate::wide::SseNodes`]) needs two 4-lane passes per axis for an 8-wide
//! node; AVX2 does the same arithmetic in one, lane for lane: `max`/`min` keep the accumulator
//! when a lane is NaN (`0 * inf` for a ray in a box's face plane, bug class B1), the compare is
//! ordered (false on NaN). [`Avx2Nodes`] can only be made by [`Avx2Nodes::detect`], after the
//! CPU has reported AVX2, which is what makes calling the `#[target_feature]` code sound.
//! AVX-512 adds no arithmetic an 8-lane f32 test needs, so there is no AVX-512 kernel. What it
//! adds is registers: 32 vector registers instead of 16. The walk keeps ten splatted values of
//! the ray live (origin, direction, inverse direction, `t_min`); with AVX2's sixteen, the
//! compiler spilled them and reloaded six at every node. The batch loops are therefore
//! compiled twice ([`batch_loops`]), once with AVX-512F and VL enabled; the same arithmetic
//! runs in both, so the answers and counters are the same. Over the 17 scenes of the default
//! suite, best of 10 passes interleaved with embree-medium in one process (`examples/wide.rs`,
//! this VM's Zen 4, 2026-11-21), the AVX-512 loops against the AVX2 ones, three sweeps:
//! primary +7.4 / +7.1 / +7.0 %, random +5.2 / +3.7 / +4.2 %, shadow +5.8 / +6.8 / +2.3 %.
//!
//! Leaves get the same treatment: two [`Tri4`] packets in one 8-lane Möller–Trumbore pass
//! ([`leaf_pairs`]), the same operations lane for lane as the SSE packet test and the same
//! choice among lanes. Bunny, 20 000 rays a workload, callgrind: primary 19.38M → 18.66M
//! instructions, shadow 9.92M → 9.73M; timed, hair shadow rays 0.80 → 0.93× embree-medium
//! and soup and grass 3–5 % faster (this VM, 2026-11-21).

use crate::simd::F4;
use crate::wide::{BvhWide, NodeKernel, Stack, WideNode, slab_quads};
use raybench_accel::{CounterSink, Hit, NoCount};
use raybench_geom::Tri4;
use raybench_geom::tri4::nearest_lane;
use raybench_geom::{Ray, TriHit};
use std::arch::x86_64::*;

/// Proof that this CPU runs AVX2 (the only way to reach the AVX2 code), and whether the batch
/// loops may also use AVX-512VL's 32 vector registers.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2Nodes {
    wide_registers: bool,
}

impl Avx2Nodes {
    /// AVX2 when the CPU has it; with `avx512` also AVX-512F and VL when it has them.
    pub(crate) fn detect(avx512: bool) -> Option<Avx2Nodes> {
        std::arch::is_x86_feature_detected!("avx2").then(|| Avx2Nodes {
            wide_registers: avx512
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl"),
        })
    }

    /// Whether the batch loops run with AVX-512VL's registers.
    pub(crate) fn wide_registers(self) -> bool {
        self.wide_registers
    }
}

/// The ray for the AVX2 tests: origin, direction, inverse direction and `t_min` splatted to 8
/// lanes, and per axis which stored side (min or max) holds the near planes.
pub(crate) struct Avx2Ray {
    origin: [__m256; 3],
    inv: [__m256; 3],
    near: [bool; 3],
    dir: [__m256; 3],
    t_min: __m256,
}

#[target_feature(enable = "avx2")]
fn splat_ray(ray: &Ray) -> Avx2Ray {
    let inv = ray.inv_dir().to_array();
    let origin = ray.origin().to_array();
    Avx2Ray {
        origin: origin.map(|x| _mm256_set1_ps(x)),
        inv: inv.map(|x| _mm256_set1_ps(x)),
        // -0 counts as negative: its inverse is -inf (bug class B3).
        near: inv.map(|x| x.is_sign_negative()),
        dir: ray.dir().to_array().map(|x| _mm256_set1_ps(x)),
        t_min: _mm256_set1_ps(ray.t_min()),
    }
}

/// The eight lanes `8 * o ..` of a plane row, for one AVX load.
#[inline(always)]
fn oct<const W: usize>(row: &[f32; W], o: usize) -> &[f32; 8] {
    &row.as_chunks::<8>().0[o]
}

/// One pass per axis and eight children.
#[target_feature(enable = "avx2")]
#[inline]
fn test_octs<const W: usize>(
    r: &Avx2Ray,
    n: &WideNode<W>,
    t_min: f32,
    t_max: f32,
) -> (u32, [f32; W]) {
    let mut mask = 0;
    let mut entry = [0.0f32; W];
    for o in 0..W / 8 {
        let mut t0 = _mm256_set1_ps(t_min);
        let mut t1 = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let near = oct(&n.planes[a][r.near[a] as usize], o);
            let far = oct(&n.planes[a][!r.near[a] as usize], o);
            // SAFETY: each is a reference to 8 contiguous initialised f32s, and `loadu` has
            // no alignment requirement.
            let (near, far) = unsafe {
                (
                    _mm256_loadu_ps(near.as_ptr()),
                    _mm256_loadu_ps(far.as_ptr()),
                )
            };
            t0 = _mm256_max_ps(
                _mm256_mul_ps(_mm256_sub_ps(near, r.origin[a]), r.inv[a]),
                t0,
            );
            t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(far, r.origin[a]), r.inv[a]), t1);
        }
        mask |= (_mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32) << (8 * o);
        let out: &mut [f32; 8] = &mut entry.as_chunks_mut::<8>().0[o];
        // SAFETY: `out` is 8 writable f32s; `storeu` has no alignment requirement.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), t0) };
    }
    (mask, entry)
}

impl<const W: usize> NodeKernel<W> for Avx2Nodes {
    type Ray = Avx2Ray;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> Avx2Ray {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { splat_ray(ray) }
    }

    #[inline(always)]
    fn test(self, ray: &Avx2Ray, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe {
            if W.is_multiple_of(8) {
                test_octs(ray, n, t_min, t_max)
            } else {
                // 4 wide: the SSE kernel's arithmetic on the low halves of the splatted ray.
                let low = |v: &[__m256; 3]| v.map(|x| F4::from_m128(_mm256_castps256_ps128(x)));
                slab_quads(&low(&ray.origin), &low(&ray.inv), ray.near, n, t_min, t_max)
            }
        }
    }

    #[inline(always)]
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &Avx2Ray,
        packets: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool {
        // SAFETY: an `Avx2Nodes` exists only after `detect` saw AVX2 on this CPU.
        unsafe { leaf_pairs::<ANY_HIT>(ray, packets, first, best_t, best) }
    }
}

/// A leaf's packets two at a time, one 8-lane pass per pair (a last odd packet alone, its upper
/// lanes zero), with [`crate::wide::intersect_packets`]'s answers: the same arithmetic lane for
/// lane as [`Tri4::intersect`], and the same choice among lanes, so the hit (and on an exact
/// tie, the triangle) is the one the packet-by-packet loop reports. Leaves of two or more
/// packets (the bunny's mean leaf holds 9.8 triangles, about three packets) take half the
/// passes.
#[target_feature(enable = "avx2")]
#[inline]
fn leaf_pairs<const ANY_HIT: bool>(
    r: &Avx2Ray,
    packets: &[Tri4],
    first: usize,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
) -> bool {
    let mut k = 0;
    while k < packets.len() {
        let (a, b) = (&packets[k], packets.get(k + 1));
        if let Some((lane, h)) = test8(r, a, b, *best_t) {
            *best_t = h.t;
            *best = Some((4 * (first + k) + lane, h));
            if ANY_HIT {
                return true;
            }
        }
        k += 2;
    }
    false
}

/// Lanes 0–3 from `a`'s row and 4–7 from `b`'s (zero without `b`).
#[target_feature(enable = "avx2")]
#[inline]
fn load8(a: &[f32; 4], b: Option<&[f32; 4]>) -> __m256 {
    // SAFETY: both are references to 4 initialised f32s; `loadu` has no alignment
    // requirement.
    unsafe {
        let lo = _mm256_zextps128_ps256(_mm_loadu_ps(a.as_ptr()));
        match b {
            Some(b) => _mm256_insertf128_ps::<1>(lo, _mm_loadu_ps(b.as_ptr())),
            None => lo,
        }
    }
}

/// The three rows of a vector field of `a` (lanes 0–3) and `b` (4–7).
#[target_feature(enable = "avx2")]
#[inline]
fn load_rows(a: &[[f32; 4]; 3], b: Option<&[[f32; 4]; 3]>) -> [__m256; 3] {
    [
        load8(&a[0], b.map(|b| &b[0])),
        load8(&a[1], b.map(|b| &b[1])),
        load8(&a[2], b.map(|b| &b[2])),
    ]
}

/// `a × b` lane-wise in glam's order, as [`Tri4::intersect`].
#[target_feature(enable = "avx2")]
#[inline]
fn cross8(a: &[__m256; 3], b: &[__m256; 3]) -> [__m256; 3] {
    [
        _mm256_sub_ps(_mm256_mul_ps(a[1], b[2]), _mm256_mul_ps(b[1], a[2])),
        _mm256_sub_ps(_mm256_mul_ps(a[2], b[0]), _mm256_mul_ps(b[2], a[0])),
        _mm256_sub_ps(_mm256_mul_ps(a[0], b[1]), _mm256_mul_ps(b[0], a[1])),
    ]
}

/// `a · b` lane-wise in glam's order, `(ax bx + ay by) + az bz`.
#[target_feature(enable = "avx2")]
#[inline]
fn dot8(a: &[__m256; 3], b: &[__m256; 3]) -> __m256 {
    _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
        _mm256_mul_ps(a[2], b[2]),
    )
}

/// `x` negated in the lanes where `by` has its sign bit set (`-0` counts as negative).
#[target_feature(enable = "avx2")]
#[inline]
fn flip8(x: __m256, by: __m256) -> __m256 {
    _mm256_xor_ps(x, _mm256_and_ps(by, _mm256_set1_ps(-0.0)))
}

/// Lanes whose (undivided) distance `t` lies in the window `(t_min, t_max]`.
#[target_feature(enable = "avx2")]
#[inline]
fn in_window8(t: __m256, abs_den: __m256, t_min: __m256, t_max: f32) -> u32 {
    let above = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_mul_ps(abs_den, t_min), t);
    let below = _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_mul_ps(abs_den, _mm256_set1_ps(t_max)));
    _mm256_movemask_ps(_mm256_and_ps(above, below)) as u32
}

/// `x * inv`, as lanes.
#[target_feature(enable = "avx2")]
#[inline]
fn scaled(x: __m256, inv: __m256) -> [f32; 8] {
    let mut out = [0.0f32; 8];
    // SAFETY: `out` is 8 writable f32s; `storeu` has no alignment requirement.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), _mm256_mul_ps(x, inv)) };
    out
}

/// [`Tri4::intersect`] for two packets in one pass: the answer of testing `a` and then `b`
/// with the window shrunk to `a`'s hit, as a lane `0..8` (4.. for `b`) and its hit.
#[target_feature(enable = "avx2")]
#[inline]
fn test8(r: &Avx2Ray, a: &Tri4, b: Option<&Tri4>, t_max: f32) -> Option<(usize, TriHit)> {
    let v0 = load_rows(&a.v0, b.map(|b| &b.v0));
    let c = [0, 1, 2].map(|i| _mm256_sub_ps(v0[i], r.origin[i]));
    let rr = cross8(&c, &r.dir);
    let e1 = load_rows(&a.e1, b.map(|b| &b.e1));
    let e2 = load_rows(&a.e2, b.map(|b| &b.e2));
    let ng = cross8(&e2, &e1);
    let den = dot8(&ng, &r.dir);
    let abs_den = _mm256_andnot_ps(_mm256_set1_ps(-0.0), den);
    let u = flip8(dot8(&rr, &e2), den);
    let v = flip8(dot8(&rr, &e1), den);
    let zero = _mm256_setzero_ps();
    let inside = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(den, zero),
            _mm256_cmp_ps::<_CMP_GE_OQ>(u, zero),
        ),
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(v, zero),
            _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_add_ps(u, v), abs_den),
        ),
    );
    let inside = _mm256_movemask_ps(inside) as u32;
    if inside == 0 {
        return None;
    }
    let t = flip8(dot8(&ng, &c), den);
    let mask = inside & in_window8(t, abs_den, r.t_min, t_max);
    if mask == 0 {
        return None;
    }
    let inv = _mm256_div_ps(_mm256_set1_ps(1.0), abs_den);
    let tt = scaled(t, inv);
    let mut pick = (mask & 0xF != 0).then(|| nearest_lane(&tt, mask & 0xF));
    let mut later = mask & 0xF0;
    if let Some(i) = pick
        && later != 0
    {
        // `b` is tested with the window shrunk to `a`'s hit, as the packet loop would.
        later &= in_window8(t, abs_den, r.t_min, tt[i]);
    }
    if later != 0 {
        pick = Some(nearest_lane(&tt, later));
    }
    let (uu, vv) = (scaled(u, inv), scaled(v, inv));
    pick.map(|i| {
        (
            i,
            TriHit {
                t: tt[i],
                u: uu[i],
                v: vv[i],
            },
        )
    })
}

/// [`BvhWide::walk_with`] compiled for AVX2, so [`test_octs`] inlines into the loop.
#[target_feature(enable = "avx2")]
fn walk_ray_avx2<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    bvh.walk_with::<ANY_HIT, C, Avx2Nodes>(k, ray, stack, c)
}

#[inline(always)]
pub(crate) fn walk_ray<const W: usize, const ANY_HIT: bool, C: CounterSink>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    ray: &Ray,
    stack: &mut Stack,
    c: &mut C,
) -> Option<Hit> {
    // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
    unsafe { walk_ray_avx2::<W, ANY_HIT, C>(bvh, k, ray, stack, c) }
}

/// The batch loops, once per instruction set: the loop lives inside the `#[target_feature]`
/// code, so a ray pays no call, prologue or kernel dispatch of its own. The AVX-512 copies run
/// the same AVX2 arithmetic lane for lane (so the same answers); what they gain is sixteen more
/// vector registers, so the splatted ray (origin, direction, inverse direction, `t_min`: ten
/// registers) no longer spills to the stack and is reloaded at every node.
macro_rules! batch_loops {
    ($features:literal, $closest:ident, $any:ident) => {
        #[target_feature(enable = $features)]
        fn $closest<const W: usize>(
            bvh: &BvhWide<W>,
            k: Avx2Nodes,
            rays: &[Ray],
            out: &mut [Option<Hit>],
            stack: &mut Stack,
        ) {
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = bvh.walk_with::<false, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount);
            }
        }

        #[target_feature(enable = $features)]
        fn $any<const W: usize>(
            bvh: &BvhWide<W>,
            k: Avx2Nodes,
            rays: &[Ray],
            out: &mut [bool],
            stack: &mut Stack,
        ) {
            for (o, ray) in out.iter_mut().zip(rays) {
                *o = bvh
                    .walk_with::<true, NoCount, Avx2Nodes>(k, ray, stack, &mut NoCount)
                    .is_some();
            }
        }
    };
}

batch_loops!("avx2", intersect_all_avx2, occluded_all_avx2);
batch_loops!(
    "avx2,avx512f,avx512vl",
    intersect_all_avx512,
    occluded_all_avx512
);

pub(crate) fn intersect_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    stack: &mut Stack,
) {
    if k.wide_registers {
        // SAFETY: `k` says AVX-512F and VL only when `detect` saw them on this CPU.
        unsafe { intersect_all_avx512(bvh, k, rays, out, stack) }
    } else {
        // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
        unsafe { intersect_all_avx2(bvh, k, rays, out, stack) }
    }
}

pub(crate) fn occluded_all<const W: usize>(
    bvh: &BvhWide<W>,
    k: Avx2Nodes,
    rays: &[Ray],
    out: &mut [bool],
    stack: &mut Stack,
) {
    if k.wide_registers {
        // SAFETY: `k` says AVX-512F and VL only when `detect` saw them on this CPU.
        unsafe { occluded_all_avx512(bvh, k, rays, out, stack) }
    } else {
        // SAFETY: `k` exists only after `detect` saw AVX2 on this CPU.
        unsafe { occluded_all_avx2(bvh, k, rays, out, stack) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wide::intersect_packets;
    use raybench_geom::{MollerTriangle, Triangle, Vec3};

    type Answer = (bool, u32, Option<(usize, u32, u32, u32)>);

    /// The leaf's answer, best distance and best hit, bit for bit.
    fn answer(stop: bool, best_t: f32, best: Option<(usize, TriHit)>) -> Answer {
        let hit = best.map(|(i, h)| (i, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
        (stop, best_t.to_bits(), hit)
    }

    /// Pairs of packets in one 8-lane pass answer exactly as the packet-by-packet loop: the
    /// same hit, distance and barycentrics bit for bit, and on exact ties (a triangle repeated
    /// in a later packet) the same lane, for leaves of one to five packets, closest and any
    /// hit, with a best distance carried in from earlier leaves.
    #[test]
    fn pairs_answer_as_the_packet_loop() {
        let Some(_) = Avx2Nodes::detect(false) else {
            eprintln!("no AVX2 on this CPU: the pair test has nothing to check");
            return;
        };
        let mut rng = raybench_geom::SplitMix64::new(0x1eaf);
        let (mut hits, mut ties) = (0, 0);
        for case in 0..20_000usize {
            let packets_used = 1 + case % 5;
            let mut tris: Vec<MollerTriangle> = Vec::new();
            for k in 0..packets_used * 4 - case % 4 {
                // Every third case repeats earlier triangles in later packets: exact ties.
                let t = if case % 3 == 0 && k >= 4 && k % 2 == 0 {
                    tris[k % 4]
                } else {
                    MollerTriangle::new(&Triangle::new(
                        rng.signed_vec() * 1.0,
                        rng.signed_vec() * 1.0,
                        rng.signed_vec() * 1.0,
                    ))
                };
                tris.push(t);
            }
            let packets: Vec<Tri4> = tris
                .chunks(4)
                .map(|c| {
                    let ids: Vec<(u32, MollerTriangle)> = c.iter().map(|t| (7, *t)).collect();
                    Tri4::pack(&ids)
                })
                .collect();
            let target = tris[case % tris.len()];
            let origin = rng.signed_vec() * 3.0;
            let (a, b) = (rng.unit() * 1.2 - 0.1, rng.unit() * 1.2 - 0.1);
            let aim = target.v0 - target.e1 * a + target.e2 * (b * (1.0 - a));
            let mut dir = aim - origin;
            if case % 5 == 0 {
                dir[case % 3] = if case % 2 == 0 { 0.0 } else { -0.0 };
            }
            let ray = Ray::new(origin, dir, 0.01, f32::INFINITY);
            let carried = if case % 4 == 0 { 1.0 } else { f32::INFINITY };
            let first = case % 9;
            // SAFETY: `detect` saw AVX2 above.
            let wide = unsafe { splat_ray(&ray) };
            let run_loop = |any: bool| {
                let (mut t, mut best) = (carried, None);
                let stop = if any {
                    intersect_packets::<true>(&packets, first, &ray, &mut t, &mut best)
                } else {
                    intersect_packets::<false>(&packets, first, &ray, &mut t, &mut best)
                };
                answer(stop, t, best)
            };
            let run_pairs = |any: bool| {
                let (mut t, mut best) = (carried, None);
                // SAFETY: `detect` saw AVX2 above.
                let stop = unsafe {
                    if any {
                        leaf_pairs::<true>(&wide, &packets, first, &mut t, &mut best)
                    } else {
                        leaf_pairs::<false>(&wide, &packets, first, &mut t, &mut best)
                    }
                };
                answer(stop, t, best)
            };
            let closest = run_loop(false);
            assert_eq!(run_pairs(false), closest, "case {case}: {ray:?}");
            // Any hit: the same verdict (which hit ends the walk is free).
            assert_eq!(run_pairs(true).0, run_loop(true).0, "case {case}: {ray:?}");
            hits += closest.2.is_some() as usize;
            ties += (case % 3 == 0 && closest.2.is_some_and(|h| h.0 >= 4 * first + 4)) as usize;
        }
        assert!(
            hits > 2_000 && ties > 100,
            "{hits} hits, {ties} in later packets"
        );
    }

    #[test]
    fn a_lone_packet_leaves_the_upper_lanes_empty() {
        let Some(_) = Avx2Nodes::detect(false) else {
            return;
        };
        let tri = MollerTriangle::new(&Triangle::new(Vec3::X, Vec3::Y, Vec3::Z));
        let packet = Tri4::pack(&[(3, tri)]);
        let ray = Ray::new(Vec3::ZERO, Vec3::ONE, 0.0, f32::INFINITY);
        // SAFETY: `detect` saw AVX2 above.
        let hit = unsafe { test8(&splat_ray(&ray), &packet, None, f32::INFINITY) };
        assert_eq!(hit.map(|(lane, _)| lane), Some(0));
        let miss = Ray::new(Vec3::splat(5.0), Vec3::ONE, 0.0, f32::INFINITY);
        // SAFETY: as above.
        assert!(unsafe { test8(&splat_ray(&miss), &packet, None, f32::INFINITY) }.is_none());
    }
}
