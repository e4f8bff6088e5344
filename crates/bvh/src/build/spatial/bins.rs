//! The search for the best spatial split of a node: per axis, `spatial_bins` equal slabs of the
//! node's box (not of its centroids), each reference chopped into the slabs it crosses (its
//! triangle clipped at the slab planes, [`split_estimate`]), counting where it enters and where
//! it leaves; then one sweep over the slab boundaries evaluates the SAH of cutting every
//! reference at that plane (Stich, Friedrich and Dietrich 2009, section 4.2). A boundary whose
//! cut would duplicate more references than the node's budget allows is not a candidate, and
//! the counts, taken first, tell which are: a reference is clipped only at the candidate planes
//! it crosses, since the sweep reads the slabs' boxes nowhere else. Nor is a plane a candidate
//! when, with only the references inside one slab in the boxes, its cost already reaches the
//! object split's: chopping only grows the boxes.

use super::chop::{Corners, corners, is_empty, split_estimate};
use crate::BvhParams;
use crate::build::split::split_cost;
use crate::build::{Box3, PrimRef};
use crate::simd::{F4, prefetch};
use glam::Vec3A;
use raybench_geom::TriangleMesh;

/// Upper bound of the `spatial_bins` knob: the slabs live in fixed arrays reused by every node
/// of a task.
pub const MAX_SPATIAL_BINS: usize = 64;

/// A chosen plane `axis = pos`, with the SAH cost and the children's boxes and reference
/// counts the binning estimated (references crossing the plane counted on both sides).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpatialSplit {
    pub axis: usize,
    pub pos: f32,
    pub cost: f64,
    pub left: Box3,
    pub right: Box3,
    pub left_count: usize,
    pub right_count: usize,
}

/// Per axis and slab: the box of the pieces of references inside it, how many references
/// start in it and how many end in it; and the sweep's right-hand sides.
pub(crate) struct SlabBins {
    boxes: [[Box3; MAX_SPATIAL_BINS]; 3],
    enter: [[u32; MAX_SPATIAL_BINS]; 3],
    exit: [[u32; MAX_SPATIAL_BINS]; 3],
    right: [(Box3, u32); MAX_SPATIAL_BINS],
}

impl SlabBins {
    pub(crate) fn new() -> Box<SlabBins> {
        Box::new(SlabBins {
            boxes: [[Box3::EMPTY; MAX_SPATIAL_BINS]; 3],
            enter: [[0; MAX_SPATIAL_BINS]; 3],
            exit: [[0; MAX_SPATIAL_BINS]; 3],
            right: [(Box3::EMPTY, 0); MAX_SPATIAL_BINS],
        })
    }
}

/// What a search may choose: `slabs` per axis, at most `budget` references duplicated, and,
/// when `beat` is given, only a plane that may cost less (the cost the split must undercut to
/// be taken).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    pub slabs: usize,
    pub budget: usize,
    pub beat: Option<f64>,
}

