//! The AVX2 leaf test: two [`Tri4`]s in one 8-lane Möller–Trumbore pass ([`leaf_pairs`]), the
//! same operations lane for lane as the SSE `Tri4` test and the same choice among lanes, so
//! the same answers in half the passes (measured: see docs/experiments.md, "AVX2 leaves: two
//! `Tri4`s in one 8-lane pass").

use super::Avx2Ray;
use raybench_geom::tri4::nearest_lane;
use raybench_geom::{Tri4, TriHit};
use std::arch::x86_64::*;

/// A leaf's `Tri4`s two at a time, one 8-lane pass per pair (a last odd one alone, its upper lanes
/// zero), with [`crate::wide::kernels::intersect_tri4s`]'s answers: the same arithmetic lane for
/// lane as [`Tri4::intersect`], and the same choice among lanes, so the hit (and on an exact tie,
/// the triangle) is the one the `Tri4`-by-`Tri4` loop reports. Leaves of two or more `Tri4`s take
/// half the passes.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn leaf_pairs<const ANY_HIT: bool>(
    r: &Avx2Ray,
    tri4s: &[Tri4],
    first: usize,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
) -> bool {
    let mut k = 0;
    while k < tri4s.len() {
        let (a, b) = (&tri4s[k], tri4s.get(k + 1));
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

/// [`Tri4::intersect`] for two `Tri4`s in one pass: the answer of testing `a` and then `b`
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
        // `b` is tested with the window shrunk to `a`'s hit, as the `Tri4` loop would.
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

#[cfg(test)]
mod tests {
    use super::super::{Avx2Nodes, splat_ray};
    use super::*;
    use crate::wide::kernels::intersect_tri4s;
    use raybench_geom::{MollerTriangle, Ray, Triangle, Vec3};

    type Answer = (bool, u32, Option<(usize, u32, u32, u32)>);

    /// The leaf's answer, best distance and best hit, bit for bit.
    fn answer(stop: bool, best_t: f32, best: Option<(usize, TriHit)>) -> Answer {
        let hit = best.map(|(i, h)| (i, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
        (stop, best_t.to_bits(), hit)
    }

    /// Pairs of `Tri4`s in one 8-lane pass answer exactly as the `Tri4`-by-`Tri4` loop: the
    /// same hit, distance and barycentrics bit for bit, and on exact ties (a triangle repeated
    /// in a later `Tri4`) the same lane, for leaves of one to five `Tri4`s, closest and any
    /// hit, with a best distance carried in from earlier leaves.
    #[test]
    fn pairs_answer_as_the_tri4_loop() {
        let Some(_) = Avx2Nodes::detect(false) else {
            eprintln!("no AVX2 on this CPU: the pair test has nothing to check");
            return;
        };
        let mut rng = raybench_geom::SplitMix64::new(0x1eaf);
        let (mut hits, mut ties) = (0, 0);
        for case in 0..20_000usize {
            let tri4s_used = 1 + case % 5;
            let mut tris: Vec<MollerTriangle> = Vec::new();
            for k in 0..tri4s_used * 4 - case % 4 {
                // Every third case repeats earlier triangles in later `Tri4`s: exact ties.
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
            let tri4s: Vec<Tri4> = tris
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
                    intersect_tri4s::<true>(&tri4s, first, &ray, &mut t, &mut best)
                } else {
                    intersect_tri4s::<false>(&tri4s, first, &ray, &mut t, &mut best)
                };
                answer(stop, t, best)
            };
            let run_pairs = |any: bool| {
                let (mut t, mut best) = (carried, None);
                // SAFETY: `detect` saw AVX2 above.
                let stop = unsafe {
                    if any {
                        leaf_pairs::<true>(&wide, &tri4s, first, &mut t, &mut best)
                    } else {
                        leaf_pairs::<false>(&wide, &tri4s, first, &mut t, &mut best)
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
            "{hits} hits, {ties} in later Tri4s"
        );
    }

    #[test]
    fn a_lone_tri4_leaves_the_upper_lanes_empty() {
        let Some(_) = Avx2Nodes::detect(false) else {
            return;
        };
        let tri = MollerTriangle::new(&Triangle::new(Vec3::X, Vec3::Y, Vec3::Z));
        let tri4 = Tri4::pack(&[(3, tri)]);
        let ray = Ray::new(Vec3::ZERO, Vec3::ONE, 0.0, f32::INFINITY);
        // SAFETY: `detect` saw AVX2 above.
        let hit = unsafe { test8(&splat_ray(&ray), &tri4, None, f32::INFINITY) };
        assert_eq!(hit.map(|(lane, _)| lane), Some(0));
        let miss = Ray::new(Vec3::splat(5.0), Vec3::ONE, 0.0, f32::INFINITY);
        // SAFETY: as above.
        assert!(unsafe { test8(&splat_ray(&miss), &tri4, None, f32::INFINITY) }.is_none());
    }
}
