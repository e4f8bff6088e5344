//! The uniform grid's ray walk, for closest hit and any hit, counted and not: the cells
//! [`crate::dda`] visits, each tested with [`test_cell`], which the two-level grid shares.
//!
//! * Entry: the ray is clipped to the grid's bounds with the NaN-safe slab test.
//! * Termination: the closest hit found so far is kept across cells (a triangle that straddles
//!   cells may be hit beyond the current one), and the walk stops in the first cell whose exit
//!   is at or beyond it — or at the end of the ray or of the grid.
//! * Tests: a cell's references are grouped by the [`raybench_geom::Tri4`] they fall in and
//!   each group is tested four lanes at a time, with lanes the cell does not reference or the
//!   ray has tested already masked out.
//! * Mailbox: a direct-mapped table of the last [`MAILBOX`] triangle ids tested, on the stack
//!   (no allocation, `&self` stays shareable across threads). A triangle met again in a later
//!   cell is skipped: its hit, if any, is already the closest hit so far or was beaten by a
//!   closer one, because hits are kept across cells — so the table needs no hit distances. A
//!   collision only costs a repeated test.

use crate::Grid;
use crate::dda::Level;
use raybench_accel::{CounterSink, Hit};
use raybench_geom::tri4::LANES;
use raybench_geom::{Ray, Tri4, TriHit};

/// Mailbox slots (a power of two). 32, not tuned: a ray rarely meets more distinct straddling
/// triangles between two visits of the same one; the table is 128 bytes, filled once per ray.
pub(crate) const MAILBOX: usize = 32;

/// The per-ray record of tested triangles.
pub(crate) type Mailbox = raybench_accel::Mailbox<MAILBOX>;

/// What a ray carries from cell to cell (and level to level): the closest hit so far and the
/// record of tested triangles.
pub(crate) struct Probe {
    pub best_t: f32,
    pub best: Option<(u32, TriHit)>,
    pub mailbox: Mailbox,
}

impl Probe {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Probe {
        Probe {
            best_t: ray.t_max(),
            best: None,
            mailbox: Mailbox::new(),
        }
    }

    /// Whether a walk may stop after a cell that ends at `t_exit`: the closest hit lies in it
    /// (or before), so nothing further can beat it; also when the ray itself ends there or
    /// never leaves (exit = inf).
    #[inline(always)]
    pub fn done<const ANY_HIT: bool>(&self, t_exit: f32) -> bool {
        self.best_t <= t_exit || (ANY_HIT && self.best.is_some())
    }

    #[inline(always)]
    pub fn hit(self) -> Option<Hit> {
        self.best.map(|(prim, h)| Hit::from_tri_hit(prim, h))
    }
}

/// Tests the triangles of one cell, `list` (internal ids, ascending), against `ray`.
#[inline(always)]
pub(crate) fn test_cell<const ANY_HIT: bool, C: CounterSink>(
    list: &[u32],
    triangles: &[Tri4],
    ray: &Ray,
    probe: &mut Probe,
    c: &mut C,
) {
    let mut i = 0;
    while i < list.len() {
        // The run of references in one Tri4 (lists are ascending), minus the triangles this
        // ray has tested already.
        let group = list[i] as usize / LANES;
        let mut active = 0u32;
        while i < list.len() && list[i] as usize / LANES == group {
            let id = list[i];
            i += 1;
            if probe.mailbox.seen(id) {
                c.mailbox_skip();
            } else {
                active |= 1 << (id as usize % LANES);
            }
        }
        if active == 0 {
            continue;
        }
        c.prim_tests(active.count_ones() as u64);
        let four = &triangles[group];
        let hits = four.test(ray, probe.best_t);
        let mut mask = hits.mask & active;
        if mask == 0 {
            continue;
        }
        // Every hit lane passed the test against the closest hit so far; keep the closest of
        // them (ties: the later lane, as a sequential scan would).
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
            probe.best_t = h.t;
            probe.best = Some((four.ids[l], h));
            if ANY_HIT {
                return;
            }
        }
    }
}

impl Grid {
    /// The grid's cells as a [`Level`] for the DDA.
    pub(crate) fn level(&self) -> Level<'_> {
        Level {
            bounds: self.bounds,
            res: self.res,
            inv_width: self.inv_width,
            planes: [&self.planes[0], &self.planes[1], &self.planes[2]],
        }
    }

    /// Whether cell `u` holds a reference (the occupancy bitmap, one bit per cell and small
    /// enough to stay in cache, spares empty cells the load of their offsets).
    #[inline(always)]
    pub(crate) fn occupied(&self, u: usize) -> bool {
        self.occupied[u >> 6] >> (u & 63) & 1 != 0
    }

    /// Cell `u`'s references.
    #[inline(always)]
    pub(crate) fn list(&self, u: usize) -> &[u32] {
        &self.refs[self.offsets[u] as usize..self.offsets[u + 1] as usize]
    }

    /// The cell's references, or `None` for an empty cell.
    #[inline(always)]
    pub(crate) fn cell_refs(&self, u: usize) -> Option<&[u32]> {
        self.occupied(u).then(|| self.list(u))
    }

    pub(crate) fn triangles(&self) -> &[Tri4] {
        &self.triangles
    }

    pub(crate) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.refs.is_empty() {
            return None;
        }
        let (t_enter, _) = self.bounds.intersect(ray)?;
        let mut probe = Probe::new(ray);
        self.level().walk(ray, t_enter, |u, t_exit| {
            c.cell();
            if let Some(list) = self.cell_refs(u) {
                test_cell::<ANY_HIT, C>(list, &self.triangles, ray, &mut probe, c);
            }
            probe.done::<ANY_HIT>(t_exit)
        });
        probe.hit()
    }
}
