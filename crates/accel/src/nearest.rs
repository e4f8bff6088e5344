//! [`Nearest`]: the state of one closest-point search, shared by every structure so that all
//! of them (and Embree's callback) accept exactly the same triangles.

use crate::{CounterSink, Mailbox, PointHit};
use raybench_geom::{
    Triangle, TriangleMesh, Vec3, closest_point_on_triangle, query_radius_squared,
};

/// The nearest triangle found so far and the squared distance that prunes the search.
///
/// The radius is inclusive; among equally near triangles the lowest primitive index wins,
/// whatever order a structure meets them in, so every structure that visits all candidates
/// no farther than the best answers bit-identically to brute force.
#[derive(Clone, Copy, Debug)]
pub struct Nearest {
    /// Squared distance of the best triangle, or the squared radius while there is none.
    d2: f32,
    /// Primitive index and nearest point of the best triangle.
    found: Option<(u32, Vec3)>,
}

impl Nearest {
    /// Nothing found yet, within `max_radius` of `p`; `None` for a query that has no answer
    /// by definition (see [`query_radius_squared`]: non-finite or huge point, negative or NaN
    /// radius).
    #[inline]
    pub fn within(p: Vec3, max_radius: f32) -> Option<Nearest> {
        Some(Nearest {
            d2: query_radius_squared(p, max_radius)?,
            found: None,
        })
    }

    /// The squared distance beyond which nothing can be accepted: a box or cell strictly
    /// farther than this can be skipped (one exactly this far may still hold a tie).
    #[inline(always)]
    pub fn bound_d2(&self) -> f32 {
        self.d2
    }

    /// Keeps `prim` (whose nearest point is `point`, at squared distance `d2`) if it is
    /// nearer, or as near with a lower index. Returns true when it was kept.
    #[inline(always)]
    pub fn offer(&mut self, prim: u32, point: Vec3, d2: f32) -> bool {
        let better = match self.found {
            None => d2 <= self.d2,
            Some((best, _)) => d2 < self.d2 || (d2 == self.d2 && prim < best),
        };
        if better {
            self.d2 = d2;
            self.found = Some((prim, point));
        }
        better
    }

    /// Computes the nearest point of `tri` to `p` and offers it (one point–triangle test).
    #[inline(always)]
    pub fn test_triangle(&mut self, p: Vec3, prim: u32, tri: &Triangle) -> bool {
        let point = closest_point_on_triangle(p, tri);
        self.offer(prim, point, point.distance_squared(p))
    }

    /// Offers every mesh triangle of `prims` that `mailbox` has not met yet in this query:
    /// one counted point–triangle test each, and a counted mailbox skip for each one met
    /// already. For structures that reference a triangle from several cells or leaves by its
    /// mesh index (grid, octree); triangles are read from the mesh, as Embree's point-query
    /// callback reads them, so the distances are brute force's.
    #[inline(always)]
    pub fn test_unseen<const N: usize, C: CounterSink>(
        &mut self,
        p: Vec3,
        mesh: &TriangleMesh,
        prims: &[u32],
        mailbox: &mut Mailbox<N>,
        c: &mut C,
    ) {
        for &prim in prims {
            if mailbox.seen(prim) {
                c.mailbox_skip();
                continue;
            }
            c.prim_tests(1);
            self.test_triangle(p, prim, &mesh.triangle(prim as usize));
        }
    }

    /// True once a triangle has been kept.
    #[inline(always)]
    pub fn found(&self) -> bool {
        self.found.is_some()
    }

    /// The answer: `distance` is `sqrt(d2)`, i.e. `|point - p|` in f32.
    #[inline]
    pub fn into_hit(self) -> Option<PointHit> {
        let (prim, point) = self.found?;
        Some(PointHit {
            prim,
            point,
            distance: self.d2.sqrt(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_is_inclusive_and_ties_go_to_the_lowest_index() {
        let mut n = Nearest::within(Vec3::ZERO, 2.0).unwrap();
        assert!(!n.offer(9, Vec3::X, 4.5), "beyond the radius");
        assert!(n.offer(7, Vec3::X, 4.0), "exactly at the radius");
        assert!(!n.offer(8, Vec3::Y, 4.0), "a tie with a higher index");
        assert!(n.offer(3, Vec3::Z, 4.0), "a tie with a lower index");
        assert!(n.offer(5, Vec3::Y, 1.0), "nearer");
        assert_eq!(n.bound_d2(), 1.0);
        let hit = n.into_hit().unwrap();
        assert_eq!((hit.prim, hit.point, hit.distance), (5, Vec3::Y, 1.0));
    }

    #[test]
    fn invalid_queries_have_no_search() {
        assert!(Nearest::within(Vec3::NAN, 1.0).is_none());
        assert!(Nearest::within(Vec3::ZERO, -1.0).is_none());
        assert!(
            Nearest::within(Vec3::ZERO, 0.0)
                .unwrap()
                .into_hit()
                .is_none()
        );
    }

    #[test]
    fn test_triangle_measures_the_nearest_point() {
        let mut n = Nearest::within(Vec3::new(0.25, 0.25, 2.0), f32::INFINITY).unwrap();
        let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert!(n.test_triangle(Vec3::new(0.25, 0.25, 2.0), 4, &tri));
        assert!(n.found());
        assert_eq!(n.into_hit().map(|h| (h.prim, h.distance)), Some((4, 2.0)));
    }
}
