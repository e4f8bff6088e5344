//! Four f32 lanes with SSE semantics, for testing both children's boxes of a node at once.
//!
//! On x86-64 these are single SSE instructions (SSE and SSE2 are part of the x86-64 baseline,
//! so no run-time detection is needed); elsewhere a portable version with the same semantics,
//! lane for lane, so both pass the same conformance tests. The semantics that matter:
//! [`F4::max_keep`] returns its second operand when either is NaN (`maxps`), which is how the
//! slab test ignores the `0 * inf` of a ray lying in a box's face plane (docs/validation.md, B1).

#[cfg(target_arch = "x86_64")]
mod imp {
    use std::arch::x86_64::*;

    #[derive(Clone, Copy, Debug)]
    pub struct F4(__m128);

    impl F4 {
        #[inline(always)]
        pub fn new(a: f32, b: f32, c: f32, d: f32) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; the intrinsic only builds a value.
            F4(unsafe { _mm_setr_ps(a, b, c, d) })
        }

        #[inline(always)]
        pub fn splat(a: f32) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; the intrinsic only builds a value.
            F4(unsafe { _mm_set1_ps(a) })
        }

        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            // SAFETY: SSE is baseline on x86-64, and the pointer comes from a reference to four
            // initialised f32s; `loadu` has no alignment requirement.
            F4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }

        #[inline(always)]
        pub fn sub(self, o: F4) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only arithmetic.
            F4(unsafe { _mm_sub_ps(self.0, o.0) })
        }

        #[inline(always)]
        pub fn mul(self, o: F4) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only arithmetic.
            F4(unsafe { _mm_mul_ps(self.0, o.0) })
        }

        /// Lane-wise `if self > keep { self } else { keep }`: `keep` wins when either is NaN.
        #[inline(always)]
        pub fn max_keep(self, keep: F4) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only arithmetic.
            F4(unsafe { _mm_max_ps(self.0, keep.0) })
        }

        /// Lane-wise `if self < keep { self } else { keep }`: `keep` wins when either is NaN.
        #[inline(always)]
        pub fn min_keep(self, keep: F4) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only arithmetic.
            F4(unsafe { _mm_min_ps(self.0, keep.0) })
        }

        /// `[c, d, a, b]` from `[a, b, c, d]`.
        #[inline(always)]
        pub fn swap_halves(self) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only shuffle.
            F4(unsafe { _mm_shuffle_ps::<0b01_00_11_10>(self.0, self.0) })
        }

        #[inline(always)]
        pub fn neg(self) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; flips the sign bits only.
            F4(unsafe { _mm_xor_ps(self.0, _mm_set1_ps(-0.0)) })
        }

        /// Bit `i` set when lane `i` of `self <= o` (false on NaN).
        #[inline(always)]
        pub fn le_mask(self, o: F4) -> u32 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only compare.
            unsafe { _mm_movemask_ps(_mm_cmple_ps(self.0, o.0)) as u32 }
        }

        #[inline(always)]
        pub fn add(self, o: F4) -> F4 {
            // SAFETY: SSE is enabled on every x86-64 target; register-only arithmetic.
            F4(unsafe { _mm_add_ps(self.0, o.0) })
        }

        /// Lanes truncated towards zero to integers. Only for lanes known to lie within the
        /// i32 range (others become `i32::MIN`, `cvttps2dq`'s "indefinite" value).
        #[inline(always)]
        pub fn trunc_i32(self) -> [i32; 4] {
            let mut out = [0i32; 4];
            // SAFETY: SSE2 is baseline on x86-64; `out` is 16 writable bytes (unaligned store).
            unsafe { _mm_storeu_si128(out.as_mut_ptr().cast(), _mm_cvttps_epi32(self.0)) };
            out
        }

        #[inline(always)]
        pub fn from_vec3a(v: glam::Vec3A) -> F4 {
            F4(v.into())
        }

        /// The four lanes of an SSE register (for the AVX2 kernels' 4-lane work).
        #[inline(always)]
        pub fn from_m128(v: __m128) -> F4 {
            F4(v)
        }

        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            let mut out = [0.0f32; 4];
            // SAFETY: SSE is baseline on x86-64; `out` is four writable f32s (unaligned store).
            unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) };
            out
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    #[derive(Clone, Copy, Debug)]
    pub struct F4([f32; 4]);

    impl F4 {
        #[inline(always)]
        pub fn new(a: f32, b: f32, c: f32, d: f32) -> F4 {
            F4([a, b, c, d])
        }
        #[inline(always)]
        pub fn splat(a: f32) -> F4 {
            F4([a; 4])
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            F4(*a)
        }
        #[inline(always)]
        pub fn sub(self, o: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] - o.0[i]))
        }
        #[inline(always)]
        pub fn mul(self, o: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] * o.0[i]))
        }
        #[inline(always)]
        pub fn max_keep(self, keep: F4) -> F4 {
            F4(std::array::from_fn(|i| {
                if self.0[i] > keep.0[i] {
                    self.0[i]
                } else {
                    keep.0[i]
                }
            }))
        }
        #[inline(always)]
        pub fn min_keep(self, keep: F4) -> F4 {
            F4(std::array::from_fn(|i| {
                if self.0[i] < keep.0[i] {
                    self.0[i]
                } else {
                    keep.0[i]
                }
            }))
        }
        #[inline(always)]
        pub fn swap_halves(self) -> F4 {
            let [a, b, c, d] = self.0;
            F4([c, d, a, b])
        }
        #[inline(always)]
        pub fn neg(self) -> F4 {
            F4(self.0.map(|x| -x))
        }
        #[inline(always)]
        pub fn le_mask(self, o: F4) -> u32 {
            (0..4).map(|i| ((self.0[i] <= o.0[i]) as u32) << i).sum()
        }
        #[inline(always)]
        pub fn add(self, o: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] + o.0[i]))
        }
        #[inline(always)]
        pub fn trunc_i32(self) -> [i32; 4] {
            self.0.map(|x| x as i32)
        }
        #[inline(always)]
        pub fn from_vec3a(v: glam::Vec3A) -> F4 {
            F4([v.x, v.y, v.z, 0.0])
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            self.0
        }
    }
}

