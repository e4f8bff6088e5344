//! The skipping walk: the uniform grid's DDA and cell tests, with a jump over the block of
//! empty cells around any cell far enough from a non-empty one (see the module note of
//! [`super`]). The closest-hit bookkeeping, the termination test and the mailbox are the
//! uniform grid's ([`Probe`]).

use super::SkipGrid;
use crate::traverse::{Probe, test_cell};
use raybench_accel::{CounterSink, Hit};
use raybench_geom::Ray;

impl SkipGrid {
    pub(crate) fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        let grid = &self.grid;
        if grid.refs.is_empty() {
            return None;
        }
        let (t_enter, _) = grid.bounds.intersect(ray)?;
        let level = grid.level();
        let min_jump = self.params.min_jump;
        let mut probe = Probe::new(ray);
        let mut dda = level.start(ray, t_enter);
        loop {
            let (a, t_exit) = dda.exit();
            let u = dda.index();
            c.cell();
            // The occupancy bitmap (8× smaller than the field) decides first, so cells near
            // triangles cost what they cost in `grid`; only empty cells read their distance.
            let k = if grid.occupied(u) {
                test_cell::<ANY_HIT, C>(grid.list(u), grid.triangles(), ray, &mut probe, c);
                0
            } else {
                self.distance[u]
            };
            if probe.done::<ANY_HIT>(t_exit) {
                break;
            }
            // Every cell within k − 1 of this one is empty.
            if k >= min_jump
                && let Some(next) = dda.jump(&level, ray, k as i32 - 1, t_exit)
            {
                dda = next;
                c.jump();
                continue;
            }
            if !dda.step(&level, ray, a, t_exit) {
                break;
            }
        }
        probe.hit()
    }
}
