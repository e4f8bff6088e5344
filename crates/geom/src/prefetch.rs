//! A cache hint shared by the walks: start fetching the lines of a value a walk will soon
//! read, so the fetch overlaps the work before it.
#![allow(unsafe_code)]

/// Starts fetching every cache line of the `T` at `p` into all cache levels. A hint only: it
/// never dereferences `p` and never faults, whatever `p` is.
#[inline(always)]
pub fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    for k in 0..std::mem::size_of::<T>().div_ceil(64) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // `wrapping_add` keeps the address computation defined even past the allocation.
        let line = p.cast::<i8>().wrapping_add(64 * k);
        // SAFETY: prefetch is a hint that never dereferences or faults, and SSE is baseline.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(line) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