/// The cheapest spatial split of `refs` (whose box is `bounds`) within `limits`; `None` when
/// the box is flat or no plane leaves both sides a reference within the budget. Ties go to the
/// first axis and the leftmost plane, so the result depends on the references alone. Planes
/// that cannot undercut `limits.beat` are not searched: the answer is then the same whenever
/// some plane costs less than `beat`, and otherwise a plane no cheaper than `beat`, or `None`.
pub(crate) fn best_spatial_split(
    refs: &[PrimRef],
    mesh: &TriangleMesh,
    bounds: &Box3,
    p: &BvhParams,
    limits: Limits,
    bins: &mut SlabBins,
) -> Option<SpatialSplit> {
    let Limits {
        slabs,
        budget,
        beat,
    } = limits;
    let parent = bounds.half_area();
    if parent <= 0.0 {
        return None;
    }
    let nb = slabs.clamp(2, MAX_SPATIAL_BINS);
    let n = refs.len();
    let mut best: Option<SpatialSplit> = None;
    // All three axes a pass over the references, so a reference crossing slab planes on
    // several axes fetches its triangle from the mesh once. Per lane, the same arithmetic as
    // one axis at a time: `extent / nb`, then `(x - lo) / step`.
    let (lo, extent) = (bounds.lo, bounds.hi - bounds.lo);
    let step = extent / nb as f32;
    let plane = |axis: usize, b: usize| lo[axis] + step[axis] * b as f32;
    // Clamped to the slabs in floats, then one SIMD truncation for the three lanes: a
    // saturating `as usize` per lane costs several instructions each. The same slabs: a
    // coordinate inside the box is never below `lo`, and a lane of zero extent (0 / 0) is
    // never read.
    let top = Vec3A::splat((nb - 1) as f32);
    let slabs_of = |x: Vec3A| {
        let s = F4::from_vec3a(((x - lo) / step).max(Vec3A::ZERO).min(top)).trunc_i32();
        [s[0] as usize, s[1] as usize, s[2] as usize]
    };
    let mut live = [0, 1, 2].map(|axis| extent[axis] > 0.0);
    for axis in (0..3).filter(|&a| live[a]) {
        bins.boxes[axis][..nb].fill(Box3::EMPTY);
        bins.enter[axis][..nb].fill(0);
        bins.exit[axis][..nb].fill(0);
    }
    // First the counts alone: a plane duplicates the references that cross it, so a plane
    // that leaves a side empty or cuts more references than the budget holds is never chosen,
    // and no reference needs cutting there (deep in the tree, where the budget left is small,
    // that is most planes, often every plane of an axis). A reference inside one slab goes
    // into it whole, here, and the chopping skips it.
    for r in refs {
        let b = r.bounds();
        let (first, last) = (slabs_of(b.lo), slabs_of(b.hi));
        for axis in (0..3).filter(|&a| live[a]) {
            bins.enter[axis][first[axis]] += 1;
            bins.exit[axis][last[axis]] += 1;
            if first[axis] == last[axis] {
                bins.boxes[axis][first[axis]] = bins.boxes[axis][first[axis]].union(&b);
            }
        }
    }
    // Per axis, a bit for each plane `b` (the lower face of slab `b`) that is a candidate.
    let mut planes = [0u64; 3];
    for axis in 0..3 {
        if !live[axis] {
            continue;
        }
        let (mut entered, mut exited) = (0, 0);
        for b in 1..nb {
            entered += bins.enter[axis][b - 1] as usize;
            exited += bins.exit[axis][b - 1] as usize;
            // Left: the references entering before the plane; right: those not leaving
            // before it; both: those crossing it.
            if candidate(entered, n - exited, n, budget) {
                planes[axis] |= 1 << b;
            }
        }
        if let Some(beat) = beat {
            planes[axis] &= below(p, parent, bins, axis, nb, planes[axis], beat);
        }
        live[axis] = planes[axis] != 0;
    }
    if !live.contains(&true) {
        return None;
    }
    // A node's references are in spatial order, their triangles anywhere in the mesh: each
    // chopped reference would wait on its triangle's index and vertices. They are prefetched
    // ahead, the index twice as far ahead as the vertices that need it.
    let (indices, positions) = (mesh.indices(), mesh.positions());
    for (i, r) in refs.iter().enumerate() {
        if let Some(ahead) = refs.get(i + 2 * AHEAD) {
            prefetch(indices.as_ptr().wrapping_add(ahead.id() as usize));
        }
        if let Some(ahead) = refs.get(i + AHEAD) {
            for v in indices[ahead.id() as usize] {
                prefetch(positions.as_ptr().wrapping_add(v as usize));
            }
        }
        let b = r.bounds();
        let (first, last) = (slabs_of(b.lo), slabs_of(b.hi));
        let mut tri: Option<Corners> = None;
        for axis in (0..3).filter(|&a| live[a]) {
            let (first, last) = (first[axis], last[axis]);
            if first == last {
                continue;
            }
            // The candidate planes the reference crosses: `first + 1 ..= last`.
            let above = u64::MAX.checked_shl(first as u32 + 1).unwrap_or(0);
            let crossed = planes[axis] & above & (u64::MAX >> (63 - last));
            if crossed == 0 {
                bins.boxes[axis][last] = bins.boxes[axis][last].union(&b);
                continue;
            }
            let tri = tri.get_or_insert_with(|| corners(&mesh.triangle(r.id() as usize)));
            chop_into_slabs(
                tri,
                axis,
                b,
                crossed,
                last,
                &|b: usize| plane(axis, b),
                &mut bins.boxes[axis],
            );
        }
    }
    for axis in (0..3).filter(|&a| live[a]) {
        each_plane(
            bins,
            axis,
            nb,
            planes[axis],
            |b, (left, lc), (right, rc)| {
                let cost = split_cost(p, parent, (left.half_area(), lc), (right.half_area(), rc));
                if best.is_none_or(|s| cost < s.cost) {
                    best = Some(SpatialSplit {
                        axis,
                        pos: plane(axis, b),
                        cost,
                        left,
                        right,
                        left_count: lc,
                        right_count: rc,
                    });
                }
            },
        );
    }
    best
}

