use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Embree's `FLT_LARGE` (1.844e18): rays or vertices with a component beyond it are invalid to
/// Embree (rays abort the process on Debian's build; triangles are silently dropped).
pub const EMBREE_LARGE: f32 = 1.844e18;

/// A ray with the hit interval `t_min < t <= t_max` (Embree's default semantics).
///
/// The direction need not be normalised. The reciprocal direction is computed once here with
/// IEEE division, so a `+0` component gives `+inf` and a `-0` component gives `-inf`; the slab
/// test in [`crate::Aabb::intersect`] is written so these never turn into NaN decisions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    origin: Vec3,
    dir: Vec3,
    inv_dir: Vec3,
    t_min: f32,
    t_max: f32,
}

/// The serialisable form of a ray: exactly the four inputs, no derived state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct RayRepr {
    origin: [f32; 3],
    dir: [f32; 3],
    t_min: f32,
    t_max: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Ray {
        Ray {
            origin,
            dir,
            inv_dir: dir.recip(),
            t_min,
            t_max,
        }
    }

    /// A ray from `origin` along `dir` over `(0, inf]`.
    pub fn infinite(origin: Vec3, dir: Vec3) -> Ray {
        Ray::new(origin, dir, 0.0, f32::INFINITY)
    }

    #[inline(always)]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
    #[inline(always)]
    pub fn dir(&self) -> Vec3 {
        self.dir
    }
    /// `1 / dir` per component (`±inf` for `±0`).
    #[inline(always)]
    pub fn inv_dir(&self) -> Vec3 {
        self.inv_dir
    }
    #[inline(always)]
    pub fn t_min(&self) -> f32 {
        self.t_min
    }
    #[inline(always)]
    pub fn t_max(&self) -> f32 {
        self.t_max
    }

    /// The same ray with a different far end (used when a closer hit shrinks the interval).
    #[inline(always)]
    pub fn with_t_max(&self, t_max: f32) -> Ray {
        Ray { t_max, ..*self }
    }

    #[inline(always)]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// The exact bits of the four inputs, for reports and replay: origin xyz, dir xyz, t_min, t_max.
    pub fn to_bits(&self) -> [u32; 8] {
        let o = self.origin;
        let d = self.dir;
        [
            o.x.to_bits(),
            o.y.to_bits(),
            o.z.to_bits(),
            d.x.to_bits(),
            d.y.to_bits(),
            d.z.to_bits(),
            self.t_min.to_bits(),
            self.t_max.to_bits(),
        ]
    }

    pub fn from_bits(b: [u32; 8]) -> Ray {
        let f = |i: usize| f32::from_bits(b[i]);
        Ray::new(
            Vec3::new(f(0), f(1), f(2)),
            Vec3::new(f(3), f(4), f(5)),
            f(6),
            f(7),
        )
    }

    /// Checks the ray against the rules Debian's Embree enforces by aborting the process
    /// (`assert(ray.valid())`, `assert(tnear >= 0)`), plus a direction that stays non-zero
    /// under flush-to-zero (a component that is not zero or subnormal), which raybench treats as
    /// invalid input although Embree merely misses: the same ray must mean the same thing with
    /// and without `--ftz-daz`.
    pub fn check(&self) -> Result<(), RayError> {
        let comps = [
            ("origin.x", self.origin.x),
            ("origin.y", self.origin.y),
            ("origin.z", self.origin.z),
            ("dir.x", self.dir.x),
            ("dir.y", self.dir.y),
            ("dir.z", self.dir.z),
        ];
        for (name, v) in comps {
            if v.is_nan() {
                return Err(RayError::NaN(name));
            }
            if v.abs() > EMBREE_LARGE {
                return Err(RayError::TooLarge(name, v));
            }
        }
        if self.t_min.is_nan() {
            return Err(RayError::NaN("t_min"));
        }
        if self.t_max.is_nan() {
            return Err(RayError::NaN("t_max"));
        }
        // -0.0 is accepted by Embree (`-0.0 >= 0.0`), so compare rather than test the sign bit.
        if self.t_min < 0.0 {
            return Err(RayError::NegativeTMin(self.t_min));
        }
        if self.dir == Vec3::ZERO {
            return Err(RayError::ZeroDirection);
        }
        if self
            .dir
            .to_array()
            .iter()
            .all(|c| *c == 0.0 || c.is_subnormal())
        {
            return Err(RayError::SubnormalDirection);
        }
        Ok(())
    }
}

