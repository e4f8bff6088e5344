//! The hierarchical walk: the top grid's DDA, and in each cell with a grid of its own the DDA
//! of that grid, clipped to its box and to the closest hit so far, recursively. One [`Probe`]
//! (closest hit and mailbox) serves the whole ray, so a triangle met in several cells, at any
//! level, is tested once; every walk stops at the first cell whose exit lies beyond the
//! closest hit. Every cell stepped, at any level, is counted as a cell.

use super::{CellGrid, Grid2};
use crate::dda::Level;
use crate::traverse::{Probe, test_cell};
use raybench_accel::{CounterSink, Hit};
use raybench_geom::Ray;

impl Grid2 {
    fn level_of(&self, g: &CellGrid) -> Level<'_> {
        let axis = |a: usize| {
            let start = g.planes[a] as usize;
            &self.planes[start..start + g.res[a] as usize + 1]
        };
        Level {
            bounds: g.bounds,
            res: g.res,
            inv_width: g.inv_width,
            planes: [axis(0), axis(1), axis(2)],
        }
    }

    pub(crate) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        let top = &self.top;
        if top.refs.is_empty() {
            return None;
        }
        let (t_enter, _) = top.bounds.intersect(ray)?;
        let mut probe = Probe::new(ray);
        top.level().walk(ray, t_enter, |u, t_exit| {
            c.cell();
            // A cell with a grid of its own also keeps its list (for closest points): its
            // offsets are not loaded.
            if top.occupied(u) {
                match self.grid_of[u] {
                    0 => test_cell::<ANY_HIT, C>(top.list(u), top.triangles(), ray, &mut probe, c),
                    k => self.walk_grid::<ANY_HIT, C>(k, ray, &mut probe, c),
                }
            }
            probe.done::<ANY_HIT>(t_exit)
        });
        probe.hit()
    }

    /// Walks cell grid `k - 1` (and the grids of its cells), clipped to its box and to the
    /// closest hit so far.
    fn walk_grid<const ANY_HIT: bool, C: CounterSink>(
        &self,
        k: u32,
        ray: &Ray,
        probe: &mut Probe,
        c: &mut C,
    ) {
        let g = &self.grids[k as usize - 1];
        let clipped =
            g.bounds
                .intersect_interval(ray.origin(), ray.inv_dir(), ray.t_min(), probe.best_t);
        let Some((t0, _)) = clipped else {
            return;
        };
        let first = g.first_cell as usize;
        self.level_of(g).walk(ray, t0, |v, t_exit| {
            c.cell();
            let i = first + v;
            if self.occupied[i >> 6] >> (i & 63) & 1 != 0 {
                match self.child[i] {
                    0 => {
                        let list =
                            &self.refs[self.offsets[i] as usize..self.offsets[i + 1] as usize];
                        test_cell::<ANY_HIT, C>(list, self.top.triangles(), ray, probe, c);
                    }
                    k => self.walk_grid::<ANY_HIT, C>(k, ray, probe, c),
                }
            }
            probe.done::<ANY_HIT>(t_exit)
        });
    }
}
