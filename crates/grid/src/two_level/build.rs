//! Hierarchical grid construction: the top grid as the uniform grid builds it, then, in
//! parallel over the top cells, each cell's own grid with the same exact insertion (its
//! triangles clipped to the cell, [`Layout::for_each_cell_clipped`]), recursing into crowded
//! cells, then one depth-first pass that lays all cell grids end to end in shared arrays.
//! References are counted as they are emitted and the build stops with
//! [`BuildError::TooLarge`] past the memory limit, as the uniform grid's does.

use super::{CellGrid, Grid2, Grid2Params};
use crate::Grid;
use crate::build::{Layout, resolution};
use raybench_accel::{Accel, BuildError, BuildStats};
use raybench_geom::{Aabb, DVec3, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The layout of the grid a cell gets for its triangles `list`, or `None` when it keeps the
/// list (its grid would have one cell): `cell_density · k` cells for `k` triangles over the box
/// their bounds occupy within the cell `(plo, phi)` (enlarged), itself enlarged by the
/// insertion margin `m` and clipped to the cell (so the box holds every point of every
/// triangle the cell references, and the DDA's rounding is covered as at the top level). Build
/// and `validate()` both call it, through [`own_grid`].
fn cell_layout(
    mesh: &TriangleMesh,
    list: &[u32],
    (plo, phi): (DVec3, DVec3),
    m: f64,
    params: &Grid2Params,
) -> Option<Layout> {
    let (lo, hi) = list
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &id| {
            let b = mesh.triangle(id as usize).bounds();
            (lo.min(b.min.as_dvec3()), hi.max(b.max.as_dvec3()))
        });
    let lo = (lo - DVec3::splat(m)).max(plo);
    let hi = (hi + DVec3::splat(m)).min(phi);
    if list.is_empty() || !lo.cmple(hi).all() {
        return None;
    }
    let e = hi - lo;
    let res = resolution(
        e.to_array(),
        list.len(),
        params.cell_density,
        params.max_cell_resolution,
    );
    // Cells no narrower than MARGINS_PER_CELL margins: below that every enlarged cell
    // overlaps its neighbours' triangles and a grid only copies its list.
    let res: [u32; 3] = std::array::from_fn(|a| {
        let fit = (e[a] / (MARGINS_PER_CELL * m)).floor().max(1.0);
        res[a].min(if fit < u32::MAX as f64 {
            fit as u32
        } else {
            u32::MAX
        })
    });
    (res != [1, 1, 1]).then(|| Layout::over(lo, hi, res, m))
}

/// The narrowest cell a cell grid may have, in insertion margins. The margin is a few f32
/// steps of the scene's largest coordinate (what the f32 DDA may be off by along a ray across
/// the scene), so it is the floor of a grid's resolution, at any level: a teapot at 1e-5 of
/// its stadium is only about 20 margins wide.
const MARGINS_PER_CELL: f64 = 4.0;

/// Whether a cell of a grid at `level` (the top grid is level 0) holding `k` triangles may get
/// a grid of its own: when it is crowded, at any level but the last.
fn may_subdivide(level: u32, k: usize, params: &Grid2Params) -> bool {
    level + 1 < params.max_levels && k > params.crowded as usize
}

/// The cells a triangle list falls into in `layout`, as (offsets, references): cell `c` holds
/// `refs[offsets[c]..offsets[c + 1]]`, in the list's (ascending) order; `None` as soon as
/// `keep` refuses the references so far (the test only grows stricter with more, so the grid
/// would be refused anyway: long triangles crossing many cells stop early instead of being
/// inserted in full).
fn insert(
    mesh: &TriangleMesh,
    list: &[u32],
    layout: &Layout,
    keep: impl Fn(usize) -> bool,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(list.len() * 2);
    for &id in list {
        layout.for_each_cell_clipped(&mesh.triangle(id as usize), |c| pairs.push((c as u32, id)));
        if !keep(pairs.len()) {
            return None;
        }
    }
    let cells = layout.cells();
    let mut offsets = vec![0u32; cells + 1];
    for &(c, _) in &pairs {
        offsets[c as usize + 1] += 1;
    }
    for c in 0..cells {
        offsets[c + 1] += offsets[c];
    }
    let mut next = offsets.clone();
    let mut refs = vec![0u32; pairs.len()];
    for &(c, id) in &pairs {
        refs[next[c as usize] as usize] = id;
        next[c as usize] += 1;
    }
    Some((offsets, refs))
}