pub(crate) use imp::F4;

pub(crate) use raybench_geom::prefetch;

#[cfg(test)]
mod tests {
    use super::F4;

    #[test]
    fn max_keep_ignores_nan_in_the_first_operand_only() {
        let m = F4::new(f32::NAN, 1.0, 3.0, -0.0)
            .max_keep(F4::new(2.0, f32::NAN, 2.0, 0.0))
            .to_array();
        assert_eq!(m[0], 2.0);
        assert!(m[1].is_nan());
        assert_eq!(m[2], 3.0);
        assert_eq!(
            m[3].to_bits(),
            0.0f32.to_bits(),
            "ties keep the second operand"
        );
    }

    #[test]
    fn lanes_move_and_compare_as_documented() {
        let v = F4::new(1.0, 2.0, 3.0, 4.0);
        assert_eq!(v.swap_halves().to_array(), [3.0, 4.0, 1.0, 2.0]);
        assert_eq!(v.neg().to_array(), [-1.0, -2.0, -3.0, -4.0]);
        assert_eq!(F4::new(0.0, 0.99, 7.5, 31.0).trunc_i32(), [0, 0, 7, 31]);
        assert_eq!(v.le_mask(F4::new(1.0, 1.0, f32::NAN, 5.0)), 0b1001);
        assert_eq!(
            F4::load(&[5.0, 6.0, 7.0, 8.0])
                .sub(F4::splat(1.0))
                .mul(F4::splat(2.0))
                .to_array(),
            [8.0, 10.0, 12.0, 14.0]
        );
    }
}
