//! Carrying out a spatial split: every reference entirely on one side of the plane goes to that
//! side; one that crosses it is either cut in two (one piece per side, each with its clipped
//! box) or, when that is cheaper by the SAH, kept whole on one side ("reference unsplitting",
//! Stich, Friedrich and Dietrich 2009, section 4.3): a large box that barely crosses the plane
//! costs less as one reference than as two. Unsplitting is decided reference by reference in
//! array order, against the children as the binning estimated them, so it is deterministic.
//! A reference already cut `max_cuts` times from its triangle is not cut again but kept whole
//! on the cheaper side: a triangle spanning the scene (a city's ground) would otherwise be cut
//! at nearly every node down to the leaves, a thousand pieces of one triangle filling the
//! budget and the leaves with references a ray tests one after another.

use super::bins::SpatialSplit;
use super::chop::{corners, is_empty, split_at};
use crate::build::PrimRef;
use raybench_geom::TriangleMesh;

/// Splits `refs` at `s` into `left` and `right` (cleared first, so a task's vectors serve
/// every node it builds) and returns how many references the split added; `None` when a side
/// would be left empty (the binning estimate and the exact cut can disagree by a rounding at
/// the plane), and the caller keeps the object split.
pub(crate) fn divide(
    refs: &[PrimRef],
    mesh: &TriangleMesh,
    s: &SpatialSplit,
    max_cuts: u32,
    left: &mut Vec<PrimRef>,
    right: &mut Vec<PrimRef>,
) -> Option<usize> {
    let (axis, pos) = (s.axis, s.pos);
    let (mut left_box, mut right_box) = (s.left, s.right);
    let (mut nl, mut nr) = (s.left_count as f64, s.right_count as f64);
    left.clear();
    right.clear();
    let mut duplicates = 0;
    for r in refs {
        let b = r.bounds();
        // A reference flat in the plane goes right, as the binning counted it (the plane is
        // the lower face of its slab).
        if b.lo[axis] >= pos {
            right.push(*r);
            continue;
        }
        if b.hi[axis] <= pos {
            left.push(*r);
            continue;
        }
        let (lp, rp) = split_at(&corners(&mesh.triangle(r.id() as usize)), axis, pos, &b);
        if is_empty(&rp) {
            left.push(*r);
            continue;
        }
        if is_empty(&lp) {
            right.push(*r);
            continue;
        }
        // The SAH numerators (area × references) of cutting it, or keeping it whole left or
        // right (the other side then has one reference less).
        let (al, ar) = (left_box.half_area(), right_box.half_area());
        let (whole_left, whole_right) = (left_box.union(&b), right_box.union(&b));
        let cut = al * nl + ar * nr;
        let keep_left = whole_left.half_area() * nl + ar * (nr - 1.0);
        let keep_right = al * (nl - 1.0) + whole_right.half_area() * nr;
        let capped = r.cuts() >= max_cuts;
        if (capped || keep_left < cut) && keep_left <= keep_right {
            left.push(*r);
            left_box = whole_left;
            nr -= 1.0;
        } else if capped || keep_right < cut {
            right.push(*r);
            right_box = whole_right;
            nl -= 1.0;
        } else {
            let cuts = r.cuts() + 1;
            left.push(PrimRef::piece(&lp.to_aabb(), r.id(), cuts));
            right.push(PrimRef::piece(&rp.to_aabb(), r.id(), cuts));
            duplicates += 1;
        }
    }
    if left.is_empty() || right.is_empty() {
        return None;
    }
    Some(duplicates)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WideParams;
    use crate::build::spatial::bins::tests::limits;
    use crate::build::spatial::bins::{SlabBins, best_spatial_split};
    use crate::build::spatial::chop::box_of;
    use raybench_geom::Vec3;

    /// A fan of long thin triangles crossing the unit cube along x, one per row: every plane
    /// across x cuts every triangle.
    fn fibres(n: usize) -> TriangleMesh {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for i in 0..n {
            let y = i as f32 / n as f32;
            let base = vertices.len() as u32;
            vertices.push(Vec3::new(0.0, y, 0.0));
            vertices.push(Vec3::new(1.0, y + 0.5, 1.0));
            vertices.push(Vec3::new(1.0, y + 0.501, 1.0));
            indices.push([base, base + 1, base + 2]);
        }
        TriangleMesh::new(vertices, indices)
            .expect("a valid mesh")
            .0
    }

    fn refs_of(mesh: &TriangleMesh) -> Vec<PrimRef> {
        (0..mesh.len())
            .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
            .collect()
    }

    #[test]
    fn cutting_diagonal_fibres_duplicates_each_within_the_budget() {
        let mesh = fibres(64);
        let refs = refs_of(&mesh);
        let bounds = box_of(&mesh.bounds());
        let p = WideParams::default().binary;
        let mut bins = SlabBins::new();
        let s = best_spatial_split(&refs, &mesh, &bounds, &p, limits(64, None), &mut bins)
            .expect("a plane");
        let (mut left, mut right) = (Vec::new(), Vec::new());
        let duplicates = divide(&refs, &mesh, &s, 64, &mut left, &mut right).expect("both sides");
        assert_eq!(left.len() + right.len(), refs.len() + duplicates);
        assert!(duplicates > 0 && duplicates <= 64);
        // Each piece lies within its triangle's box and on its side of the plane.
        for (side, pieces) in [(0, &left), (1, &right)] {
            for r in pieces.iter() {
                let b = r.bounds();
                let tri = box_of(&mesh.triangle(r.id() as usize).bounds());
                assert!(b.lo.cmpge(tri.lo).all() && b.hi.cmple(tri.hi).all());
                if side == 0 {
                    assert!(b.hi[s.axis] <= s.pos);
                } else {
                    assert!(b.lo[s.axis] >= s.pos);
                }
            }
        }
        // No budget: no plane that cuts a reference is a candidate.
        let none = best_spatial_split(&refs, &mesh, &bounds, &p, limits(0, None), &mut bins);
        assert!(none.is_none_or(|s| s.left_count + s.right_count == refs.len()));
    }
}
