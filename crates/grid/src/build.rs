//! Grid construction: resolution from a density, exact insertion, counting sort.
//!
//! Resolution follows Cleary and Wyvill ("Analysis of an algorithm for fast ray tracing using
//! uniform space subdivision", The Visual Computer 4(2), 1988): for N triangles and density λ,
//! cells of side `s = (V / λN)^(1/k)` over the k axes with extent, so cells are as close to cubes
//! as the bounds allow and number about λ·N; an axis thinner than one cell gets one cell and the
//! others share the budget (a flat scene gets a 2D grid: docs/validation.md, G9 and B14), and no
//! axis gets more than [`GridParams::max_resolution`].
//!
//! Insertion is exact: each triangle goes into the cells of its bounding box that pass the
//! separating-axis test of Akenine-Möller ([`raybench_geom::tribox`]), run on the cell
//! enlarged by a margin of 2^-20 of the grid's largest coordinate magnitude (a few f32 steps:
//! the f32 DDA can never disagree with insertion about which side of a plane it is on by more).
//! A triangle whose bounding box meets a single cell skips the test. The trade-off: the test
//! costs ~100 flops per candidate cell at build time, and saves every useless reference of a
//! long or slanted triangle at trace time. A triangle whose bounding box holds many cells (a
//! hair strand, a ground plane) is first clipped to each layer and row of cells, so only the
//! cells it can reach are tested ([`crate::reach`]): the same references, without a test per
//! cell of the box.
//!
//! Storage is one offsets array (cells + 1 entries) into one reference array, never a `Vec`
//! per cell: insertion (parallel over chunks of triangles) emits `(cell, triangle)` pairs in
//! triangle order, then a counting pass and a prefix sum give the offsets and a scatter fills
//! the references, ascending within each cell. Triangles are stored four to a
//! [`raybench_geom::Tri4`] in mesh order; meshes list neighbouring triangles together, so a
//! cell's references mostly fall into a few Tri4s, each tested four lanes at a time, with no copy
//! of a triangle per cell. Memory is
//! estimated before every allocation (offsets and triangle copies from the resolution,
//! references counted as they are emitted) and the build stops with
//! [`BuildError::TooLarge`] past [`GridParams::memory_limit_bytes`] instead of exhausting
//! memory.

use crate::{Grid, GridParams};
use raybench_accel::{BuildError, BuildStats};
use raybench_geom::Tri4;
use raybench_geom::tri4::LANES;
use raybench_geom::tribox::{MARGIN_REL, TriBox};
use raybench_geom::{Aabb, DVec3, MollerTriangle, Triangle, TriangleMesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The f64 geometry of a grid: resolution, cell planes and the insertion margin. Insertion and
/// `validate()` both go through it, so they agree bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub res: [u32; 3],
    /// `res[a] + 1` planes per axis; the first is the bounds' min, the last exactly its max.
    pub planes: [Vec<f64>; 3],
    /// Every cell is enlarged by this on every side for insertion.
    pub margin: f64,
    /// Cells per unit length (for the first guess of a cell index; 0 with one cell).
    pub inv_width: [f32; 3],
    /// Per axis and cell, the enlarged cell's faces `planes[c] - margin` and
    /// `planes[c + 1] + margin` rounded inwards to f32 (up and down), so that for an f32
    /// coordinate `x`, `lower <= x` and `x <= upper` hold exactly when they hold against the
    /// f64 faces: the candidate ranges are exact.
    lower: [Vec<f32>; 3],
    upper: [Vec<f32>; 3],
}

/// The largest f32 not above `x` (for finite `x` in f32 range).
pub(crate) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

/// The smallest f32 not below `x`.
pub(crate) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

impl Layout {
    /// The resolution for `n` triangles in `bounds` (see the module note).
    pub fn new(bounds: &Aabb, n: usize, params: &GridParams) -> Layout {
        let (min, max) = if bounds.is_empty() {
            (DVec3::ZERO, DVec3::ZERO)
        } else {
            (bounds.min.as_dvec3(), bounds.max.as_dvec3())
        };
        let e = max - min;
        let res = resolution(e.to_array(), n, params.density, params.max_resolution);
        let margin = min.abs().max(max.abs()).max_element() * MARGIN_REL;
        Layout::over(min, max, res, margin)
    }

