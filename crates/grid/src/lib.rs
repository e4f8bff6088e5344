//! raybench-grid: a uniform grid over triangles.
//!
//! The scene's bounding box is cut into `nx × ny × nz` cells of (nearly) cubic shape, about
//! λ·N of them for N triangles ([`GridParams::density`], Cleary and Wyvill 1988). Each
//! triangle is referenced by exactly the cells its exact triangle–box test
//! ([`raybench_geom::tribox`]) says it overlaps, in one compact layout: an offsets array with
//! one entry per cell (plus one) into one reference array, built by a counting sort
//! ([`build`]). Rays walk the cells they pierce in order with the 3D-DDA of Amanatides and Woo
//! (1987), test each triangle once thanks to a small on-stack mailbox, and stop in the first
//! cell whose exit lies beyond the closest hit (`traverse`). Closest-point queries visit the
//! cells in expanding shells around the point's cell and stop when the next shell is farther
//! than the nearest triangle found (`points.rs`).
//!
//! Three registered variants show the "too few / too many cells" trade-off:
//!
//! | name | λ (cells per triangle) |
//! |---|---|
//! | `grid-coarse` | [`GridParams::COARSE_DENSITY`] |
//! | `grid` | [`GridParams::DEFAULT_DENSITY`] |
//! | `grid-fine` | [`GridParams::FINE_DENSITY`] |
//!
//! Grids are the cheapest structure to build and shine on evenly spread detail; they collapse
//! when detail is concentrated (a teapot in a stadium puts the whole teapot into one or two
//! cells), which the reports measure. Two variants attack that: the hierarchical grid
//! ([`two_level`], `grid2`) refines crowded cells, and the skipping grid ([`skip`],
//! `grid-skip`) lets rays jump over empty space with a distance field.
#![forbid(unsafe_code)]

pub mod build;
mod dda;
mod points;
mod reach;
pub mod skip;
mod traverse;
pub mod two_level;
mod validate;

use raybench_accel::{Accel, BuildError, BuildStats, CounterSink, Hit, Memory, PointHit, Walk};
use raybench_geom::tri4::LANES;
use raybench_geom::{Aabb, Ray, Tri4, TriangleMesh, Vec3};
use serde::Serialize;
use std::sync::Arc;

pub use skip::{SkipGrid, SkipGridParams};
pub use two_level::{Grid2, Grid2Params};

/// The named knobs of a uniform grid, written into every report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GridParams {
    /// λ: target number of cells per triangle (the grid has about λ·N cells, cubic as far as
    /// the bounds allow; axes too thin for one cell get one). See the constants for where the
    /// presets were measured.
    pub density: f64,
    /// Most cells along one axis (bounds memory for needle-shaped scenes and caps λ·N).
    pub max_resolution: u32,
    /// The build refuses with [`BuildError::TooLarge`] when its estimate of the memory it
    /// needs (offsets, references, the triangle copies and the temporary pair list) exceeds
    /// this, checked before each allocation, instead of running out of memory.
    pub memory_limit_bytes: u64,
    /// Triangles per rayon task while inserting (work is split only above this).
    pub parallel_chunk: u32,
}

impl GridParams {
    /// λ = 1: against 0.5, 1.5, 2, 3 and 4, the fastest or within 10 % of it on every scene
    /// and workload, and the cheapest build of those, with triangles tested four lanes at a
    /// time (measured: see docs/experiments.md, Uniform grid and octree).
    pub const DEFAULT_DENSITY: f64 = 1.0;
    /// λ = 1/8: "too few cells" (cells hold dozens of triangles).
    pub const COARSE_DENSITY: f64 = 0.125;
    /// λ = 8: "too many cells" (most cells empty; long DDA walks, more references).
    pub const FINE_DENSITY: f64 = 8.0;
    /// 1024 cells per axis.
    pub const MAX_RESOLUTION: u32 = 1024;
    /// 8 GiB.
    pub const MEMORY_LIMIT: u64 = 8 << 30;

    pub fn with_density(density: f64) -> GridParams {
        GridParams {
            density,
            max_resolution: GridParams::MAX_RESOLUTION,
            memory_limit_bytes: GridParams::MEMORY_LIMIT,
            parallel_chunk: 8192,
        }
    }
    pub fn coarse() -> GridParams {
        GridParams::with_density(GridParams::COARSE_DENSITY)
    }
    pub fn fine() -> GridParams {
        GridParams::with_density(GridParams::FINE_DENSITY)
    }

