//! raybench's ray in tinybvh's layout, and tinybvh's hit record back in raybench's terms.
//!
//! tinybvh's rays have no `t_min`: a traversal accepts hits in `[0, hit.t]` (the Wald BVH's
//! scalar test) or `(0, hit.t)` (BVH8_CPU's four-wide test). A ray with `t_min > 0` therefore
//! starts at `origin + t_min·dir` with `t_max - t_min`, and `t_min` is added back to the hit:
//! two extra roundings, so such hits agree with Embree within tolerance rather than bit for bit.
//! Directions are passed as they are (tinybvh's own `Ray` constructor normalises, which would
//! rescale `t`); the reciprocal follows tinybvh's rule (±1e30 for |d| <= 1e-12). Whether the
//! ray hit is told by the primitive field, set to an impossible index before the call, because
//! a hit at exactly the initial `hit.t` leaves `t` unchanged.

use raybench_accel::Hit;
use raybench_geom::Ray;
use tinybvh_rs::{INFINITE, Intersection};

/// The primitive index no mesh reaches: still there after a traversal means "no hit".
const NO_PRIM: u32 = u32::MAX;

/// tinybvh's C++ `Ray` is 128 bytes aligned to 64 (its hit record carries 64 bytes of user
/// data), while tinybvh-rs declares a 64-byte Rust `Ray` aligned to 16. The traversals read and
/// write only the first 64 bytes, but the C++ compiler may assume the full object: the ray is
/// therefore handed over inside a block of the C++ size and alignment.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct CppRay {
    pub(crate) ray: tinybvh_rs::Ray,
    _user_data: [u8; 64],
}

/// Size and alignment of tinybvh's `Ray` (sizeof/alignof measured with g++ 12, `-std=c++20
/// -march=native`, tinybvh 1.6.8 as bundled).
const _: () = assert!(size_of::<CppRay>() == 128 && align_of::<CppRay>() == 64);

/// tinybvh's reciprocal: ±1e30 (the sign of `x`, +0 counting as positive) for |x| <= 1e-12.
fn safe_rcp(x: f32) -> f32 {
    if !(-1e-12..=1e-12).contains(&x) {
        1.0 / x
    } else if x >= 0.0 {
        INFINITE
    } else {
        -INFINITE
    }
}

impl CppRay {
    /// The ray in tinybvh's layout with `hit.t` = `t_max` shifted by `t_min` (see the module
    /// note), or `None` for a ray that can hit nothing: non-finite origin or direction (tinybvh
    /// aborts the process on a NaN), or an empty `[t_min, t_max]`.
    /// `exclusive_t_max`: the traversal accepts only `t < hit.t`, so `hit.t` is moved one ulp up.
    #[inline]
    pub(crate) fn new(ray: &Ray, exclusive_t_max: bool) -> Option<CppRay> {
        let (o, d, t_min) = (ray.origin(), ray.dir(), ray.t_min());
        let empty = ray.t_max().partial_cmp(&t_min).is_none_or(|o| o.is_lt());
        if !o.is_finite() || !d.is_finite() || empty {
            return None;
        }
        let start = if t_min > 0.0 { o + d * t_min } else { o };
        let mut t_max = if t_min > 0.0 {
            ray.t_max() - t_min
        } else {
            ray.t_max()
        };
        if exclusive_t_max {
            t_max = t_max.next_up();
        }
        if !start.is_finite() {
            return None;
        }
        let ray = tinybvh_rs::Ray {
            origin: start.to_array(),
            dir: d.to_array(),
            r_d: [safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z)],
            hit: Intersection {
                t: t_max,
                u: 0.0,
                v: 0.0,
                prim: NO_PRIM,
            },
            ..Default::default()
        };
        Some(CppRay {
            ray,
            _user_data: [0; 64],
        })
    }

    /// The hit in raybench's terms (`t` measured from the original origin), if the traversal
    /// recorded one strictly above `t_min`: a hit at the shifted origin is at `t_min` itself,
    /// which raybench's `t_min < t` excludes.
    #[inline]
    pub(crate) fn hit(&self, original: &Ray) -> Option<Hit> {
        let h = self.ray.hit;
        if h.prim == NO_PRIM {
            return None;
        }
        let t_min = original.t_min();
        let t = if t_min > 0.0 { h.t + t_min } else { h.t };
        (t > t_min && t <= original.t_max()).then_some(Hit {
            t,
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    }
}