    /// `res` cells over the box `[min, max]`, each enlarged by `margin` for insertion.
    pub fn over(min: DVec3, max: DVec3, res: [u32; 3], margin: f64) -> Layout {
        let e = max - min;
        let planes = std::array::from_fn(|a| {
            let k = res[a] as usize;
            let w = e[a] / k as f64;
            let mut p: Vec<f64> = (0..=k).map(|i| min[a] + i as f64 * w).collect();
            p[k] = max[a];
            p
        });
        let inv_width = std::array::from_fn(|a| {
            if res[a] > 1 {
                (res[a] as f64 / e[a]) as f32
            } else {
                0.0
            }
        });
        let faces = |a: usize, upper: bool| -> Vec<f32> {
            let p: &Vec<f64> = &planes[a];
            (0..res[a] as usize)
                .map(|c| {
                    if upper {
                        f32_down(p[c + 1] + margin)
                    } else {
                        f32_up(p[c] - margin)
                    }
                })
                .collect()
        };
        let lower = std::array::from_fn(|a| faces(a, false));
        let upper = std::array::from_fn(|a| faces(a, true));
        Layout {
            res,
            planes,
            margin,
            inv_width,
            lower,
            upper,
        }
    }

    pub fn cells(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    #[inline(always)]
    pub fn index(&self, [x, y, z]: [u32; 3]) -> usize {
        x as usize + self.res[0] as usize * (y as usize + self.res[1] as usize * z as usize)
    }

    /// The cell of linear index `i` (the inverse of [`Layout::index`]).
    pub fn coords(&self, i: usize) -> [u32; 3] {
        let (nx, ny) = (self.res[0] as usize, self.res[1] as usize);
        [
            (i % nx) as u32,
            (i / nx % ny) as u32,
            (i / (nx * ny)) as u32,
        ]
    }

    /// Axis `a`'s cell planes rounded to f32, as traversal uses them.
    pub fn f32_planes(&self, a: usize) -> Vec<f32> {
        self.planes[a].iter().map(|&p| p as f32).collect()
    }

    /// Whether the triangle overlaps cell `c`'s enlarged box, by the 3 edge axes along `flat`
    /// when it lies within the cell's slab on that axis, else by all 10 non-box axes (its
    /// bounding box meets the cell's: the cell is one of its candidates).
    #[inline(always)]
    pub(crate) fn overlaps(&self, tb: &TriBox, flat: Option<usize>, c: [u32; 3]) -> bool {
        let (clo, chi) = self.cell_box(c);
        match flat {
            Some(axis) => tb.edges_overlap_along(clo, chi, axis),
            None => tb.plane_and_edges_overlap(clo, chi),
        }
    }

    /// Cell `(x, y, z)` enlarged by the margin: the box the overlap test sees.
    #[inline]
    pub fn cell_box(&self, c: [u32; 3]) -> (DVec3, DVec3) {
        let m = self.margin;
        let lo = DVec3::from_array(std::array::from_fn(|a| self.planes[a][c[a] as usize] - m));
        let hi = DVec3::from_array(std::array::from_fn(|a| {
            self.planes[a][c[a] as usize + 1] + m
        }));
        (lo, hi)
    }

    /// The cells along `axis` whose enlarged extent meets the closed interval `[lo, hi]`
    /// (first, last), exactly: a floating-point guess corrected against the enlarged faces.
    /// Assumes the interval lies within the bounds, as every triangle's does.
    #[inline]
    pub fn range(&self, axis: usize, lo: f32, hi: f32) -> (u32, u32) {
        let lower = self.lower[axis].as_slice();
        let upper = self.upper[axis].as_slice();
        let n = upper.len();
        let origin = self.planes[axis][0] as f32;
        let scale = self.inv_width[axis];
        let guess = |x: f32| (((x - origin) * scale) as i32).clamp(0, n as i32 - 1) as usize;
        // first: the smallest c with upper[c] >= lo
        let mut first = guess(lo);
        while first > 0 && upper[first - 1] >= lo {
            first -= 1;
        }
        while first + 1 < n && upper[first] < lo {
            first += 1;
        }
        // last: the largest c with lower[c] <= hi
        let mut last = guess(hi);
        while last + 1 < n && lower[last + 1] <= hi {
            last += 1;
        }
        while last > 0 && lower[last] > hi {
            last -= 1;
        }
        (first as u32, last as u32)
    }

    /// Calls `emit` with the linear index of every cell the triangle overlaps, in ascending
    /// order: the cells of its bounding box that pass the triangle–box test on their enlarged
    /// box. The test shrinks with the bounding box's spread: none when it spans more than one
    /// cell along one axis at most (every candidate overlaps), the 3 edge axes along the third
    /// axis when it spans two, all 10 non-box axes when it spans three. A triangle with a NaN
    /// coordinate overlaps nothing.
    #[inline]
    pub fn for_each_cell(&self, tri: &Triangle, emit: impl FnMut(usize)) {
        self.insert::<false>(tri, crate::reach::REACH_FROM, emit)
    }

    /// [`Layout::for_each_cell`] for a triangle that may reach beyond the layout's box (a
    /// sub-grid's triangles cross its parent cell's faces): its candidate cells are those of its
    /// bounding box clipped to the box, and the shortcuts that assume it reaches from the first
    /// candidate to the last no longer hold, so every candidate but a lone one is tested on all
    /// ten non-box axes. A lone candidate needs no test: the triangle meets the box (it was
    /// inserted into the parent cell), within its bounding box, so within that cell.
    #[inline]
    pub fn for_each_cell_clipped(&self, tri: &Triangle, emit: impl FnMut(usize)) {
        self.insert::<true>(tri, crate::reach::REACH_FROM, emit)
    }

    /// Both of the above; from `reach_from` candidate cells the candidates are narrowed by
    /// clipping (the tests compare it with `u64::MAX`, the full scan).
    #[inline]
    pub(crate) fn insert<const CLIPPED: bool>(
        &self,
        tri: &Triangle,
        reach_from: u64,
        mut emit: impl FnMut(usize),
    ) {
        let b = tri.bounds();
        if !b.min.cmple(b.max).all() {
            return;
        }
        let r: [(u32, u32); 3] = std::array::from_fn(|a| self.range(a, b.min[a], b.max[a]));
        let spread = r.iter().filter(|&&(f, l)| f != l).count();
        if spread == 0 || (spread == 1 && !CLIPPED) {
            // One row of cells: the triangle lies in the row's (enlarged) cross-section and,
            // being connected, reaches from its bounding box's first cell to its last, so it
            // overlaps every candidate without a test.
            for z in r[2].0..=r[2].1 {
                for y in r[1].0..=r[1].1 {
                    for x in r[0].0..=r[0].1 {
                        emit(self.index([x, y, z]));
                    }
                }
            }
            return;
        }
        let tb = TriBox::new(tri);
        // Spread over two axes: the triangle lies in the slab of the third, so the overlap is
        // the 2D one of the projections along it (its 3 edge axes); over three: the full test.
        let flat = if CLIPPED {
            None
        } else {
            (0..3).find(|&a| r[a].0 == r[a].1)
        };
        let candidates: u64 = r.iter().map(|&(f, l)| (l - f + 1) as u64).product();
        if candidates >= reach_from {
            return self.insert_reached(&tb, r, flat, emit);
        }
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    if self.overlaps(&tb, flat, [x, y, z]) {
                        emit(self.index([x, y, z]));
                    }
                }
            }
        }
    }
}