impl Serialize for Ray {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        RayRepr {
            origin: self.origin.to_array(),
            dir: self.dir.to_array(),
            t_min: self.t_min,
            t_max: self.t_max,
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Ray {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Ray, D::Error> {
        let r = RayRepr::deserialize(d)?;
        Ok(Ray::new(r.origin.into(), r.dir.into(), r.t_min, r.t_max))
    }
}

/// Why a ray may not be traced (it would abort Debian's Embree, or it has no direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayError {
    NaN(&'static str),
    TooLarge(&'static str, f32),
    NegativeTMin(f32),
    ZeroDirection,
    SubnormalDirection,
}

impl fmt::Display for RayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RayError::NaN(c) => write!(f, "{c} is NaN"),
            RayError::TooLarge(c, v) => {
                write!(
                    f,
                    "{c} = {v:e} is infinite or beyond Embree's limit {EMBREE_LARGE:e}"
                )
            }
            RayError::NegativeTMin(t) => write!(f, "t_min = {t:e} is negative"),
            RayError::ZeroDirection => write!(f, "direction is (0, 0, 0)"),
            RayError::SubnormalDirection => write!(
                f,
                "direction has no component above the subnormal range, so flush-to-zero makes \
                 it (0, 0, 0)"
            ),
        }
    }
}

impl std::error::Error for RayError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reciprocal_keeps_sign_of_zero() {
        let r = Ray::infinite(Vec3::ZERO, Vec3::new(0.0, -0.0, 2.0));
        assert_eq!(r.inv_dir().x, f32::INFINITY);
        assert_eq!(r.inv_dir().y, f32::NEG_INFINITY);
        assert_eq!(r.inv_dir().z, 0.5);
    }

    #[test]
    fn check_rejects_what_aborts_embree() {
        let ok = Ray::infinite(Vec3::ZERO, Vec3::X);
        assert_eq!(ok.check(), Ok(()));
        let neg_zero_tmin = Ray::new(Vec3::ZERO, Vec3::X, -0.0, 1.0);
        assert_eq!(neg_zero_tmin.check(), Ok(()));
        let bad = [
            Ray::infinite(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
            Ray::infinite(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0)),
            Ray::infinite(Vec3::new(0.0, 0.0, 1e19), Vec3::X),
            Ray::infinite(Vec3::ZERO, Vec3::new(1e19, 0.0, 0.0)),
            Ray::new(Vec3::ZERO, Vec3::X, -1.0, 1.0),
            Ray::new(Vec3::ZERO, Vec3::X, f32::NAN, 1.0),
            Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::NAN),
            Ray::infinite(Vec3::ZERO, Vec3::ZERO),
        ];
        for r in bad {
            assert!(r.check().is_err(), "{r:?} must be rejected");
        }
        // 1e18 is below Embree's limit and must be accepted.
        assert_eq!(
            Ray::infinite(Vec3::new(1e18, 0.0, 0.0), Vec3::X).check(),
            Ok(())
        );
        // Subnormal in every component is zero under flush-to-zero; one normal component is
        // enough.
        let tiny = Vec3::new(1e-40, -0.0, f32::from_bits(1));
        assert_eq!(
            Ray::infinite(Vec3::ZERO, tiny).check(),
            Err(RayError::SubnormalDirection)
        );
        let small = Vec3::new(f32::MIN_POSITIVE, 1e-40, 0.0);
        assert_eq!(Ray::infinite(Vec3::ZERO, small).check(), Ok(()));
    }

    #[test]
    fn bits_round_trip_exactly() {
        let r = Ray::new(
            Vec3::new(0.1, -0.0, 3.0),
            Vec3::new(1e-30, 2.0, -0.0),
            0.0,
            f32::INFINITY,
        );
        assert_eq!(Ray::from_bits(r.to_bits()).to_bits(), r.to_bits());
    }
}
