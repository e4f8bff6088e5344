//! The closest-hit walk's child ordering for 8-wide nodes where a ray enters four or more
//! children, without a branch per child: the insertion of `walk::nearest_first` mispredicts on
//! such nodes, which are common where boxes overlap heavily (hair, triangle soups). The children
//! are sorted in a bitonic network on one AVX2 register (Batcher 1968): six compare-exchange
//! stages on eight 32-bit keys.
//!
//! The keys are the entry distances' bits (non-negative floats order as integers; -0 is made +0)
//! with the slot in the low three bits, and the children not entered get the largest key. So the
//! order is the insertion's — nearest first, equal distances lower slot first — except that
//! distances within 8 ulps of each other also count as equal. The stack keeps each child's exact
//! distance, so the pops skip exactly what they skip after the insertion.

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
    let mut sorted = [0u32; 8];
    // SAFETY: `sorted` is 8 writable u32s; `storeu` has no alignment requirement.
    unsafe { _mm256_storeu_si256(sorted.as_mut_ptr().cast(), sort8(keys)) };
    let count = mask.count_ones() as usize;
    for &key in sorted[1..count].iter().rev() {
        let slot = (key & 7) as usize;
        stack[*sp] = (child[slot], entry[slot]);
        *sp += 1;
    }
    child[(sorted[0] & 7) as usize]
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
        let checked = check_against_insertion(4..=8, |child, mask, entry, stack, sp| {
            // SAFETY: AVX2 was detected above.
            unsafe { nearest_first_sorted(child, mask, entry, stack, sp) }
        });
        assert_eq!(checked, 163 * 25);
    }
}