/// A grid and its cells' lists: cell `c` holds `refs[offsets[c]..offsets[c + 1]]`.
pub(super) struct Inserted {
    pub layout: Layout,
    pub offsets: Vec<u32>,
    pub refs: Vec<u32>,
}

impl Inserted {
    pub fn list(&self, c: usize) -> &[u32] {
        &self.refs[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }
}

/// The grid a cell of a grid at `level` (the top grid is level 0) gets for its triangles
/// `list`, inserted, or `None` when it keeps its list: the cell must be crowded
/// ([`may_subdivide`]), its grid more than one cell ([`cell_layout`]; `cell` is the cell's
/// enlarged box, `m` the insertion margin), [`worth_it`] (first with one reference per
/// triangle, before paying for the insertion), able to tell the list's triangles apart
/// ([`separates`]) and within [`Grid2Params::max_refs_per_triangle`]. Build and `validate()`
/// both decide with it.
pub(super) fn own_grid(
    mesh: &TriangleMesh,
    list: &[u32],
    cell: (DVec3, DVec3),
    m: f64,
    level: u32,
    params: &Grid2Params,
) -> Option<Inserted> {
    if !may_subdivide(level, list.len(), params) {
        return None;
    }
    let layout = cell_layout(mesh, list, cell, m, params)?;
    if !worth_it(list.len(), list.len(), &layout, params) || !separates(mesh, list, &layout) {
        return None;
    }
    // Checked after every triangle, so a grid that comes back passed with all its references.
    let most = list.len() as u64 * params.max_refs_per_triangle as u64;
    let keep = |refs: usize| refs as u64 <= most && worth_it(refs, list.len(), &layout, params);
    let (offsets, refs) = insert(mesh, list, &layout, keep)?;
    Some(Inserted {
        layout,
        offsets,
        refs,
    })
}

/// Triangles of a list that [`separates`] inserts: the first, the middle and the last.
const SAMPLES: usize = 3;

/// Whether `layout` puts the triangles of `list` into different cells, judged on [`SAMPLES`]
/// of them spread over the list. When every sampled triangle lands in exactly the same cells
/// (copies of one triangle, say), the grid would copy the whole list into each of those cells,
/// whose own grids would do the same again down to the last level, each insertion testing every
/// triangle against every cell its box covers: for `k` copies of a triangle across the cell,
/// about `k` times the grid's `cell_density · k` cells a level, so a thousand copies cost
/// billions of triangle-cell tests. [`worth_it`] cannot see this: it prices the mean cell, and
/// the copies crowd a few cells of an otherwise empty grid. The check inserts three triangles
/// where the insertion would insert them all; a list it refuses stays a list, which costs only
/// speed where the sample misjudges.
fn separates(mesh: &TriangleMesh, list: &[u32], layout: &Layout) -> bool {
    let cells_of = |id: u32| {
        let mut cells = Vec::new();
        layout.for_each_cell_clipped(&mesh.triangle(id as usize), |c| cells.push(c));
        cells
    };
    let last = list.len() - 1;
    let first = cells_of(list[0]);
    (1..SAMPLES).any(|s| cells_of(list[s * last / (SAMPLES - 1)]) != first)
}

/// A cell grid being built: its cells' lists (also those of cells with a grid of their own,
/// which the assembly drops) and its cells' own grids.
struct Filled {
    grid: Inserted,
    children: Vec<(usize, Filled)>,
}

struct Ctx<'a> {
    mesh: &'a TriangleMesh,
    params: &'a Grid2Params,
    margin: f64,
    budget: u64,
    emitted: AtomicU64,
}

