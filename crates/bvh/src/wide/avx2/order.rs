//! The closest-hit walk's child ordering for 8- and 16-wide nodes where a ray enters four or more
//! children, without a branch per child: the insertion of `walk::nearest_first` mispredicts on
//! such nodes, which are common where boxes overlap heavily (hair, triangle soups). The children
//! are sorted in a bitonic network on one register (Batcher 1968): six compare-exchange stages on
//! eight 32-bit keys in AVX2, ten on sixteen in AVX-512F.
//!
//! The keys are the entry distances' bits (non-negative floats order as integers; -0 is made +0)
//! with the slot in the low three (four) bits, and the children not entered get the largest key.
//! So the order is the insertion's — nearest first, equal distances lower slot first — except
//! that distances within 8 (16) ulps of each other also count as equal. The stack keeps each
//! child's exact distance, so the pops skip exactly what they skip after the insertion.
//!
//! The walk goes on with the nearest child alone; the others wait on the stack. So the nearest
//! is taken by a reduction of the keys to their minimum (three steps on eight keys, four on
//! sixteen) beside the network (six and ten stages): the next node's test waits for the
//! reduction only, and the network and the pushes run beside it (measured: see
//! docs/experiments.md, "the nearest of four or more entered children taken by a reduction").

use crate::node::ChildRef;
use crate::wide::walk::Stack;
use std::arch::x86_64::*;

/// One compare-exchange stage: lane `i` meets lane `perm[i]`, and the lanes set in `HI` keep
/// the larger key.
#[target_feature(enable = "avx2")]
#[inline]
fn stage<const HI: i32>(keys: __m256i, perm: __m256i) -> __m256i {
    let other = _mm256_permutevar8x32_epi32(keys, perm);
    let lo = _mm256_min_epu32(keys, other);
    let hi = _mm256_max_epu32(keys, other);
    _mm256_blend_epi32::<HI>(lo, hi)
}

/// The eight keys in ascending order.
#[target_feature(enable = "avx2")]
#[inline]
fn sort8(mut k: __m256i) -> __m256i {
    let neighbour = _mm256_setr_epi32(1, 0, 3, 2, 5, 4, 7, 6);
    // Sorted pairs, then sorted quadruples (a reversed compare, then a half cleaner), then the
    // eight (the same, twice as wide).
    k = stage::<0b1010_1010>(k, neighbour);
    k = stage::<0b1100_1100>(k, _mm256_setr_epi32(3, 2, 1, 0, 7, 6, 5, 4));
    k = stage::<0b1010_1010>(k, neighbour);
    k = stage::<0b1111_0000>(k, _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0));
    k = stage::<0b1100_1100>(k, _mm256_setr_epi32(2, 3, 0, 1, 6, 7, 4, 5));
    stage::<0b1010_1010>(k, neighbour)
}

/// `walk::nearest_first` for an 8-wide node through the network: returns the nearest child in
/// `mask` and pushes the others so that they pop nearest first.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn nearest_first_sorted<const W: usize>(
    child: &[ChildRef; W],
    mask: u32,
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    debug_assert!(W == 8 && mask != 0 && mask < 256);
    let e: &[f32; 8] = &entry.as_chunks::<8>().0[0];
    // SAFETY: a reference to 8 initialised f32s; `loadu` has no alignment requirement.
    let e = unsafe { _mm256_loadu_ps(e.as_ptr()) };
    // Adding +0 turns -0 (from a ray's `t_min` of -0) into +0, so every key is a non-negative
    // float's bits.
    let bits = _mm256_castps_si256(_mm256_add_ps(e, _mm256_setzero_ps()));
    let slots = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let keys = _mm256_or_si256(_mm256_andnot_si256(_mm256_set1_epi32(7), bits), slots);
    let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let entered = _mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_set1_epi32(mask as i32), lane_bits),
        lane_bits,
    );
    let keys = _mm256_blendv_epi8(_mm256_set1_epi32(-1), keys, entered);
    let nearest = min8(keys);
    let mut sorted = [0u32; 8];
    // SAFETY: `sorted` is 8 writable u32s; `storeu` has no alignment requirement.
    unsafe { _mm256_storeu_si256(sorted.as_mut_ptr().cast(), sort8(keys)) };
    push_sorted(
        &sorted[..mask.count_ones() as usize],
        child,
        entry,
        stack,
        sp,
    );
    child[(nearest & 7) as usize]
}

/// The smallest of eight keys, in three steps.
#[target_feature(enable = "avx2")]
#[inline]
fn min8(k: __m256i) -> u32 {
    let k = _mm256_min_epu32(k, _mm256_permute2x128_si256::<1>(k, k));
    let k = _mm256_min_epu32(k, _mm256_shuffle_epi32::<0b01_00_11_10>(k));
    let k = _mm256_min_epu32(k, _mm256_shuffle_epi32::<0b10_11_00_01>(k));
    _mm256_cvtsi256_si32(k) as u32
}

