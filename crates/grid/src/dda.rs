//! The one cell walk: Amanatides and Woo's 3D-DDA ("A Fast Voxel Traversal Algorithm for Ray
//! Tracing", Eurographics 1987) over one level of cells, shared by the uniform grid and both
//! levels of the two-level grid.
//!
//! * Entry: the cell of the entry point is found by a floor, clamped (pbrt's `posToVoxel`;
//!   docs/validation.md, B13), then corrected against the cell planes so it is never *ahead* of
//!   the ray on an axis it moves along (that would skip a cell); a cell behind is harmless (its
//!   exit is at once).
//! * Stepping: the next crossing on each axis is recomputed from the f32 cell planes at every
//!   step, never accumulated, so long walks do not drift away from the planes insertion used.
//!   A `±0` direction component never crosses (its crossing is `+inf`; the sign bit, not `< 0`,
//!   picks the step; docs/validation.md, B3).
//! * Termination is the caller's: `visit` gets each cell and its exit distance and says whether
//!   to stop. Otherwise the walk ends when the ray leaves the level. Every iteration steps one
//!   axis towards the level's side, so the walk is bounded by `nx + ny + nz` cells even for NaN
//!   input.

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

impl Level<'_> {
    /// Walks the cells `ray` pierces from `t_enter` (where it is inside [`Level::bounds`]) in
    /// order, calling `visit(cell index, exit distance)` until it returns `true` or the ray
    /// leaves the level.
    #[inline(always)]
    pub fn walk(&self, ray: &Ray, t_enter: f32, mut visit: impl FnMut(usize, f32) -> bool) {
        let o = ray.origin();
        let d = ray.dir();
        let inv = ray.inv_dir();
        let p = o + d * t_enter;
        let min = self.bounds.min;
        let planes = self.planes;
        let mut cell = [0i32; 3];
        let mut step = [0i32; 3];
        // 1 where the next plane is above the cell (positive step).
        let mut up = [0i32; 3];
        // The cell index at which the walk leaves the level on each axis; for an axis that
        // never steps, its own cell, so stepping it (only when every crossing is +inf, which
        // the caller's exit test sees first) would end the walk too.
        let mut out = [0i32; 3];
        let mut next_t = [f32::INFINITY; 3];
        let stride = [
            1isize,
            self.res[0] as isize,
            self.res[0] as isize * self.res[1] as isize,
        ];
        for a in 0..3 {
            let n = self.res[a] as i32;
            let planes = planes[a];
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
        let didx = [0, 1, 2].map(|a| stride[a] * step[a] as isize);
        let mut idx =
            cell[0] as isize + stride[1] * cell[1] as isize + stride[2] * cell[2] as isize;
        loop {
            // The axis of the nearest crossing, without branches (pbrt's cmpToAxis): the
            // cell's exit.
            let bits = ((next_t[0] < next_t[1]) as usize) << 2
                | ((next_t[0] < next_t[2]) as usize) << 1
                | (next_t[1] < next_t[2]) as usize;
            let a = CMP_TO_AXIS[bits];
            let t_exit = next_t[a];
            if visit(idx as usize, t_exit) {
                return;
            }
            cell[a] += step[a];
            if cell[a] == out[a] {
                return;
            }
            idx += didx[a];
            let plane = planes[a][(cell[a] + up[a]) as usize];
            next_t[a] = max_keep(t_exit, (plane - o[a]) * inv[a]);
        }
    }
}
