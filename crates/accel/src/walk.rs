//! The one walk a structure writes, and the macro that turns it into [`crate::Accel`]'s six
//! query methods.
//!
//! Every structure answers closest hit and any hit, timed and counted, with one traversal loop
//! generic over "any hit" and a [`CounterSink`] (madmann91/bvh's `intersect<IsAnyHit>`), and
//! closest-point queries with one loop generic over the sink. [`Walk`] names those two loops;
//! [`walk_queries!`](crate::walk_queries) writes `intersect`, `occluded`, `intersect_counted`,
//! `occluded_counted`, `closest_point` and `closest_point_counted` on top of them, so the
//! forwarding exists once and the timed path is, by construction, the counted path with a
//! zero-sized sink.

use crate::{CounterSink, Hit, PointHit};
use raybench_geom::{Ray, Vec3};

/// A structure's traversal loops (see the module documentation).
pub trait Walk {
    /// Closest hit (`ANY_HIT = false`) or any hit (`true`: the first hit found ends the walk)
    /// within the ray's `(t_min, t_max]`, counting the work into `c`.
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit>;

    /// The triangle nearest to `p` within `max_radius` (inclusive), counting the work into
    /// `c`: the contract of [`crate::Accel::closest_point`].
    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit>;
}

/// Writes [`crate::Accel`]'s six query methods inside an `impl Accel for T` block, for a `T`
/// that implements [`Walk`].
#[macro_export]
macro_rules! walk_queries {
    () => {
        fn intersect(&self, ray: &$crate::geom::Ray) -> Option<$crate::Hit> {
            $crate::Walk::walk_ray::<false, _>(self, ray, &mut $crate::NoCount)
        }

        fn occluded(&self, ray: &$crate::geom::Ray) -> bool {
            $crate::Walk::walk_ray::<true, _>(self, ray, &mut $crate::NoCount).is_some()
        }

        fn intersect_counted(
            &self,
            ray: &$crate::geom::Ray,
            c: &mut $crate::Counters,
        ) -> Option<$crate::Hit> {
            $crate::Walk::walk_ray::<false, _>(self, ray, c)
        }

        fn occluded_counted(&self, ray: &$crate::geom::Ray, c: &mut $crate::Counters) -> bool {
            $crate::Walk::walk_ray::<true, _>(self, ray, c).is_some()
        }

        fn closest_point(
            &self,
            p: $crate::geom::Vec3,
            max_radius: f32,
        ) -> Option<$crate::PointHit> {
            $crate::Walk::walk_point(self, p, max_radius, &mut $crate::NoCount)
        }

        fn closest_point_counted(
            &self,
            p: $crate::geom::Vec3,
            max_radius: f32,
            c: &mut $crate::Counters,
        ) -> Option<$crate::PointHit> {
            $crate::Walk::walk_point(self, p, max_radius, c)
        }
    };
}
