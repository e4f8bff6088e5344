use crate::{Ray, max_keep, min_keep};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Axis-aligned bounding box; `min > max` on any axis means empty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The identity of [`Aabb::union`]: contains nothing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grow(p))
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    #[must_use]
    pub fn grow(&self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[must_use]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Centre computed as `min/2 + max/2` so boxes near `±f32::MAX` do not overflow.
    pub fn center(&self) -> Vec3 {
        self.min * 0.5 + self.max * 0.5
    }

    /// Length of the diagonal (0 for an empty box).
    pub fn diagonal(&self) -> f32 {
        self.extent().length()
    }

    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// Surface area in f64 (SAH costs are summed over millions of nodes; f32 loses them).
    pub fn surface_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        // Extent in f64: `max - min` overflows f32 for boxes spanning +-3e38.
        let e = self.max.as_dvec3() - self.min.as_dvec3();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// True when `p` lies in the closed box.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when `other` lies in the closed box.
    pub fn contains_box(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.contains(other.min) && self.contains(other.max))
    }

    /// Scales the box about its centre by `1 + 2 * margin` (per side `margin` of the extent),
    /// with a floor so that flat or point boxes still grow.
    #[must_use]
    pub fn enlarged(&self, margin: f32) -> Aabb {
        let pad = (self.extent() * margin).max(Vec3::splat(self.diagonal().max(1.0) * margin));
        Aabb {
            min: self.min - pad,
            max: self.max + pad,
        }
    }

    /// Slab test over the closed interval `[ray.t_min, ray.t_max]`: the entry and exit distance,
    /// or `None`. Flat boxes are hit (`<=`), and axis-parallel rays are exact: for a zero
    /// direction component the near and far planes are chosen by the sign bit of `1/d`, so the
    /// only NaN possible is `0 * inf` when the origin lies exactly on that plane, and
    /// [`max_keep`]/[`min_keep`] then ignore it, which is the right answer (the ray stays inside
    /// the closed slab for every `t`).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<(f32, f32)> {
        self.intersect_interval(ray.origin(), ray.inv_dir(), ray.t_min(), ray.t_max())
    }

    #[inline(always)]
    pub fn intersect_interval(
        &self,
        origin: Vec3,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        let mut t0 = t_min;
        let mut t1 = t_max;
        for axis in 0..3 {
            let inv = inv_dir[axis];
            let (near, far) = if inv.is_sign_negative() {
                (self.max[axis], self.min[axis])
            } else {
                (self.min[axis], self.max[axis])
            };
            t0 = max_keep(t0, (near - origin[axis]) * inv);
            t1 = min_keep(t1, (far - origin[axis]) * inv);
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn oblique_ray_enters_and_leaves() {
        let r = Ray::infinite(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        assert_eq!(unit().intersect(&r), Some((1.0, 2.0)));
    }

    #[test]
    fn axis_parallel_ray_with_signed_zeros() {
        for dz in [0.0f32, -0.0] {
            for dy in [0.0f32, -0.0] {
                let inside = Ray::infinite(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, dy, dz));
                assert_eq!(unit().intersect(&inside), Some((1.0, 2.0)));
                let outside = Ray::infinite(Vec3::new(-1.0, 1.5, 0.5), Vec3::new(1.0, dy, dz));
                assert_eq!(unit().intersect(&outside), None);
            }
        }
    }

    #[test]
    fn origin_on_face_plane_with_zero_direction_is_inside() {
        // The 0 * inf case (docs/validation.md, B1): origin exactly on y = 0 and y = 1, dir.y = ±0.
        for y in [0.0f32, 1.0] {
            for dy in [0.0f32, -0.0] {
                let r = Ray::infinite(Vec3::new(-1.0, y, 0.5), Vec3::new(1.0, dy, 0.0));
                assert_eq!(unit().intersect(&r), Some((1.0, 2.0)), "y={y} dy={dy}");
            }
        }
    }

    #[test]
    fn flat_box_is_hit() {
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 0.5), Vec3::new(1.0, 1.0, 0.5));
        let r = Ray::infinite(Vec3::new(0.5, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(flat.intersect(&r), Some((1.5, 1.5)));
    }

    #[test]
    fn interval_limits_are_respected() {
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 0.0, 0.5);
        assert_eq!(unit().intersect(&r), None);
        let inside = Ray::new(Vec3::splat(0.5), Vec3::X, 0.0, f32::INFINITY);
        assert_eq!(unit().intersect(&inside), Some((0.0, 0.5)));
    }

    #[test]
    fn center_does_not_overflow() {
        let b = Aabb::new(Vec3::splat(-3e38), Vec3::splat(3e38));
        assert_eq!(b.center(), Vec3::ZERO);
        assert!(b.surface_area().is_finite());
    }

    #[test]
    fn empty_box() {
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let r = Ray::infinite(Vec3::ZERO, Vec3::X);
        assert_eq!(Aabb::EMPTY.intersect(&r), None);
    }
}
