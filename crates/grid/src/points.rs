//! Closest-point queries: the triangle nearest to a point, within a radius.
//!
//! The cells are visited in expanding shells around the point's cell (the cells at Chebyshev
//! index distance 0, 1, 2, … from it: cube rings), the classic nearest-neighbour search on a
//! uniform grid (Samet, *Foundations of Multidimensional and Metric Data Structures*, 2006,
//! §4.1, for the general incremental form). When the point lies outside the grid, its cell is
//! clamped into it, so the shells start at the grid's near face and there are never more of
//! them than the grid's largest resolution.
//!
//! Pruning, three ways, all with exact lower bounds taken from the f32 cell planes:
//! * a shell: every cell of shell `k` lies `k` cells away on some axis, so its squared distance
//!   is at least that axis's gap to the `k`-th plane plus the point's distance outside the grid
//!   on the other two axes; once that bound exceeds the best squared distance found (or the
//!   radius), no later shell can do better and the search stops;
//! * a face of a shell, or a row of cells in it, whose gaps already exceed it is skipped
//!   without visiting its cells; gaps only grow away from the point's cell, so rows are
//!   walked outwards from it and stop at the first cell out of reach;
//! * a cell whose box is farther than the best so far is not opened.
//!
//! Why it is exact: a triangle is referenced by every cell it overlaps (insertion tests the
//! cell enlarged by a margin covering the rounding of its planes, `build.rs`), so its nearest
//! point lies in a cell that references it, and that cell is no farther than the triangle.
//! Cells exactly as far as the best are still opened, and the shared [`Nearest`] keeps the
//! lowest id among equally near triangles, so the answer is brute force's bit for bit.
//! Trade-off: the visiting order is by shell, not by exact cell distance, so a shell is
//! finished even after its first cell found a close triangle (the per-cell test keeps that
//! cheap); a point far outside the grid sees all cells at nearly the same distance, so it
//! examines the whole layer of cells facing it (a row's first cells, not the volume).
//! A triangle spanning several cells is tested once thanks to the ray walk's mailbox, and
//! triangles are read from the mesh (an index and three vertex loads), as Embree's
//! point-query callback does, so the distances are bit-identical to brute force's.

use crate::Grid;
use crate::traverse::Mailbox;
use raybench_accel::{CounterSink, Nearest, PointHit};
use raybench_geom::Vec3;

/// One query in flight: the point, its (clamped) cell, the squared gap from the point to that
/// cell on each axis (the smallest gap any cell has on that axis, since the point lies in its
/// cell's slab or, outside the grid, beyond the clamped cell), the best so far, the mailbox
/// and the counters.
struct Search<'c, C> {
    p: Vec3,
    home: [u32; 3],
    base: [f32; 3],
    best: Nearest,
    mailbox: Mailbox,
    counters: &'c mut C,
}

impl Grid {
    /// [`raybench_accel::Walk::walk_point`] on the grid: shells around the point's (clamped)
    /// cell, nearest first, until the next shell lies beyond the best triangle.
    pub(crate) fn closest<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<PointHit> {
        if self.refs.is_empty() {
            return None;
        }
        let best = Nearest::within(p, max_radius)?;
        let home: [u32; 3] = std::array::from_fn(|a| self.home_index(a, p[a]));
        let mut s = Search {
            p,
            home,
            base: std::array::from_fn(|a| self.gap2(a, home[a], p[a])),
            best,
            mailbox: Mailbox::new(),
            counters: c,
        };
        if s.base[0] + s.base[1] + s.base[2] <= s.best.bound_d2() {
            let last = (0..3)
                .map(|a| home[a].max(self.res[a] - 1 - home[a]))
                .max()
                .unwrap_or(0);
            for k in 0..=last {
                if k > 0 && self.shell_bound(&s, k) > s.best.bound_d2() {
                    break;
                }
                self.visit_shell(&mut s, k);
            }
        }
        s.best.into_hit()
    }

    /// The cell holding coordinate `x` on axis `a`, clamped into the grid: a floor guess
    /// corrected against the f32 planes, so the gap to it is the smallest on that axis.
    fn home_index(&self, a: usize, x: f32) -> u32 {
        let planes = &self.planes[a];
        let n = self.res[a] as usize;
        // `as i32` saturates far outside the grid; the clamp does the rest.
        let guess = ((x - self.bounds.min[a]) * self.inv_width[a]).floor() as i32;
        let mut i = guess.clamp(0, n as i32 - 1) as usize;
        while i > 0 && x < planes[i] {
            i -= 1;
        }
        while i + 1 < n && x > planes[i + 1] {
            i += 1;
        }
        i as u32
    }

    /// Squared distance from coordinate `x` to the slab of cell `i` on axis `a` (0 inside).
    #[inline(always)]
    fn gap2(&self, a: usize, i: u32, x: f32) -> f32 {
        let planes = &self.planes[a];
        let g = (planes[i as usize] - x)
            .max(x - planes[i as usize + 1])
            .max(0.0);
        g * g
    }

    /// A lower bound on the squared distance to every cell of shell `k` and beyond: the
    /// nearest existing `k`-th neighbour slab on any axis, plus the other axes' smallest gaps.
    fn shell_bound<C>(&self, s: &Search<C>, k: u32) -> f32 {
        let mut bound = f32::INFINITY;
        for a in 0..3 {
            let others = s.base[(a + 1) % 3] + s.base[(a + 2) % 3];
            if let Some(i) = s.home[a].checked_sub(k) {
                bound = bound.min(self.gap2(a, i, s.p[a]) + others);
            }
            if s.home[a] + k < self.res[a] {
                bound = bound.min(self.gap2(a, s.home[a] + k, s.p[a]) + others);
            }
        }
        bound
    }

