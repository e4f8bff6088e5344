//! The two-level grid (`grid2`): a coarse uniform grid whose crowded cells hold grids of their
//! own, sized by their triangle counts (Jevans and Wyvill 1989, "Adaptive voxel subdivision for
//! ray tracing"; Kalojanov, Billeter and Slusallek 2011, "Two-level grids for ray tracing on
//! GPUs").
//!
//! * The top grid is a [`Grid`] with about `top_density · N` cells, built and stored exactly as
//!   the uniform grid is (exact insertion, one offsets array, the Tri4s in mesh order). Its
//!   cell lists serve the cells that get no grid of their own, and closest-point queries, which
//!   search the top grid's shells.
//! * A top cell holding `k` triangles gets about `cell_density · k` cells of its own, over the
//!   part of the cell its triangles occupy (their bounds clipped to the cell, both enlarged by
//!   the insertion margin), not over the whole cell: a teapot in one stadium cell gets its grid
//!   around the teapot, so the detail is resolved however small it is against the stadium.
//!   A cell whose own grid would have one cell, would not pay by the cost model, or would put
//!   its triangles all in the same cells (copies of one triangle) keeps its list. Within a
//!   cell grid, a cell still holding more than `crowded` triangles gets a grid of its own the
//!   same way, down to `max_levels` levels: a teapot at 1e-5 of its stadium is several orders
//!   of magnitude below one level's resolution, and each level resolves about two.
//! * A ray walks the top grid with the 3D-DDA; in a cell with a grid of its own it clips itself
//!   to that grid's box and walks it with the same DDA (and so on down), one mailbox and one
//!   closest hit for the whole ray. Every walk stops at the first cell whose exit lies beyond
//!   the closest hit.
//!
//! Trade-off: a second level costs a box test and a DDA setup per crowded top cell crossed,
//! and a top-cell list plus the cell grids' lists in memory; it buys a resolution that follows
//! the triangle density, which one uniform resolution cannot (the seeds' teapot in a stadium).

mod build;
mod traverse;
mod validate;

use crate::{Grid, GridParams};
use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, Walk};
use raybench_geom::{Aabb, Ray, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

/// The named knobs of a two-level grid, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Grid2Params {
    /// λ₁: top-grid cells per triangle.
    pub top_density: f64,
    /// λ₂: cells per triangle in each top cell's own grid.
    pub cell_density: f64,
    /// Most top cells along one axis.
    pub max_resolution: u32,
    /// Most cells along one axis of a cell's own grid.
    pub max_cell_resolution: u32,
    /// Levels of grids, the top one included (2: Kalojanov's two-level grid).
    pub max_levels: u32,
    /// A cell is offered a grid of its own only when it holds more than this many triangles.
    pub crowded: u32,
    /// The cost of entering a cell grid (a box test, the DDA's setup, its descriptor and
    /// planes), in triangle tests: a cell keeps its list unless walking its grid costs less.
    pub entry_cost: f64,
    /// The cost of stepping one cell (a cache line or two of offsets and occupancy, the DDA's
    /// comparisons), in triangle tests.
    pub cell_cost: f64,
    /// The most references per triangle of its list a cell's grid may make: a grid making more
    /// is refused and the cell keeps its list. See [`Grid2Params::MAX_REFS_PER_TRIANGLE`].
    pub max_refs_per_triangle: u32,

    /// The build refuses with [`BuildError::TooLarge`] past this estimate of its memory.
    pub memory_limit_bytes: u64,
    /// Triangles per rayon task while inserting into the top grid.
    pub parallel_chunk: u32,
}

impl Grid2Params {
    /// See docs/experiments.md (two-level grid) for where the densities were measured.
    pub const TOP_DENSITY: f64 = 1.0;
    pub const CELL_DENSITY: f64 = 2.0;
    pub const MAX_CELL_RESOLUTION: u32 = 128;
    pub const MAX_LEVELS: u32 = 3;

    pub const CROWDED: u32 = 8;
    pub const ENTRY_COST: f64 = 8.0;
    pub const CELL_COST: f64 = 4.0;
    /// Why a cap besides the cost model: triangles that all cross one point fill about
    /// `(cell_density · k)^(2/3)` cells each of a grid for `k` of them, and the cost model,
    /// pricing the mean cell against a list of `k`, still accepts such grids, so references and
    /// build time grow as `k^(5/3)` per crowded cell (10,000 triangles through one point: 2,300
    /// references per triangle, a 52 s build). Accepted grids of the shared and generated
    /// scenes make at most 24 per triangle (a 500k-triangle sphere's poles; conference 19), 56
    /// on the adversarial `fan` at 50k triangles, so 64 binds only on such piles, and it bounds
    /// every cell's insertion.
    pub const MAX_REFS_PER_TRIANGLE: u32 = 64;
    /// The most levels a build accepts (the walk recurses once per level).
    pub const LEVEL_LIMIT: u32 = 8;

