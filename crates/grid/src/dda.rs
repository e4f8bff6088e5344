//! The one cell walk: Amanatides and Woo's 3D-DDA ("A Fast Voxel Traversal Algorithm for Ray
//! Tracing", Eurographics 1987) over one level of cells, shared by the uniform grid, both
//! levels of the two-level grid and the skipping grid.
//!
//! * Entry: the cell of the entry point is found by a floor, clamped (pbrt's `posToVoxel`;
//!   docs/validation.md, B13), then corrected against the cell planes so it is never *ahead* of
//!   the ray on an axis it moves along (that would skip a cell); a cell behind is harmless (its
//!   exit is at once).
//! * Stepping: the next crossing on each axis is recomputed from the f32 cell planes at every
//!   step, never accumulated, so long walks do not drift away from the planes insertion used.
//!   A `±0` direction component never crosses (its crossing is `+inf`; the sign bit, not `< 0`,
//!   picks the step; docs/validation.md, B3).
//! * Termination is the caller's: [`Level::walk`]'s `visit` gets each cell and its exit
//!   distance and says whether to stop. Otherwise the walk ends when the ray leaves the level.
//!   Every iteration steps one axis towards the level's side, so the walk is bounded by
//!   `nx + ny + nz` cells even for NaN input.
//! * Jumping ([`Dda::jump`], for the skipping grid): the walk moves at once to the state it
//!   would reach by stepping through a block of cells known to be empty.

use raybench_geom::{Aabb, Ray, max_keep};

/// The axis with the smallest of three crossings, indexed by the bits
/// `t0 < t1`, `t0 < t2`, `t1 < t2` (two entries are unreachable).
const CMP_TO_AXIS: [usize; 8] = [2, 1, 2, 1, 2, 2, 0, 0];

/// One level of cells: its box, resolution and f32 cell planes (`res[a] + 1` per axis, the
/// first and last the box's faces). Cell `(x, y, z)` has index `x + nx·(y + ny·z)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Level<'a> {
    pub bounds: Aabb,
    pub res: [u32; 3],
    /// Cells per unit length on each axis (0 on an axis with one cell), for the entry guess.
    pub inv_width: [f32; 3],
    pub planes: [&'a [f32]; 3],
}

/// A walk in progress: the current cell and the distance of the next crossing on each axis.
#[derive(Clone, Copy)]
pub(crate) struct Dda {
    cell: [i32; 3],
    step: [i32; 3],
    /// 1 where the next plane is above the cell (positive step).
    up: [i32; 3],
    /// The cell index at which the walk leaves the level on each axis; for an axis that never
    /// steps, its own cell, so stepping it (only when every crossing is +inf, which the
    /// caller's exit test sees first) would end the walk too.
    out: [i32; 3],
    next_t: [f32; 3],
    stride: [isize; 3],
    /// The linear index of `cell`.
    idx: isize,
}

impl Level<'_> {
    /// Walks the cells `ray` pierces from `t_enter` (where it is inside [`Level::bounds`]) in
    /// order, calling `visit(cell index, exit distance)` until it returns `true` or the ray
    /// leaves the level.
    #[inline(always)]
    pub fn walk(&self, ray: &Ray, t_enter: f32, mut visit: impl FnMut(usize, f32) -> bool) {
        let mut dda = self.start(ray, t_enter);
        loop {
            let (a, t_exit) = dda.exit();
            if visit(dda.index(), t_exit) || !dda.step(self, ray, a, t_exit) {
                return;
            }
        }
    }

    /// The walk's state in the cell where `ray` is at `t_enter` (inside [`Level::bounds`]).
    #[inline(always)]
    pub fn start(&self, ray: &Ray, t_enter: f32) -> Dda {
        let o = ray.origin();
        let d = ray.dir();
        let inv = ray.inv_dir();
        let p = o + d * t_enter;
        let min = self.bounds.min;
        let mut cell = [0i32; 3];
        let mut step = [0i32; 3];
        let mut up = [0i32; 3];
        let mut out = [0i32; 3];
        let mut next_t = [f32::INFINITY; 3];
        let stride = [
            1isize,
            self.res[0] as isize,
            self.res[0] as isize * self.res[1] as isize,
        ];
        for a in 0..3 {
            let n = self.res[a] as i32;
            let planes = self.planes[a];
            // `as i32` saturates and maps NaN to 0; the clamp does the rest.
            let mut i = (((p[a] - min[a]) * self.inv_width[a]).floor() as i32).clamp(0, n - 1);
            if d[a] > 0.0 {
                // Never ahead: the largest i with planes[i] <= p, or behind by rounding.
                while i > 0 && p[a] < planes[i as usize] {
                    i -= 1;
                }
                step[a] = 1;
                up[a] = 1;
                out[a] = n;
                next_t[a] = max_keep(t_enter, (planes[i as usize + 1] - o[a]) * inv[a]);
            } else if d[a] < 0.0 {
                while i + 1 < n && p[a] > planes[i as usize + 1] {
                    i += 1;
                }
                step[a] = -1;
                out[a] = -1;
                next_t[a] = max_keep(t_enter, (planes[i as usize] - o[a]) * inv[a]);
            } else {
                out[a] = i;
            }
            cell[a] = i;
        }
        let idx = cell[0] as isize + stride[1] * cell[1] as isize + stride[2] * cell[2] as isize;
        Dda {
            cell,
            step,
            up,
            out,
            next_t,
            stride,
            idx,
        }
    }
}