/// Cells per axis for extents `e`, `n` triangles and density λ (module note).
pub(crate) fn resolution(e: [f64; 3], n: usize, density: f64, max_res: u32) -> [u32; 3] {
    let target = (density * n as f64).max(1.0);
    let mut active = e.map(|x| x > 0.0);
    let mut side = 0.0;
    loop {
        let k = active.iter().filter(|&&a| a).count();
        if k == 0 {
            break;
        }
        let volume: f64 = (0..3).filter(|&a| active[a]).map(|a| e[a]).product();
        side = (volume / target).powf(1.0 / k as f64);
        let mut changed = false;
        for a in 0..3 {
            if active[a] && e[a] < side {
                active[a] = false; // thinner than one cell: one cell, budget to the others
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    std::array::from_fn(|a| {
        if active[a] && side > 0.0 {
            (e[a] / side).round().clamp(1.0, max_res as f64) as u32
        } else {
            1
        }
    })
}

/// Bytes per reference at the build's peak: the (cell, triangle) pair and the final reference.
const PEAK_BYTES_PER_REF: u64 = 8 + 4;

fn too_large(needed_bytes: u64, params: &GridParams) -> BuildError {
    BuildError::TooLarge {
        needed_bytes,
        limit_bytes: params.memory_limit_bytes,
    }
}

pub(crate) fn build(mesh: &Arc<TriangleMesh>, params: &GridParams) -> Result<Grid, BuildError> {
    let n = mesh.len();
    let bounds = mesh.bounds();
    let layout = Layout::new(&bounds, n, params);
    let cells = layout.cells();
    let base = (cells as u64 + 1) * 4 + n as u64 * std::mem::size_of::<MollerTriangle>() as u64;
    if base > params.memory_limit_bytes {
        return Err(too_large(base, params));
    }
    // Insertion: (cell, triangle) pairs per chunk of triangles, in triangle order.
    let budget = (params.memory_limit_bytes - base) / PEAK_BYTES_PER_REF;
    let emitted = AtomicU64::new(0);
    let chunk = params.parallel_chunk as usize;
    let chunks: Vec<Vec<(u32, u32)>> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let mut pairs = Vec::with_capacity(chunk * 4);
            for prim in c * chunk..((c + 1) * chunk).min(n) {
                let before = pairs.len();
                layout.for_each_cell(&mesh.triangle(prim), |cell| {
                    pairs.push((cell as u32, prim as u32))
                });
                let added = (pairs.len() - before) as u64;
                if emitted.fetch_add(added, Ordering::Relaxed) + added > budget {
                    return Err(());
                }
            }
            Ok(pairs)
        })
        .collect::<Result<_, ()>>()
        .map_err(|()| {
            too_large(
                base + emitted.load(Ordering::Relaxed) * PEAK_BYTES_PER_REF,
                params,
            )
        })?;
    let total: usize = chunks.iter().map(Vec::len).sum();
    let refs_len = u32::try_from(total).map_err(|_| too_large(u64::MAX, params))?;

    // Counting sort: counts, exclusive prefix sums, scatter, then shift back to offsets.
    let mut offsets = vec![0u32; cells + 1];
    for &(cell, _) in chunks.iter().flatten() {
        offsets[cell as usize] += 1;
    }
    let mut sum = 0u32;
    for o in offsets.iter_mut() {
        let count = *o;
        *o = sum;
        sum += count;
    }
    debug_assert_eq!(sum, refs_len);
    let mut refs = vec![0u32; total];
    for &(cell, prim) in chunks.iter().flatten() {
        let slot = &mut offsets[cell as usize];
        refs[*slot as usize] = prim;
        *slot += 1;
    }
    drop(chunks);
    // offsets[c] now holds the end of cell c, i.e. the start of c + 1.
    for c in (1..=cells).rev() {
        offsets[c] = offsets[c - 1];
    }
    offsets[0] = 0;

    // The triangles in mesh order, four to a Tri4: triangle `i` is lane `i % 4` of Tri4
    // `i / 4`. Meshes list neighbouring triangles together (scans, strips, generators), so a
    // cell's ascending references mostly fall into a few Tri4s.
    let triangles: Vec<Tri4> = (0..n.div_ceil(LANES))
        .into_par_iter()
        .map(|k| {
            let mut four = Tri4::default();
            for l in 0..LANES.min(n - k * LANES) {
                let id = k * LANES + l;
                four.set_lane(l, id as u32, &MollerTriangle::new(&mesh.triangle(id)));
            }
            four
        })
        .collect();
    let mut occupied = vec![0u64; cells.div_ceil(64)];
    for (c, w) in offsets.windows(2).enumerate() {
        if w[1] > w[0] {
            occupied[c >> 6] |= 1 << (c & 63);
        }
    }
    let stats = stats(&layout, &offsets, total, n, params);
    let planes = std::array::from_fn(|a| layout.f32_planes(a));
    let inv_width = layout.inv_width;
    Ok(Grid {
        name: params.name(),
        params: params.clone(),
        bounds: if n == 0 { Aabb::EMPTY } else { bounds },
        res: layout.res,
        inv_width,
        planes,
        layout,
        offsets,
        occupied,
        refs,
        triangles,
        stats,
        mesh: mesh.clone(),
    })
}

fn stats(
    layout: &Layout,
    offsets: &[u32],
    refs: usize,
    n: usize,
    params: &GridParams,
) -> BuildStats {
    let cells = layout.cells();
    let counts = offsets.windows(2).map(|w| w[1] - w[0]);
    let non_empty = counts.clone().filter(|&c| c > 0).count();
    let max_per_cell = counts.max().unwrap_or(0);
    let mut extra = BTreeMap::new();
    extra.insert("cells".into(), cells as f64);
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        extra.insert(format!("resolution_{axis}"), layout.res[a] as f64);
    }
    extra.insert(
        "empty_cell_fraction".into(),
        1.0 - non_empty as f64 / cells as f64,
    );
    extra.insert(
        "refs_per_triangle".into(),
        if n == 0 { 0.0 } else { refs as f64 / n as f64 },
    );
    extra.insert("max_refs_per_cell".into(), max_per_cell as f64);
    extra.insert(
        "refs_per_non_empty_cell".into(),
        if non_empty == 0 {
            0.0
        } else {
            refs as f64 / non_empty as f64
        },
    );
    extra.insert("density".into(), params.density);
    extra.insert("insertion_margin".into(), layout.margin);
    BuildStats {
        nodes: cells as u64,
        leaves: non_empty as u64,
        max_depth: 0,
        refs: refs as u64,
        sah_cost: None,
        extra,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_is_near_cubic_and_near_lambda_n() {
        let r = resolution([1.0, 1.0, 1.0], 1000, 8.0, 1024);
        assert_eq!(r, [20, 20, 20]);
        let r = resolution([4.0, 2.0, 1.0], 1000, 1.0, 1024);
        assert_eq!(r, [20, 10, 5]);
    }

    #[test]
    fn flat_and_point_scenes_get_one_cell_on_degenerate_axes() {
        assert_eq!(resolution([1.0, 1.0, 0.0], 100, 1.0, 1024), [10, 10, 1]);
        assert_eq!(resolution([0.0, 0.0, 0.0], 100, 1.0, 1024), [1, 1, 1]);
        // Very thin but not flat: the thin axis gets one cell, the others keep the budget.
        assert_eq!(resolution([1.0, 1.0, 1e-9], 100, 1.0, 1024), [10, 10, 1]);
        // A needle: the long axis is capped; the thin ones keep their cubic share.
        assert_eq!(
            resolution([1.0, 1e-6, 1e-6], 1_000_000, 8.0, 1024),
            [1024, 2, 2]
        );
        assert_eq!(resolution([1.0, 1.0, 1.0], 0, 1.0, 1024), [1, 1, 1]);
    }

    #[test]
    fn range_is_exact_at_planes_and_margins() {
        let b = Aabb::new(raybench_geom::Vec3::ZERO, raybench_geom::Vec3::splat(4.0));
        let l = Layout::new(&b, 64, &GridParams::with_density(1.0)); // 4 x 4 x 4, width 1
        assert_eq!(l.res, [4, 4, 4]);
        let m = l.margin as f32;
        assert!(m > 0.0 && m < 1e-5);
        // Strictly inside a cell; touching plane 1 from below and from above.
        assert_eq!(l.range(0, 0.25, 0.5), (0, 0));
        assert_eq!(l.range(0, 0.25, 1.0), (0, 1));
        assert_eq!(l.range(0, 1.0, 1.5), (0, 1));
        // Within the margin of plane 2, and just beyond it.
        assert_eq!(l.range(0, 1.5, 2.0 - m * 0.5), (1, 2));
        assert_eq!(l.range(0, 1.5, 2.0 - m * 2.0), (1, 1));
        // The f32 faces are the f64 ones rounded inwards, at most one f32 step away.
        for c in 0..4 {
            let (lo, hi) = (l.planes[0][c] - l.margin, l.planes[0][c + 1] + l.margin);
            assert!(l.lower[0][c] as f64 >= lo && (l.lower[0][c].next_down() as f64) < lo);
            assert!(l.upper[0][c] as f64 <= hi && (l.upper[0][c].next_up() as f64) > hi);
        }
        // The whole axis, and a point on the last plane.
        assert_eq!(l.range(0, 0.0, 4.0), (0, 3));
        assert_eq!(l.range(0, 4.0, 4.0), (3, 3));
    }
}