    /// Grids in nearly every cell, six levels deep (a top grid of 1/16 cell per triangle, no
    /// crowding threshold, free entries and steps): a stress configuration that exercises
    /// every level on small scenes, not a fast one.
    pub fn deep() -> Grid2Params {
        Grid2Params {
            top_density: 1.0 / 16.0,
            crowded: 0,
            max_levels: 6,
            entry_cost: 0.0,
            cell_cost: 0.0,
            ..Grid2Params::default()
        }
    }

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        if *self == Grid2Params::default() {
            "grid2".into()
        } else {
            format!(
                "grid2-top{}-cell{}-levels{}",
                self.top_density, self.cell_density, self.max_levels
            )
        }
    }

    fn top(&self) -> GridParams {
        GridParams {
            density: self.top_density,
            max_resolution: self.max_resolution,
            memory_limit_bytes: self.memory_limit_bytes,
            parallel_chunk: self.parallel_chunk,
        }
    }
}

impl Default for Grid2Params {
    fn default() -> Self {
        Grid2Params {
            top_density: Grid2Params::TOP_DENSITY,
            cell_density: Grid2Params::CELL_DENSITY,
            max_resolution: GridParams::MAX_RESOLUTION,
            max_cell_resolution: Grid2Params::MAX_CELL_RESOLUTION,
            max_levels: Grid2Params::MAX_LEVELS,
            crowded: Grid2Params::CROWDED,
            entry_cost: Grid2Params::ENTRY_COST,
            cell_cost: Grid2Params::CELL_COST,
            max_refs_per_triangle: Grid2Params::MAX_REFS_PER_TRIANGLE,

            memory_limit_bytes: GridParams::MEMORY_LIMIT,
            parallel_chunk: 8192,
        }
    }
}

/// A cell's own grid: its box (the DDA clips rays to it), resolution and where its planes and
/// cells start in [`Grid2`]'s shared arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CellGrid {
    bounds: Aabb,
    res: [u32; 3],
    inv_width: [f32; 3],
    /// Start of each axis's `res[a] + 1` planes in [`Grid2::planes`].
    planes: [u32; 3],
    /// Index of its first cell in [`Grid2::child`], [`Grid2::offsets`] and the occupancy bits.
    first_cell: u32,
}

/// A built two-level grid.
#[derive(Debug)]
pub struct Grid2 {
    name: String,
    params: Grid2Params,
    top: Grid,
    /// Per top cell, the index of its own grid plus one, or 0 when its list is tested as is.
    grid_of: Vec<u32>,
    grids: Vec<CellGrid>,
    /// The cell planes of every cell grid, in f32, rounded from the f64 planes insertion used.
    planes: Vec<f32>,
    /// Per cell of the cell grids (counted over all of them, each grid's cells together, grids
    /// in depth-first order): the index of its own grid plus one, or 0.
    child: Vec<u32>,
    /// Cell `g` without a grid of its own holds `refs[offsets[g]..offsets[g + 1]]`, mesh ids
    /// ascending (a cell with a grid holds none).
    offsets: Vec<u32>,
    /// Bit `g` set when cell `g` holds a reference or a grid.
    occupied: Vec<u64>,
    refs: Vec<u32>,
    stats: BuildStats,
}

impl Grid2 {
    pub fn params(&self) -> &Grid2Params {
        &self.params
    }

    /// The top grid.
    pub fn top(&self) -> &Grid {
        &self.top
    }

    /// How many cells, at any level, have a grid of their own.
    pub fn cell_grids(&self) -> usize {
        self.grids.len()
    }

    /// Checks the invariants (see `validate`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        validate::validate(self, mesh)
    }
}

impl Accel for Grid2 {
    type Params = Grid2Params;

    fn build(mesh: Arc<TriangleMesh>, params: &Grid2Params) -> Result<Grid2, BuildError> {
        let ok = |x: f64| x > 0.0 && x.is_finite();
        let cost = |x: f64| x >= 0.0 && x.is_finite();
        if !ok(params.top_density)
            || !ok(params.cell_density)
            || !cost(params.entry_cost)
            || !cost(params.cell_cost)
            || params.max_resolution < 1
            || params.max_cell_resolution < 1
            || params.max_refs_per_triangle < 1
            || !(1..=Grid2Params::LEVEL_LIMIT).contains(&params.max_levels)
            || params.parallel_chunk < 1
        {
            return Err(BuildError::Unsupported(format!(
                "densities > 0, costs >= 0, resolutions >= 1, max_refs_per_triangle >= 1, \
                 max_levels in 1..={}, parallel_chunk >= 1 (got {params:?})",
                Grid2Params::LEVEL_LIMIT
            )));
        }
        build::build(&mesh, params)
    }

    fn name(&self) -> &str {
        &self.name
    }

    raybench_accel::walk_queries!();

    fn build_stats(&self) -> BuildStats {
        self.stats.clone()
    }

    fn memory(&self) -> Memory {
        let top = self.top.memory();
        Memory {
            nodes: top.nodes
                + (std::mem::size_of_val(self.grid_of.as_slice())
                    + std::mem::size_of_val(self.grids.as_slice())
                    + std::mem::size_of_val(self.planes.as_slice())
                    + std::mem::size_of_val(self.child.as_slice())
                    + std::mem::size_of_val(self.offsets.as_slice())
                    + std::mem::size_of_val(self.occupied.as_slice())) as u64,
            indices: top.indices + std::mem::size_of_val(self.refs.as_slice()) as u64,
            primitives: top.primitives,
        }
    }
}

impl Walk for Grid2 {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.top.closest(p, max_radius, c)
    }
}