/// Calls `f` with each plane `b` of `planes` on `axis`, in order, and the box and reference
/// count of either side of it: the unions of the slabs' boxes below and above the plane, the
/// references entering below it and those not leaving below it.
#[inline(always)]
fn each_plane(
    bins: &mut SlabBins,
    axis: usize,
    nb: usize,
    planes: u64,
    mut f: impl FnMut(usize, (Box3, usize), (Box3, usize)),
) {
    let (boxes, enter, exit) = (&bins.boxes[axis], &bins.enter[axis], &bins.exit[axis]);
    let (mut acc, mut count) = (Box3::EMPTY, 0u32);
    for b in (1..nb).rev() {
        acc = acc.union(&boxes[b]);
        count += exit[b];
        bins.right[b] = (acc, count);
    }
    let (mut left, mut left_count) = (Box3::EMPTY, 0u32);
    for b in 1..nb {
        left = left.union(&boxes[b - 1]);
        left_count += enter[b - 1];
        if planes & 1 << b == 0 {
            continue;
        }
        let (right, right_count) = bins.right[b];
        f(
            b,
            (left, left_count as usize),
            (right, right_count as usize),
        );
    }
}

/// References ahead of the chopping whose vertices are prefetched (not tuned: 8 was the first
/// value tried, see docs/experiments.md).
const AHEAD: usize = 8;

/// Of the planes in `planes` on `axis`, those whose cost may lie below `beat`: a plane's cost
/// is at least that of sides holding only the references inside one slab (the slabs' boxes
/// after the counting pass) with the sides' full counts, since the pieces the chopping adds
/// only grow the boxes. The cost grows with the areas (and rounding keeps that order), so a
/// plane dropped here costs no less than `beat` once chopped either.
fn below(
    p: &BvhParams,
    parent: f64,
    bins: &mut SlabBins,
    axis: usize,
    nb: usize,
    planes: u64,
    beat: f64,
) -> u64 {
    // A side may hold no reference inside one slab: its box is then empty, of area 0.
    let area = |x: &Box3| if is_empty(x) { 0.0 } else { x.half_area() };
    let mut kept = 0;
    each_plane(bins, axis, nb, planes, |b, (left, lc), (right, rc)| {
        if split_cost(p, parent, (area(&left), lc), (area(&right), rc)) < beat {
            kept |= 1 << b;
        }
    });
    kept
}

/// Whether a plane with `lc` references on its left and `rc` on its right (those crossing it
/// on both) is a candidate: both sides hold one, and the crossings fit the budget.
#[inline(always)]
fn candidate(lc: usize, rc: usize, n: usize, budget: usize) -> bool {
    lc > 0 && rc > 0 && lc + rc - n <= budget
}

