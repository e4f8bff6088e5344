//! Method sets for structures whose inner walk raybench cannot see (Embree, the peer crates):
//! written once here, invoked inside their `impl Accel` blocks. A structure opts in by name,
//! so none of raybench's own structures can answer a counted query without counting by
//! accident.

/// Writes the three counted queries of [`crate::Accel`] as the timed ones, counting nothing,
/// and `has_counters` as false (reports then show no work per query for the structure).
#[macro_export]
macro_rules! uncounted_queries {
    () => {
        fn intersect_counted(
            &self,
            ray: &$crate::geom::Ray,
            _c: &mut $crate::Counters,
        ) -> Option<$crate::Hit> {
            $crate::Accel::intersect(self, ray)
        }

        fn occluded_counted(&self, ray: &$crate::geom::Ray, _c: &mut $crate::Counters) -> bool {
            $crate::Accel::occluded(self, ray)
        }

        fn closest_point_counted(
            &self,
            p: $crate::geom::Vec3,
            max_radius: f32,
            _c: &mut $crate::Counters,
        ) -> Option<$crate::PointHit> {
            $crate::Accel::closest_point(self, p, max_radius)
        }

        fn has_counters(&self) -> bool {
            false
        }
    };
}

/// Writes [`crate::Accel::closest_point`] as "no answer" and `offers_closest_point` as false,
/// for a structure that cannot answer closest-point queries: runs report those workloads as
/// "not offered" instead of timing them.
#[macro_export]
macro_rules! no_closest_point {
    () => {
        fn closest_point(
            &self,
            _p: $crate::geom::Vec3,
            _max_radius: f32,
        ) -> Option<$crate::PointHit> {
            None
        }

        fn offers_closest_point(&self) -> bool {
            false
        }
    };
}