/// Whether a grid `layout` whose insertion made `refs` references for `k` triangles is kept:
/// when a ray crossing it (entering it, then stepping through about `(nx + ny + nz) / 2` cells
/// holding `refs / cells` triangles each) costs less than testing the `k` triangles of the list
/// it replaces, with the costs of [`Grid2Params`] in units of one triangle test. Triangles
/// crossing at one point, or much larger than the cells, fill every cell and fail this, so
/// they are not copied again level after level; so do cells of a few triangles, which a list
/// serves faster than a walk.
fn worth_it(refs: usize, k: usize, layout: &Layout, params: &Grid2Params) -> bool {
    let steps = layout.res.iter().sum::<u32>() as f64 / 2.0;
    let per_cell = refs as f64 / layout.cells() as f64;
    let walk = params.entry_cost + steps * (params.cell_cost + per_cell);
    walk < k as f64
}

/// Counts `grid`'s references against the memory budget, then builds the grids of its
/// cells (it is a grid at `level`), recursively.
fn fill(ctx: &Ctx, grid: Inserted, level: u32) -> Result<Filled, ()> {
    let added = grid.refs.len() as u64;
    if ctx.emitted.fetch_add(added, Ordering::Relaxed) + added > ctx.budget {
        return Err(());
    }
    let children = (0..grid.layout.cells())
        .into_par_iter()
        .filter_map(|c| {
            let cell = grid.layout.cell_box(grid.layout.coords(c));
            let own = own_grid(ctx.mesh, grid.list(c), cell, ctx.margin, level, ctx.params)?;
            Some(fill(ctx, own, level + 1).map(|f| (c, f)))
        })
        .collect::<Result<Vec<_>, ()>>()?;
    Ok(Filled { grid, children })
}

/// Bytes per cell-grid reference at the build's peak: the (cell, triangle) pair, the list
/// and the final reference.
const PEAK_BYTES_PER_REF: u64 = 8 + 4 + 4;

fn too_large(needed_bytes: u64, params: &Grid2Params) -> BuildError {
    BuildError::TooLarge {
        needed_bytes,
        limit_bytes: params.memory_limit_bytes,
    }
}

pub(super) fn build(mesh: &Arc<TriangleMesh>, params: &Grid2Params) -> Result<Grid2, BuildError> {
    let top = crate::build::build(mesh, &params.top())?;
    let top_cells = top.layout.cells();
    let base = top.memory().total() + top_cells as u64 * 4;
    if base > params.memory_limit_bytes {
        return Err(too_large(base, params));
    }
    let ctx = Ctx {
        mesh,
        params,
        margin: top.layout.margin,
        budget: (params.memory_limit_bytes - base) / PEAK_BYTES_PER_REF,
        emitted: AtomicU64::new(0),
    };
    let filled: Vec<(usize, Filled)> = (0..top_cells)
        .into_par_iter()
        .filter_map(|u| {
            let cell = top.layout.cell_box(top.layout.coords(u));
            let own = own_grid(mesh, top.cell_refs(u)?, cell, ctx.margin, 0, params)?;
            Some(fill(&ctx, own, 1).map(|f| (u, f)))
        })
        .collect::<Result<_, ()>>()
        .map_err(|()| {
            too_large(
                base + ctx.emitted.load(Ordering::Relaxed) * PEAK_BYTES_PER_REF,
                params,
            )
        })?;
    let emitted = ctx.emitted.load(Ordering::Relaxed);
    if emitted >= u32::MAX as u64 {
        return Err(too_large(base + emitted * PEAK_BYTES_PER_REF, params));
    }
    let mut out = Arrays {
        levels: 1,
        ..Arrays::default()
    };
    let mut grid_of = vec![0u32; top_cells];
    for (u, f) in &filled {
        grid_of[*u] = out.place(f, 1)? + 1;
    }
    out.offsets.push(out.refs.len() as u32);
    let cells = out.child.len();
    let mut occupied = vec![0u64; cells.div_ceil(64)];
    for g in 0..cells {
        if out.child[g] != 0 || out.offsets[g + 1] > out.offsets[g] {
            occupied[g >> 6] |= 1 << (g & 63);
        }
    }
    let stats = stats(&top, &grid_of, &out, mesh.len(), params);
    Ok(Grid2 {
        name: params.name(),
        params: params.clone(),
        top,
        grid_of,
        grids: out.grids,
        planes: out.planes,
        child: out.child,
        offsets: out.offsets,
        occupied,
        refs: out.refs,
        stats,
    })
}