impl Dda {
    /// The current cell's linear index.
    #[inline(always)]
    pub fn index(&self) -> usize {
        self.idx as usize
    }

    /// The axis of the nearest crossing and its distance: the current cell's exit. Without
    /// branches (pbrt's cmpToAxis).
    #[inline(always)]
    pub fn exit(&self) -> (usize, f32) {
        let t = &self.next_t;
        let bits =
            ((t[0] < t[1]) as usize) << 2 | ((t[0] < t[2]) as usize) << 1 | (t[1] < t[2]) as usize;
        let a = CMP_TO_AXIS[bits];
        (a, t[a])
    }

    /// Crosses into the next cell along axis `a`, the current cell's exit at `t_exit` (from
    /// [`Dda::exit`]); `false` when that leaves the level.
    #[inline(always)]
    pub fn step(&mut self, level: &Level, ray: &Ray, a: usize, t_exit: f32) -> bool {
        self.cell[a] += self.step[a];
        if self.cell[a] == self.out[a] {
            return false;
        }
        self.idx += self.stride[a] * self.step[a] as isize;
        let plane = level.planes[a][(self.cell[a] + self.up[a]) as usize];
        self.next_t[a] = max_keep(t_exit, (plane - ray.origin()[a]) * ray.inv_dir()[a]);
        true
    }

    /// Whether [`Dda::jump`] may move `ray`: its origin is finite and every axis it moves along
    /// has a finite reciprocal direction, so every crossing is a number (never the NaN of
    /// `0 × ∞` or of a NaN origin, which stepping takes as "now") and crossings are monotonic
    /// in the plane index, which the jump's reasoning needs.
    #[inline(always)]
    fn can_jump(ray: &Ray) -> bool {
        let (o, d, inv) = (ray.origin(), ray.dir(), ray.inv_dir());
        // An axis with a zero or NaN component does not move (as `start` decides).
        o.is_finite() && (0..3).all(|a| inv[a].is_finite() || d[a] == 0.0 || d[a].is_nan())
    }

    /// The walk moved through the block of cells within `reach` cells of the current one on
    /// every axis (clipped to the level), which the caller knows to be empty, to the state
    /// stepping would reach: every crossing before the ray leaves the block taken, none after.
    /// `t_exit` is the current cell's exit. `None` for rays [`Dda::can_jump`] refuses, and
    /// unless the ray leaves the block strictly after `t_exit` and at a finite distance and the
    /// walk moves at least one cell (it always does for the rays accepted: the current cell's
    /// exit crossing lies before the block's; the test guards the bound on the walk's length
    /// all the same).
    ///
    /// Why it is exact: each axis's crossings, taken in order, are non-decreasing (the planes
    /// are, and `(plane − o) · inv` is monotonic in the plane), and stepping always takes the
    /// nearest crossing next, so the cells stepped before the block's exit `T` are those whose
    /// crossings lie before `T` on every axis, all in the block; the crossing after them on
    /// each axis is at or beyond `T`, so the state after the jump is the one stepping reaches,
    /// bit for bit, and the walk goes on exactly as stepping would. A cell index is found from
    /// a guess at the point where the ray leaves the block, corrected against the f32 crossings
    /// (the planes are the truth), within the block.
    /// Out of line, and by value: inlined, or taking `&mut self`, it made the whole walk keep
    /// its state in memory, 3–10 % slower on dense scenes where it never runs (measured: see
    /// docs/experiments.md, uniform grid).
    #[inline(never)]
    pub fn jump(&self, level: &Level, ray: &Ray, reach: i32, t_exit: f32) -> Option<Dda> {
        if !Dda::can_jump(ray) {
            return None;
        }
        let (o, d, inv) = (ray.origin(), ray.dir(), ray.inv_dir());
        let crossing = |a: usize, plane: i32| (level.planes[a][plane as usize] - o[a]) * inv[a];
        let mut last = self.cell;
        let mut t_block = f32::INFINITY;
        #[allow(clippy::needless_range_loop)] // `a` indexes the cell, steps, planes and bounds
        for a in 0..3 {
            if self.step[a] != 0 {
                let n = level.res[a] as i32;
                last[a] = (self.cell[a] + self.step[a] * reach).clamp(0, n - 1);
                t_block = t_block.min(crossing(a, last[a] + self.up[a]));
            }
        }
        if !(t_block > t_exit && t_block < f32::INFINITY) {
            return None;
        }
        let mut next = *self;
        let mut moved = false;
        for a in 0..3 {
            let (c, s, up) = (self.cell[a], self.step[a], self.up[a]);
            if s == 0 || last[a] == c {
                continue;
            }
            let crossed = |plane: i32| crossing(a, plane) < t_block;
            // The guess: the cell of the point where the ray leaves the block, kept in the
            // block's span along this axis.
            let p = o[a] + d[a] * t_block;
            let guess = ((p - level.bounds.min[a]) * level.inv_width[a]).floor() as i32;
            let mut i = guess.clamp(c.min(last[a]), c.max(last[a]));
            // Not entered yet: back towards the current cell.
            while i != c && !crossed(i + 1 - up) {
                i -= s;
            }
            // Left already: on towards the block's side.
            while i != last[a] && crossed(i + up) {
                i += s;
            }
            if i != c {
                next.idx += self.stride[a] * (i - c) as isize;
                next.cell[a] = i;
                next.next_t[a] = crossing(a, i + up);
                moved = true;
            }
        }
        moved.then_some(next)
    }
}
