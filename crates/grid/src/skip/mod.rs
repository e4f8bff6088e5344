//! The skipping grid (`grid-skip`): the uniform grid plus a distance field that lets rays jump
//! over blocks of empty cells (Cohen and Sheffer 1994, "Proximity clouds — an acceleration
//! technique for 3D grid traversal").
//!
//! * Build: the uniform grid exactly as `grid` builds it, then one byte per cell: the Chebyshev
//!   distance, in cells, to the nearest non-empty cell (0 for a non-empty cell, capped at 255),
//!   by a two-pass chamfer transform over the 26 neighbours (`field.rs`).
//! * Traversal: the uniform grid's 3D-DDA, reading the cell's distance `k` instead of its
//!   occupancy bit. A non-empty cell is tested as in `grid`. In an empty cell with
//!   `k >= min_jump`, every cell within `k − 1` cells of it is empty, so the walk jumps to the
//!   state it would reach by stepping to where the ray leaves that block of (2k−1)³ cells
//!   (clipped to the grid), computed from the f32 cell planes (`crate::dda::Dda::jump`).
//!   The jump is exact: the walk then visits the same non-empty cells in the same order as
//!   `grid`, so hits, triangle tests and mailbox skips are `grid`'s bit for bit; only the empty
//!   cells stepped (`cells`) drop, and each jump is counted (`jumps`). A jump must move the ray
//!   strictly forward, or the walk takes a normal step; rays with a direction component so small
//!   that its reciprocal is infinite never jump.
//! * Closest-point queries are the uniform grid's (the field is not used).
//!
//! Trade-off: one byte per cell (eight times the occupancy bitmap) and a build pass over the
//! cells, for walks whose length follows the empty space's shape instead of its size; on dense
//! scenes cells are mostly within one cell of a triangle and the field buys nothing.

mod field;
mod traverse;
mod validate;

use crate::{Grid, GridParams};
use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, Walk};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// The named knobs of a skipping grid, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SkipGridParams {
    /// The uniform grid underneath (λ and the rest).
    pub grid: GridParams,
    /// The walk jumps only from empty cells at least this far (in cells) from a non-empty
    /// one: a jump costs a few steps (the block's exit, a guess and a correction on each
    /// axis), and from a cell at distance 2 it saves one or two.
    pub min_jump: u8,
}

impl SkipGridParams {
    /// 4: against 2, 3, 5, 6 and 8, the fastest or within noise of it on 16 scenes (2 and 3
    /// lose up to 15 % on random rays where 4 breaks even); measured with the `skiptune`
    /// probe, see docs/experiments.md (uniform grid).
    pub const MIN_JUMP: u8 = 4;

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        if *self == SkipGridParams::default() {
            "grid-skip".into()
        } else {
            format!(
                "grid-skip-lambda{}-jump{}",
                self.grid.density, self.min_jump
            )
        }
    }
}

impl Default for SkipGridParams {
    fn default() -> Self {
        SkipGridParams {
            grid: GridParams::default(),
            min_jump: SkipGridParams::MIN_JUMP,
        }
    }
}

/// A uniform grid with a distance field over its cells.
#[derive(Debug)]
pub struct SkipGrid {
    name: String,
    params: SkipGridParams,
    grid: Grid,
    /// Per cell (the grid's linear index): Chebyshev distance in cells to the nearest
    /// non-empty cell, capped at [`field::CAP`]; 0 exactly for non-empty cells.
    distance: Vec<u8>,
    stats: BuildStats,
}

impl SkipGrid {
    pub fn params(&self) -> &SkipGridParams {
        &self.params
    }

    /// The uniform grid underneath.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The distance field's value at cell `(x, y, z)`.
    pub fn distance(&self, x: u32, y: u32, z: u32) -> u8 {
        self.distance[self.grid.layout.index([x, y, z])]
    }

    /// Checks the grid's invariants and the distance field's (see `validate`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        self.grid.validate(mesh)?;
        validate::validate(self)
    }
}

impl Accel for SkipGrid {
    type Params = SkipGridParams;

    fn build(mesh: Arc<TriangleMesh>, params: &SkipGridParams) -> Result<SkipGrid, BuildError> {
        if params.min_jump < 2 {
            return Err(BuildError::Unsupported(format!(
                "min_jump >= 2: a cell at distance 1 has no empty block to jump over (got {})",
                params.min_jump
            )));
        }
        let grid = Grid::build(mesh, &params.grid)?;
        let cells = grid.layout.cells() as u64;
        let needed = grid.memory().total() + field::build_bytes(grid.res);
        if needed > params.grid.memory_limit_bytes {
            return Err(BuildError::TooLarge {
                needed_bytes: needed,
                limit_bytes: params.grid.memory_limit_bytes,
            });
        }
        let distance = field::distance_field(grid.res, |i| grid.occupied(i));
        debug_assert_eq!(distance.len() as u64, cells);
        let mut stats = grid.stats.clone();
        field::add_stats(&distance, params.min_jump, &mut stats.extra);
        Ok(SkipGrid {
            name: params.name(),
            params: params.clone(),
            grid,
            distance,
            stats,
        })
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        self.stats.clone()
    }

    fn memory(&self) -> Memory {
        let grid = self.grid.memory();
        Memory {
            nodes: grid.nodes + self.distance.len() as u64,
            ..grid
        }
    }
}

impl Walk for SkipGrid {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.grid.closest(p, max_radius, c)
    }
}