    /// The registered name of this configuration.
    pub fn name(&self) -> String {
        if self.density == GridParams::DEFAULT_DENSITY {
            "grid".into()
        } else if self.density == GridParams::COARSE_DENSITY {
            "grid-coarse".into()
        } else if self.density == GridParams::FINE_DENSITY {
            "grid-fine".into()
        } else {
            format!("grid-lambda{}", self.density)
        }
    }
}

impl Default for GridParams {
    fn default() -> Self {
        GridParams::with_density(GridParams::DEFAULT_DENSITY)
    }
}

/// A built grid. Cell `(x, y, z)` has linear index `x + nx·(y + ny·z)`; its triangles are
/// `refs[offsets[i]..offsets[i + 1]]`, stored four to a [`Tri4`] in Embree's precomputed
/// layout.
#[derive(Debug)]
pub struct Grid {
    name: String,
    params: GridParams,
    /// The mesh's bounds (empty for an empty mesh).
    bounds: Aabb,
    res: [u32; 3],
    /// Cells per unit length on each axis (0 on an axis with one cell).
    inv_width: [f32; 3],
    /// Cell boundaries per axis: `res[a] + 1` planes, the first and last the bounds. Rounded
    /// once from the f64 planes insertion uses ([`build::Layout`]).
    planes: [Vec<f32>; 3],
    /// The f64 geometry insertion used (validate() repeats it exactly).
    layout: build::Layout,
    /// Cell `i`'s references are `refs[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<u32>,
    /// Bit `i` set when cell `i` holds a reference.
    occupied: Vec<u64>,
    /// Triangle ids, ascending within each cell.
    refs: Vec<u32>,
    /// The triangles in mesh order, four to a [`Tri4`]: triangle `i` is lane `i % 4` of
    /// `triangles[i / 4]`.
    triangles: Vec<Tri4>,
    stats: BuildStats,
    /// The mesh, for the exact vertices closest-point queries need (the [`Tri4`]s hold
    /// Möller–Trumbore's edge form, which does not give the vertices back bit for bit).
    mesh: Arc<TriangleMesh>,
}

impl Grid {
    pub fn params(&self) -> &GridParams {
        &self.params
    }

    /// Cells along x, y and z.
    pub fn resolution(&self) -> [u32; 3] {
        self.res
    }

    /// The mesh triangles referenced by cell `(x, y, z)`.
    pub fn cell(&self, x: u32, y: u32, z: u32) -> impl Iterator<Item = u32> + '_ {
        let i = self.layout.index([x, y, z]);
        self.refs[self.offsets[i] as usize..self.offsets[i + 1] as usize]
            .iter()
            .map(|&r| self.mesh_id(r))
    }

    /// The mesh id of internal triangle `i`.
    fn mesh_id(&self, i: u32) -> u32 {
        self.triangles[i as usize / LANES].ids[i as usize % LANES]
    }

    /// Checks the invariants (see `validate`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        validate::validate(self, mesh)
    }
}

impl Accel for Grid {
    type Params = GridParams;

    fn build(mesh: Arc<TriangleMesh>, params: &GridParams) -> Result<Grid, BuildError> {
        if !(params.density > 0.0 && params.density.is_finite())
            || params.max_resolution < 1
            || params.parallel_chunk < 1
        {
            return Err(BuildError::Unsupported(format!(
                "density > 0, max_resolution >= 1, parallel_chunk >= 1 (got {params:?})"
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
        let planes: usize = self
            .planes
            .iter()
            .map(|p| std::mem::size_of_val(p.as_slice()))
            .sum();
        let ids = (self.triangles.len() * LANES * 4) as u64;
        Memory {
            nodes: (std::mem::size_of_val(self.offsets.as_slice())
                + std::mem::size_of_val(self.occupied.as_slice())
                + planes) as u64,
            indices: std::mem::size_of_val(self.refs.as_slice()) as u64 + ids,
            primitives: std::mem::size_of_val(self.triangles.as_slice()) as u64 - ids,
        }
    }
}

impl Walk for Grid {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(&self, p: Vec3, max_radius: f32, c: &mut C) -> Option<PointHit> {
        self.closest(p, max_radius, c)
    }
}