/// Adds the pieces of one reference (box `b`, triangle `tri`, last slab `last`) to the slabs
/// on `axis`, cut only at the candidate planes it crosses (bits of `crossed`): the piece below
/// candidate plane `c` goes to slab `c - 1`, the rest to slab `last`. The sweep reads the boxes
/// only at candidate planes, and there each side's union is the same as if the reference were
/// cut at every slab plane; a reference crossing planes that cannot be chosen is cut fewer
/// times (with a small budget, most of them), and one crossing none needs no triangle.
fn chop_into_slabs(
    tri: &Corners,
    axis: usize,
    b: Box3,
    mut crossed: u64,
    last: usize,
    plane: &impl Fn(usize) -> f32,
    boxes: &mut [Box3; MAX_SPATIAL_BINS],
) {
    let mut rest = b;
    while crossed != 0 {
        let c = crossed.trailing_zeros() as usize;
        crossed &= crossed - 1;
        let (piece, beyond) = split_estimate(tri, axis, plane(c), &rest);
        if !is_empty(&piece) {
            boxes[c - 1] = boxes[c - 1].union(&piece);
        }
        if is_empty(&beyond) {
            return;
        }
        rest = beyond;
    }
    boxes[last] = boxes[last].union(&rest);
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::WideParams;
    use crate::build::spatial::chop::box_of;
    use raybench_geom::Vec3;

    /// 16 slabs, as the builder's default.
    pub(crate) fn limits(budget: usize, beat: Option<f64>) -> Limits {
        Limits {
            slabs: 16,
            budget,
            beat,
        }
    }

    /// Slanted triangles each spanning the whole box in y and z (so every plane on those axes
    /// cuts them all): ten narrow ones near x = 0, ten near x = 1, and three spanning x too.
    fn walls() -> TriangleMesh {
        let mut spans: Vec<(f32, f32)> = (0..10)
            .flat_map(|k| {
                let a = 0.01 * k as f32;
                [(a, a + 0.01), (0.9 + a, 0.91 + a)]
            })
            .collect();
        spans.extend([(0.0, 1.0); 3]);
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for (a, b) in spans {
            let base = vertices.len() as u32;
            vertices.push(Vec3::new(a, 0.0, 0.0));
            vertices.push(Vec3::new(b, 1.0, 0.0));
            vertices.push(Vec3::new(a, 0.0, 1.0));
            indices.push([base, base + 1, base + 2]);
        }
        TriangleMesh::new(vertices, indices)
            .expect("a valid mesh")
            .0
    }

    /// The cheapest plane cuts only the three long triangles; a budget of three admits it, a
    /// budget of two admits no plane on any axis (the counts rule every axis out before any
    /// reference is chopped), and the answer is `None`, not a plane over the budget.
    #[test]
    fn a_plane_is_a_candidate_only_within_the_budget() {
        let mesh = walls();
        let refs: Vec<PrimRef> = (0..mesh.len())
            .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
            .collect();
        let bounds = box_of(&mesh.bounds());
        let p = WideParams::default().binary;
        let mut bins = SlabBins::new();
        let s = best_spatial_split(&refs, &mesh, &bounds, &p, limits(3, None), &mut bins)
            .expect("a plane within a budget of three");
        assert_eq!(s.axis, 0);
        assert_eq!(s.left_count + s.right_count - refs.len(), 3);
        assert!(s.pos > 0.1 && s.pos < 0.9, "{s:?}");
        assert!(
            best_spatial_split(&refs, &mesh, &bounds, &p, limits(2, None), &mut bins).is_none()
        );
    }

    /// With a budget that leaves only some planes as candidates, the references are cut only
    /// at those; the chosen plane's boxes and counts must still be those of cutting every
    /// reference at it. Checked against each reference cut once at the plane, on scenes whose
    /// references cross many slabs, for several budgets.
    #[test]
    fn cutting_only_at_candidate_planes_gives_the_boxes_of_the_plane() {
        let p = WideParams::default().binary;
        let mut bins = SlabBins::new();
        for spec in ["hair:triangles=2000", "soup:triangles=2000", "grass"] {
            let mesh = raybench_testkit::generated(spec, 3);
            let refs: Vec<PrimRef> = (0..mesh.len())
                .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
                .collect();
            let bounds = box_of(&mesh.bounds());
            let mut found = 0;
            for budget in [1, 5, 40, 300, refs.len()] {
                let Some(s) =
                    best_spatial_split(&refs, &mesh, &bounds, &p, limits(budget, None), &mut bins)
                else {
                    continue;
                };
                found += 1;
                let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
                let (mut nl, mut nr) = (0, 0);
                for r in &refs {
                    let b = r.bounds();
                    let tri = corners(&mesh.triangle(r.id() as usize));
                    let (l, rt) = split_estimate(&tri, s.axis, s.pos, &b);
                    // The binning's counts: a reference whose box starts below the plane's slab
                    // is on the left, one whose box ends in or above it on the right.
                    if b.lo[s.axis] < s.pos && !is_empty(&l) {
                        left = left.union(&l);
                    }
                    if b.hi[s.axis] >= s.pos && !is_empty(&rt) {
                        right = right.union(&rt);
                    }
                    nl += usize::from(b.lo[s.axis] < s.pos);
                    nr += usize::from(b.hi[s.axis] >= s.pos);
                }
                assert_eq!((s.left_count, s.right_count), (nl, nr), "{spec} {budget}");
                assert!(s.left_count + s.right_count - refs.len() <= budget);
                for (got, want) in [(s.left, left), (s.right, right)] {
                    let scale = (bounds.hi - bounds.lo).max_element();
                    let off = (got.lo - want.lo).abs().max((got.hi - want.hi).abs());
                    assert!(
                        off.max_element() <= 1e-5 * scale,
                        "{spec} {budget}: {got:?} {want:?}"
                    );
                }
            }
            assert!(found >= 2, "{spec}: a plane for at least two budgets");
        }
    }

    /// With a cost to beat, the planes that cannot undercut it are not searched: when the best
    /// plane undercuts it, the answer is that plane, bit for bit; otherwise no answer undercuts
    /// it either.
    #[test]
    fn a_cost_to_beat_leaves_the_winning_plane_alone() {
        let p = WideParams::default().binary;
        let mut bins = SlabBins::new();
        let mut same = 0;
        for spec in [
            "hair:triangles=2000",
            "soup:triangles=2000",
            "grass",
            "city",
        ] {
            let mesh = raybench_testkit::generated(spec, 5);
            let refs: Vec<PrimRef> = (0..mesh.len())
                .map(|i| PrimRef::new(&mesh.triangle(i).bounds(), i as u32))
                .collect();
            let bounds = box_of(&mesh.bounds());
            for budget in [1, 3, 10, 40, 200, refs.len()] {
                let search = |beat, bins: &mut SlabBins| {
                    best_spatial_split(&refs, &mesh, &bounds, &p, limits(budget, beat), bins)
                };
                let Some(full) = search(None, &mut bins) else {
                    continue;
                };
                for factor in [1.0001, 1.05, 1.0, 0.98, 0.5] {
                    let beat = full.cost * factor;
                    let pruned = search(Some(beat), &mut bins);
                    if full.cost < beat {
                        let s = pruned.expect("the winning plane is kept");
                        assert_eq!((s.axis, s.pos, s.cost), (full.axis, full.pos, full.cost));
                        assert_eq!((s.left, s.right), (full.left, full.right));
                        assert_eq!(
                            (s.left_count, s.right_count),
                            (full.left_count, full.right_count)
                        );
                        same += 1;
                    } else {
                        assert!(
                            pruned.is_none_or(|s| s.cost >= beat),
                            "{spec} {budget} {factor}"
                        );
                    }
                }
            }
        }
        assert!(same >= 10, "{same} cases where the best plane wins");
    }
}