/// The shared arrays the cell grids are laid out in, and how many levels they make with the
/// top grid.
#[derive(Default)]
struct Arrays {
    grids: Vec<CellGrid>,
    planes: Vec<f32>,
    child: Vec<u32>,
    offsets: Vec<u32>,
    refs: Vec<u32>,
    levels: u32,
}

impl Arrays {
    /// Lays out `f` (a grid at `level`, the top grid being level 0) and then its cells' grids,
    /// depth first; returns its grid index.
    fn place(&mut self, f: &Filled, level: u32) -> Result<u32, BuildError> {
        self.levels = self.levels.max(level + 1);
        let l = &f.grid.layout;
        let index = self.grids.len() as u32;
        let first_cell = self.child.len() as u32;
        let mut starts = [0u32; 3];
        for (a, start) in starts.iter_mut().enumerate() {
            *start = self.planes.len() as u32;
            self.planes.extend(l.f32_planes(a));
        }
        let ends = |a: usize, i: usize| l.planes[a][i] as f32;
        let res = l.res;
        self.grids.push(CellGrid {
            bounds: Aabb::new(
                Vec3::from_array(std::array::from_fn(|a| ends(a, 0))),
                Vec3::from_array(std::array::from_fn(|a| ends(a, res[a] as usize))),
            ),
            res,
            inv_width: l.inv_width,
            planes: starts,
            first_cell,
        });
        let mut children = f.children.iter().peekable();
        for c in 0..l.cells() {
            self.child.push(0);
            self.offsets.push(self.refs.len() as u32);
            if children.peek().is_some_and(|(k, _)| *k == c) {
                children.next();
            } else {
                self.refs.extend_from_slice(f.grid.list(c));
            }
        }
        if self.child.len() >= u32::MAX as usize {
            return Err(BuildError::Unsupported("more than 2^32 cells".into()));
        }
        for (c, sub) in &f.children {
            let k = self.place(sub, level + 1)?;
            self.child[first_cell as usize + c] = k + 1;
        }
        Ok(index)
    }
}

fn stats(top: &Grid, grid_of: &[u32], out: &Arrays, n: usize, params: &Grid2Params) -> BuildStats {
    let top_cells = top.layout.cells();
    // The leaf level: cells at any level without a grid of their own.
    let top_lists = (0..top_cells)
        .filter(|&u| grid_of[u] == 0)
        .map(|u| top.cell_refs(u).map_or(0, <[u32]>::len));
    let lower = (0..out.child.len())
        .filter(|&g| out.child[g] == 0)
        .map(|g| (out.offsets[g + 1] - out.offsets[g]) as usize);
    let (mut leaves, mut non_empty, mut refs, mut max) = (0u64, 0u64, 0u64, 0usize);
    for k in top_lists.chain(lower) {
        leaves += 1;
        non_empty += (k > 0) as u64;
        refs += k as u64;
        max = max.max(k);
    }
    let mut extra = BTreeMap::new();
    extra.insert("top_cells".into(), top_cells as f64);
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        extra.insert(format!("top_resolution_{axis}"), top.layout.res[a] as f64);
    }
    extra.insert("cell_grids".into(), out.grids.len() as f64);
    extra.insert("cells".into(), leaves as f64);
    extra.insert(
        "empty_cell_fraction".into(),
        1.0 - non_empty as f64 / leaves.max(1) as f64,
    );
    extra.insert(
        "refs_per_triangle".into(),
        if n == 0 { 0.0 } else { refs as f64 / n as f64 },
    );
    extra.insert("max_refs_per_cell".into(), max as f64);
    extra.insert("top_density".into(), params.top_density);
    extra.insert("cell_density".into(), params.cell_density);
    BuildStats {
        nodes: (top_cells + out.child.len()) as u64,
        leaves: non_empty,
        // Levels below the top grid.
        max_depth: out.levels.saturating_sub(1),
        refs,
        sah_cost: None,
        extra,
    }
}