    /// The indices `home ± k` on axis `a` that lie in the grid (the two faces of shell `k`).
    fn sides(&self, a: usize, home: u32, k: u32) -> impl Iterator<Item = u32> + use<> {
        let above = home + k;
        [home.checked_sub(k), (above < self.res[a]).then_some(above)]
            .into_iter()
            .flatten()
    }

    /// The indices within `reach` of `home` on axis `a`, clamped to the grid: (first, last).
    fn span(&self, a: usize, home: u32, reach: u32) -> (u32, u32) {
        (
            home.saturating_sub(reach),
            (home + reach).min(self.res[a] - 1),
        )
    }

    /// Every cell of shell `k` (clamped to the grid) that can still hold a closer triangle,
    /// face by face without overlap: the two z faces whole, the two y faces between them, the
    /// two x faces inside both. A face, a row or the rest of a row whose gaps already exceed
    /// the best distance is skipped; gaps only grow away from the home cell, so each row is
    /// walked outwards from it and stops at the first cell out of reach.
    fn visit_shell<C: CounterSink>(&self, s: &mut Search<C>, k: u32) {
        let home = s.home;
        if k == 0 {
            let gyz = self.gap2(1, home[1], s.p.y) + self.gap2(2, home[2], s.p.z);
            self.visit_row(s, k, home[1], home[2], gyz);
            return;
        }
        for z in self.sides(2, home[2], k) {
            let gz = self.gap2(2, z, s.p.z);
            if gz + s.base[0] + s.base[1] <= s.best.bound_d2() {
                let (first, last) = self.span(1, home[1], k);
                outward(first, home[1], last, |y| {
                    let gyz = self.gap2(1, y, s.p.y) + gz;
                    gyz + s.base[0] <= s.best.bound_d2() && {
                        self.visit_row(s, k, y, z, gyz);
                        true
                    }
                });
            }
        }
        let (z_first, z_last) = self.span(2, home[2], k - 1);
        for y in self.sides(1, home[1], k) {
            let gy = self.gap2(1, y, s.p.y);
            if gy + s.base[0] + s.base[2] <= s.best.bound_d2() {
                outward(z_first, home[2], z_last, |z| {
                    let gyz = gy + self.gap2(2, z, s.p.z);
                    gyz + s.base[0] <= s.best.bound_d2() && {
                        self.visit_row(s, k, y, z, gyz);
                        true
                    }
                });
            }
        }
        let (y_first, y_last) = self.span(1, home[1], k - 1);
        for x in self.sides(0, home[0], k) {
            let gx = self.gap2(0, x, s.p.x);
            if gx + s.base[1] + s.base[2] <= s.best.bound_d2() {
                outward(z_first, home[2], z_last, |z| {
                    let gz = self.gap2(2, z, s.p.z);
                    gx + gz + s.base[1] <= s.best.bound_d2() && {
                        outward(y_first, home[1], y_last, |y| {
                            self.visit_cell(s, [x, y, z], self.gap2(1, y, s.p.y) + gz)
                        });
                        true
                    }
                });
            }
        }
    }

    /// The cells of row `(y, z)` within shell `k`'s x range, outwards from the home cell.
    fn visit_row<C: CounterSink>(&self, s: &mut Search<C>, k: u32, y: u32, z: u32, gyz: f32) {
        let (first, last) = self.span(0, s.home[0], k);
        outward(first, s.home[0], last, |x| {
            self.visit_cell(s, [x, y, z], gyz)
        });
    }

    /// Examines cell `xyz` (whose squared y and z gaps sum to `gyz`): false when it is farther
    /// than the best so far (so are the cells beyond it in the row); otherwise tests its
    /// triangles, if any.
    #[inline(always)]
    fn visit_cell<C: CounterSink>(&self, s: &mut Search<C>, [x, y, z]: [u32; 3], gyz: f32) -> bool {
        s.counters.cell();
        if self.gap2(0, x, s.p.x) + gyz > s.best.bound_d2() {
            return false;
        }
        let u = self.layout.index([x, y, z]);
        if self.occupied[u >> 6] >> (u & 63) & 1 == 0 {
            return true;
        }
        // References are mesh triangle ids (the Tri4s keep mesh order, `build.rs`).
        let refs = &self.refs[self.offsets[u] as usize..self.offsets[u + 1] as usize];
        s.best
            .test_unseen(s.p, &self.mesh, refs, &mut s.mailbox, s.counters);
        true
    }
}

/// Calls `visit` on `at`, then on the indices below it down to `first` and above it up to
/// `last`, each direction until `visit` returns false (`first <= at <= last`). The distance
/// gaps grow away from the home cell, so once one index is out of reach so is the rest of
/// that direction.
#[inline(always)]
fn outward(first: u32, at: u32, last: u32, mut visit: impl FnMut(u32) -> bool) {
    if !visit(at) {
        return; // both neighbours are at least as far
    }
    let mut i = at;
    while i > first && visit(i - 1) {
        i -= 1;
    }
    let mut i = at;
    while i < last && visit(i + 1) {
        i += 1;
    }
}