/// The children of the sorted keys `sorted` (the entered ones, nearest first; the slot in the
/// low bits, below `W`, a power of two): pushes all but the first so that they pop nearest
/// first. The first, which the walk takes next, the callers find by a reduction of their own.
#[inline(always)]
fn push_sorted<const W: usize>(
    sorted: &[u32],
    child: &[ChildRef; W],
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) {
    let slot_bits = (W - 1) as u32;
    for &key in sorted[1..].iter().rev() {
        let slot = (key & slot_bits) as usize;
        stack[*sp] = (child[slot], entry[slot]);
        *sp += 1;
    }
}

/// One compare-exchange stage on sixteen keys: lane `i` meets lane `perm[i]`, and the lanes set
/// in `hi` keep the larger key.
#[target_feature(enable = "avx2,avx512f")]
#[inline]
fn stage16(keys: __m512i, perm: __m512i, hi: __mmask16) -> __m512i {
    let other = _mm512_permutexvar_epi32(perm, keys);
    let lo = _mm512_min_epu32(keys, other);
    let high = _mm512_max_epu32(keys, other);
    _mm512_mask_blend_epi32(hi, lo, high)
}

/// The sixteen keys in ascending order: sorted pairs, quadruples, eights, then the sixteen, each
/// merge a reversed compare followed by half cleaners (as `sort8`, one size further).
#[target_feature(enable = "avx2,avx512f")]
#[inline]
fn sort16(mut k: __m512i) -> __m512i {
    let lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    let xor = |x: i32| _mm512_xor_si512(lanes, _mm512_set1_epi32(x));
    // Lane i meets lane i ^ x, x = 2^b (a half cleaner) or 2^(b+1) - 1 (a reversed compare); of
    // the two, the lane with bit b set keeps the larger key.
    const UPPER: [__mmask16; 4] = [0xaaaa, 0xcccc, 0xf0f0, 0xff00];
    for size in 1..=4 {
        k = stage16(k, xor((1 << size) - 1), UPPER[size - 1]);
        for b in (0..size - 1).rev() {
            k = stage16(k, xor(1 << b), UPPER[b]);
        }
    }
    k
}

/// `walk::nearest_first` for a 16-wide node through the sixteen-key network: returns the
/// nearest child in `mask` and pushes the others so that they pop nearest first.
#[target_feature(enable = "avx2,avx512f")]
#[inline]
pub(super) fn nearest_first_sorted16<const W: usize>(
    child: &[ChildRef; W],
    mask: u32,
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    assert!(W == 16, "a 16-key sort of a {W}-wide node");
    debug_assert!(mask != 0 && mask < 1 << 16);
    // SAFETY: W is 16 (asserted above): 16 initialised f32s; `loadu` has no alignment requirement.
    let e = unsafe { _mm512_loadu_ps(entry.as_ptr()) };
    // +0 turns -0 into +0, so every key is a non-negative float's bits.
    let bits = _mm512_castps_si512(_mm512_add_ps(e, _mm512_setzero_ps()));
    let slots = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    let keys = _mm512_or_si512(_mm512_andnot_si512(_mm512_set1_epi32(15), bits), slots);
    let keys = _mm512_mask_mov_epi32(_mm512_set1_epi32(-1), mask as __mmask16, keys);
    let nearest = _mm512_reduce_min_epu32(keys);
    let mut sorted = [0u32; 16];
    // SAFETY: `sorted` is 16 writable u32s; `storeu` has no alignment requirement.
    unsafe { _mm512_storeu_si512(sorted.as_mut_ptr().cast(), sort16(keys)) };
    push_sorted(
        &sorted[..mask.count_ones() as usize],
        child,
        entry,
        stack,
        sp,
    );
    child[(nearest & 15) as usize]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wide::walk::check_against_insertion;

    /// Every mask of four or more children: the network orders as the insertion (distances
    /// within 8 ulps of each other never occur in the check, so the orders must be identical).
    #[test]
    fn the_network_orders_as_the_insertion() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let masks = (1u32..256).filter(|m| m.count_ones() >= 4);
        let checked = check_against_insertion::<8>(masks, |child, mask, entry, stack, sp| {
            // SAFETY: AVX2 was detected above.
            unsafe { nearest_first_sorted(child, mask, entry, stack, sp) }
        });
        assert_eq!(checked, 163 * 25);
    }

    /// Masks of sixteen children with four or more set (every 7th, all counts from 4 to 16
    /// among them), likewise.
    #[test]
    fn the_sixteen_key_network_orders_as_the_insertion() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            eprintln!("no AVX-512F on this CPU: nothing to compare");
            return;
        }
        let masks = (1u32..1 << 16)
            .step_by(7)
            .chain([0xffff])
            .filter(|m| m.count_ones() >= 4);
        let checked = check_against_insertion::<16>(masks, |child, mask, entry, stack, sp| {
            // SAFETY: AVX-512F (and so AVX2) was detected above.
            unsafe { nearest_first_sorted16(child, mask, entry, stack, sp) }
        });
        assert!(checked > 8_000 * 25, "{checked}");
    }
}
