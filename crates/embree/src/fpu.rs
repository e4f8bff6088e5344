//! The SSE control register (MXCSR) of the calling thread: its flush-to-zero (FTZ, bit 15) and
//! denormals-are-zero (DAZ, bit 6) modes.
//!
//! Embree recommends FTZ/DAZ on every thread that traces rays; they also change our own
//! kernels' results and speed. The harness therefore sets one state on *every* worker thread
//! (Embree's and ours alike) and records it; the default, as on any fresh thread, is off.
//! MXCSR is per thread, so these functions affect only the thread that calls them.
//!
//! Caveat: LLVM assumes the default floating-point environment; constant folding done at
//! compile time keeps IEEE denormals whatever is set here. Only run-time arithmetic changes.
//! On targets other than x86_64 these are no-ops reporting 0 / off.

/// FTZ: results that would be denormal become zero.
pub const FTZ_BIT: u32 = 1 << 15;
/// DAZ: denormal inputs are read as zero.
pub const DAZ_BIT: u32 = 1 << 6;

/// The sticky exception-status bits (invalid, denormal, divide-by-zero, overflow, underflow,
/// precision): arithmetic sets them, so they are not part of the mode.
pub const EXCEPTION_FLAGS: u32 = 0x3F;

/// The calling thread's MXCSR (0 off x86_64).
pub fn mxcsr() -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        let mut value: u32 = 0;
        // SAFETY: stmxcsr only stores the 32-bit register to `value`, a valid, writable,
        // 4-byte location on our stack; it changes no flags and touches nothing else.
        unsafe {
            std::arch::asm!(
                "stmxcsr [{ptr}]",
                ptr = in(reg) &mut value,
                options(nostack, preserves_flags)
            );
        }
        value
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        0
    }
}

/// Turns FTZ and DAZ both on or both off for the calling thread, leaving every other MXCSR
/// bit (rounding mode, exception masks) as it was.
pub fn set_ftz_daz(on: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        let bits = FTZ_BIT | DAZ_BIT;
        let value = if on { mxcsr() | bits } else { mxcsr() & !bits };
        // SAFETY: ldmxcsr reads 4 bytes from `value`, which lives on our stack. The new value
        // differs from the current one only in FTZ/DAZ, so no reserved bit is set (which would
        // fault) and no floating-point exception gets unmasked.
        unsafe {
            std::arch::asm!(
                "ldmxcsr [{ptr}]",
                ptr = in(reg) &value,
                options(nostack, preserves_flags, readonly)
            );
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = on;
    }
}

/// `(ftz, daz)` of the calling thread.
pub fn ftz_daz() -> (bool, bool) {
    let value = mxcsr();
    (value & FTZ_BIT != 0, value & DAZ_BIT != 0)
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    #[test]
    fn round_trip_on_a_fresh_thread() {
        std::thread::spawn(|| {
            let initial = mxcsr();
            assert_eq!(
                ftz_daz(),
                (false, false),
                "fresh threads start without FTZ/DAZ"
            );
            set_ftz_daz(true);
            assert_eq!(ftz_daz(), (true, true));
            assert_eq!(mxcsr(), initial | FTZ_BIT | DAZ_BIT, "other bits untouched");
            // Denormal arithmetic now flushes: the smallest normal halved becomes 0.
            let tiny = std::hint::black_box(f32::MIN_POSITIVE);
            assert_eq!(std::hint::black_box(tiny * 0.5), 0.0);
            set_ftz_daz(false);
            assert_eq!(ftz_daz(), (false, false));
            // Bits 0-5 are sticky exception flags, which the flushed multiply just raised.
            let control = |m: u32| m & !EXCEPTION_FLAGS;
            assert_eq!(control(mxcsr()), control(initial));
            assert!(std::hint::black_box(tiny) * 0.5 > 0.0);
        })
        .join()
        .unwrap();
        assert_eq!(ftz_daz(), (false, false), "other threads are unaffected");
    }
}
