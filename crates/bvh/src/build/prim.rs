//! The builder's working set: one 32-byte record per triangle (its box, with the triangle's id
//! and, for a piece of a triangle, how often it was cut riding in the spare lanes), and SIMD
//! boxes for bins and ranges.

use glam::{Vec3A, Vec4};
use raybench_geom::{Aabb, Vec3};

/// A triangle's bounding box with its mesh index in the fourth lane of `lo` (as raw bits, with
/// bit 30 set so the lane is never a denormal float: arithmetic on the box also touches the
/// spare lane, and denormal operands can be slow).
/// Split functions partition and sort an array of these in place: each node owns a contiguous
/// range, and moving the box with the id keeps every pass over a range sequential in memory
/// (an index array into a separate box array made every pass a random gather).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

impl PrimRef {
    pub(crate) fn new(bounds: &Aabb, id: u32) -> PrimRef {
        PrimRef::piece(bounds, id, 0)
    }

    /// A reference to the part of triangle `id` inside `bounds`, made by `cuts` cuts.
    pub(crate) fn piece(bounds: &Aabb, id: u32, cuts: u32) -> PrimRef {
        debug_assert!(cuts <= MAX_CUTS);
        PrimRef {
            lo: bounds.min.extend(f32::from_bits(id | ID_TAG)),
            hi: bounds.max.extend(cuts as f32),
        }
    }

    /// How many cuts made this reference out of its triangle: its piece is one of at most
    /// `2^cuts` the triangle has.
    #[inline(always)]
    pub(crate) fn cuts(&self) -> u32 {
        self.hi.w as u32
    }

    #[inline(always)]
    pub(crate) fn id(&self) -> u32 {
        self.lo.w.to_bits() & !ID_TAG
    }

    #[inline(always)]
    pub(crate) fn bounds(&self) -> Box3 {
        Box3 {
            lo: Vec3A::from_vec4(self.lo),
            hi: Vec3A::from_vec4(self.hi),
        }
    }

    /// Twice the centroid of the box (`lo + hi`): the halving is left out of every split
    /// decision, which only compares centroids with each other.
    #[inline(always)]
    pub(crate) fn centroid2(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo) + Vec3A::from_vec4(self.hi)
    }

    /// Lane `axis` of [`PrimRef::centroid2`], in scalar (the same sum).
    #[inline(always)]
    pub(crate) fn centroid2_on(&self, axis: usize) -> f32 {
        self.lo[axis] + self.hi[axis]
    }
}

const ID_TAG: u32 = 1 << 30;

/// The most cuts a reference's count can hold exactly (a whole float up to 2^24 would do; a
/// lineage of cuts is never deeper than the tree).
pub(crate) const MAX_CUTS: u32 = 64;

/// The largest mesh the id encoding can hold.
pub(crate) const MAX_PRIMS: usize = 1 << 30;

/// An axis-aligned box in SIMD lanes; `lo > hi` means empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Box3 {
    pub lo: Vec3A,
    pub hi: Vec3A,
}

impl Box3 {
    pub(crate) const EMPTY: Box3 = Box3 {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    #[must_use]
    pub(crate) fn union(&self, o: &Box3) -> Box3 {
        Box3 {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    #[inline(always)]
    #[must_use]
    pub(crate) fn grow(&self, p: Vec3A) -> Box3 {
        Box3 {
            lo: self.lo.min(p),
            hi: self.hi.max(p),
        }
    }

    /// Extent per axis, zero for an empty box.
    #[inline(always)]
    pub(crate) fn extent(&self) -> Vec3A {
        (self.hi - self.lo).max(Vec3A::ZERO)
    }

    /// Half the surface area, as the SAH compares areas only with each other. In f64: with
    /// coordinates up to the mesh limit of 1.8e18 the products would still fit in f32, but the
    /// area-weighted counts the builder sums would not.
    #[inline(always)]
    pub(crate) fn half_area(&self) -> f64 {
        let e = self.extent().as_dvec3();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The bounds of the (doubled) centroids of `refs`, in one pass (on rayon at or above
    /// `parallel`; min and max give the same box in any order).
    pub(crate) fn centroids_of(refs: &[PrimRef], parallel: usize) -> Box3 {
        use rayon::prelude::*;
        let fold = |b: Box3, p: &PrimRef| b.grow(p.centroid2());
        if refs.len() >= parallel {
            refs.par_chunks(8192)
                .map(|c| c.iter().fold(Box3::EMPTY, fold))
                .reduce(|| Box3::EMPTY, |a, b| a.union(&b))
        } else {
            refs.iter().fold(Box3::EMPTY, fold)
        }
    }

    pub(crate) fn to_aabb(self) -> Aabb {
        if self.lo.cmpgt(self.hi).any() {
            return Aabb::EMPTY;
        }
        Aabb::new(Vec3::from(self.lo), Vec3::from(self.hi))
    }
}

/// A range's triangle bounds and (doubled) centroid bounds, computed by whoever made it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ranged {
    pub bounds: Box3,
    pub centroids: Box3,
}

impl Ranged {
    pub(crate) const EMPTY: Ranged = Ranged {
        bounds: Box3::EMPTY,
        centroids: Box3::EMPTY,
    };

    #[inline(always)]
    pub(crate) fn add(&mut self, p: &PrimRef) {
        self.bounds = self.bounds.union(&p.bounds());
        self.centroids = self.centroids.grow(p.centroid2());
    }

    pub(crate) fn merge(a: Ranged, b: Ranged) -> Ranged {
        Ranged {
            bounds: a.bounds.union(&b.bounds),
            centroids: a.centroids.union(&b.centroids),
        }
    }

    /// One pass over `refs` (on rayon above `parallel`).
    pub(crate) fn of(refs: &[PrimRef], parallel: usize) -> Ranged {
        use rayon::prelude::*;
        let fold = |mut r: Ranged, p: &PrimRef| {
            r.add(p);
            r
        };
        if refs.len() >= parallel {
            refs.par_chunks(8192)
                .map(|c| c.iter().fold(Ranged::EMPTY, fold))
                .reduce(|| Ranged::EMPTY, Ranged::merge)
        } else {
            refs.iter().fold(Ranged::EMPTY, fold)
        }
    }
}
