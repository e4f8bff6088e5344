//! The one traversal loop: Amanatides and Woo's 3D-DDA ("A Fast Voxel Traversal Algorithm for
//! Ray Tracing", Eurographics 1987), for closest hit and any hit, counted and not.
//!
//! * Entry: the ray is clipped to the grid's bounds with the NaN-safe slab test, and the cell of
//!   the entry point is found by a floor, clamped (pbrt's `posToVoxel`; docs/validation.md, B13),
//!   then corrected against the cell planes so it is never *ahead* of the ray on an axis it moves
//!   along (that would skip a cell); a cell behind is harmless (its exit is at once).
//! * Stepping: the next crossing on each axis is recomputed from the f32 cell planes at every
//!   step, never accumulated, so long walks do not drift away from the planes insertion used.
//!   A `±0` direction component never crosses (its crossing is `+inf`; the sign bit, not `< 0`,
//!   picks the step; docs/validation.md, B3).
//! * Termination: the closest hit found so far is kept across cells (a triangle that straddles
//!   cells may be hit beyond the current one), and the walk stops in the first cell whose exit
//!   is at or beyond it — or at the end of the ray or of the grid. Every iteration steps one
//!   axis towards the grid's side, so the walk is bounded by `nx + ny + nz` cells even for NaN
//!   input.
//! * Tests: a cell's references are grouped by the [`raybench_geom::Tri4`] they fall in and
//!   each group is tested four lanes at a time, with lanes the cell does not reference or the
//!   ray has tested already masked out.
//! * Mailbox: a direct-mapped table of the last [`MAILBOX`] triangle ids tested, on the stack
//!   (no allocation, `&self` stays shareable across threads). A triangle met again in a later
//!   cell is skipped: its hit, if any, is already the closest hit so far or was beaten by a
//!   closer one, because hits are kept across cells — so the table needs no hit distances. A
//!   collision only costs a repeated test.

use crate::Grid;
use raybench_accel::{CounterSink, Hit};
use raybench_geom::tri4::LANES;
use raybench_geom::{Ray, TriHit, max_keep};

/// Mailbox slots (a power of two). 32, not tuned: a ray rarely meets more distinct straddling
/// triangles between two visits of the same one; the table is 128 bytes, filled once per ray.
pub(crate) const MAILBOX: usize = 32;

/// The axis with the smallest of three crossings, indexed by the bits
/// `t0 < t1`, `t0 < t2`, `t1 < t2` (two entries are unreachable).
const CMP_TO_AXIS: [usize; 8] = [2, 1, 2, 1, 2, 2, 0, 0];

/// The per-ray record of tested triangles.
pub(crate) type Mailbox = raybench_accel::Mailbox<MAILBOX>;

impl Grid {
    pub(crate) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.refs.is_empty() {
            return None;
        }
        let (t_enter, _) = self.bounds.intersect(ray)?;
        let o = ray.origin();
        let d = ray.dir();
        let inv = ray.inv_dir();
        let p = o + d * t_enter;
        let min = self.bounds.min;

        let planes: [&[f32]; 3] = [&self.planes[0], &self.planes[1], &self.planes[2]];
        let mut cell = [0i32; 3];
        let mut step = [0i32; 3];
        // 1 where the next plane is above the cell (positive step).
        let mut up = [0i32; 3];
        // The cell index at which the walk leaves the grid on each axis; for an axis that
        // never steps, its own cell, so stepping it (only when every crossing is +inf, which
        // the exit test catches first) would end the walk too.
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

        let mut best_t = ray.t_max();
        let mut best: Option<(u32, TriHit)> = None;
        let mut mailbox = Mailbox::new();
        loop {
            c.cell();
            // The axis of the nearest crossing, without branches (pbrt's cmpToAxis): the
            // cell's exit.
            let bits = ((next_t[0] < next_t[1]) as usize) << 2
                | ((next_t[0] < next_t[2]) as usize) << 1
                | (next_t[1] < next_t[2]) as usize;
            let a = CMP_TO_AXIS[bits];
            let t_exit = next_t[a];
            let u = idx as usize;
            // The occupancy bitmap (1 bit per cell, small enough to stay in cache) spares
            // empty cells the load of their offsets.
            if self.occupied[u >> 6] >> (u & 63) & 1 != 0 {
                let first = self.offsets[u] as usize;
                let last = self.offsets[u + 1] as usize;
                let list = &self.refs[first..last];
                let mut i = 0;
                while i < list.len() {
                    // The run of references in one Tri4 (lists are ascending), minus the
                    // triangles this ray has tested already.
                    let group = list[i] as usize / LANES;
                    let mut active = 0u32;
                    while i < list.len() && list[i] as usize / LANES == group {
                        let id = list[i];
                        i += 1;
                        if mailbox.seen(id) {
                            c.mailbox_skip();
                        } else {
                            active |= 1 << (id as usize % LANES);
                        }
                    }
                    if active == 0 {
                        continue;
                    }
                    c.prim_tests(active.count_ones() as u64);
                    let four = &self.triangles[group];
                    let hits = four.test(ray, best_t);
                    let mut mask = hits.mask & active;
                    if mask == 0 {
                        continue;
                    }
                    // Every hit lane passed the test against the closest hit so far; keep the
                    // closest of them (ties: the later lane, as a sequential scan would).
                    let mut pick: Option<(usize, TriHit)> = None;
                    while mask != 0 {
                        let l = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let h = hits.get(l);
                        if pick.is_none_or(|(_, p)| h.t <= p.t) {
                            pick = Some((l, h));
                        }
                    }
                    if let Some((l, h)) = pick {
                        best_t = h.t;
                        best = Some((four.ids[l], h));
                        if ANY_HIT {
                            break;
                        }
                    }
                }
            }
            // The closest hit lies in this cell (or before): nothing further can beat it. Also
            // ends the walk when the ray itself ends here, or never leaves (exit = inf).
            if best_t <= t_exit || (ANY_HIT && best.is_some()) {
                break;
            }
            cell[a] += step[a];
            if cell[a] == out[a] {
                break;
            }
            idx += didx[a];
            let plane = planes[a][(cell[a] + up[a]) as usize];
            next_t[a] = max_keep(t_exit, (plane - o[a]) * inv[a]);
        }
        best.map(|(prim, h)| Hit::from_tri_hit(prim, h))
    }
}
