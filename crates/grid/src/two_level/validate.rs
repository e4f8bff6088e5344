//! The invariants of a built hierarchical grid, checked by tests after every build.

use super::Grid2;
use super::build::{Inserted, own_grid};
use raybench_geom::tribox::{MARGIN_REL, TriBox};
use raybench_geom::{DVec3, TriangleMesh};

/// As for the uniform grid: the full 13-axis test on each enlarged cell, moved out or in by
/// this fraction of the margin, so insertion's shortcuts and rounding are not mistaken for
/// errors; a broken structure is wrong by far more.
const TOLERANCE: f64 = 1e-3;

fn widened((lo, hi): (DVec3, DVec3), f: f64) -> (DVec3, DVec3) {
    let m = lo.abs().max(hi.abs()).max_element() * MARGIN_REL * f;
    (lo - DVec3::splat(m), hi + DVec3::splat(m))
}

/// Where the next grid, cell and plane must be, in the depth-first order the build lays them.
#[derive(Default)]
struct Cursor {
    grid: usize,
    cell: usize,
    plane: usize,
}

/// The top grid passes the uniform grid's checks; exactly the cells the build's rules give a
/// grid of their own ([`own_grid`]: a box holding every point of the cell's triangles within
/// the enlarged cell) have one, with that layout, f32 planes and box rounded
/// from it, laid out depth first; the offsets tile the references and agree with the
/// occupancy bits; a cell with a grid holds no list; and every cell's list (stored, or for a
/// cell with a grid the one insertion gives it) is strictly ascending, holds only triangles of
/// its parent cell that overlap it, and every one that does (both up to [`TOLERANCE`]).
pub(crate) fn validate(g: &Grid2, mesh: &TriangleMesh) -> Result<(), String> {
    g.top.validate(mesh)?;
    let top_cells = g.top.layout.cells();
    if g.grid_of.len() != top_cells {
        return Err(format!(
            "{} grid indices for {top_cells} top cells",
            g.grid_of.len()
        ));
    }
    let cells = g.child.len();
    if g.offsets.len() != cells + 1
        || g.offsets.first() != Some(&0)
        || g.offsets.last().map(|&o| o as usize) != Some(g.refs.len())
        || g.offsets.windows(2).any(|w| w[0] > w[1])
        || g.occupied.len() != cells.div_ceil(64)
    {
        return Err(format!(
            "{} offsets and {} occupancy words for {cells} cells and {} references",
            g.offsets.len(),
            g.occupied.len(),
            g.refs.len()
        ));
    }
    let mut at = Cursor::default();
    for u in 0..top_cells {
        let list = g.top.cell_refs(u).unwrap_or_default();
        let cell = g.top.layout.cell_box(g.top.layout.coords(u));
        let expected = own_grid(mesh, list, cell, g.top.layout.margin, 0, &g.params);
        match (expected, g.grid_of[u]) {
            (None, 0) => {}
            (Some(grid), k) if k as usize == at.grid + 1 => {
                check_grid(g, mesh, list, &grid, 1, &mut at)?
            }
            (e, k) => {
                return Err(format!(
                    "top cell {u}: grid {k}, expected {}",
                    if e.is_some() { at.grid + 1 } else { 0 }
                ));
            }
        }
    }
    if at.grid != g.grids.len() || at.plane != g.planes.len() || at.cell != cells {
        return Err(format!(
            "{} grids, {} planes and {cells} cells stored; {}, {} and {} expected",
            g.grids.len(),
            g.planes.len(),
            at.grid,
            at.plane,
            at.cell
        ));
    }
    Ok(())
}

/// Checks the grid at `at.grid` against `expected` (a grid at `level` over the triangles
/// `list`, as the build's rules make it), and then the grids of its cells.
fn check_grid(
    g: &Grid2,
    mesh: &TriangleMesh,
    list: &[u32],
    expected: &Inserted,
    level: u32,
    at: &mut Cursor,
) -> Result<(), String> {
    let layout = &expected.layout;
    let cg = *g.grids.get(at.grid).ok_or("grid index out of range")?;
    let name = at.grid;
    at.grid += 1;
    if cg.res != layout.res || cg.first_cell as usize != at.cell {
        return Err(format!(
            "grid {name}: {:?} at cell {}, expected {:?} at {}",
            cg.res, cg.first_cell, layout.res, at.cell
        ));
    }
    for a in 0..3 {
        let f32_planes = layout.f32_planes(a);
        let start = cg.planes[a] as usize;
        if start != at.plane
            || g.planes.get(start..start + f32_planes.len()) != Some(&f32_planes[..])
        {
            return Err(format!(
                "grid {name}, axis {a}: planes differ from insertion's"
            ));
        }
        at.plane += f32_planes.len();
        if cg.bounds.min[a] != f32_planes[0] || cg.bounds.max[a] != *f32_planes.last().unwrap() {
            return Err(format!(
                "grid {name}, axis {a}: box differs from its planes"
            ));
        }
    }
    let first = at.cell;
    at.cell += layout.cells();
    if at.cell > g.child.len() {
        return Err(format!("grid {name}: cells run past the arrays"));
    }
    let mut children = Vec::new();
    let [nx, ny, nz] = layout.res;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let c = layout.index([x, y, z]);
                let i = first + c;
                let inserted = expected.list(c);
                let stored = &g.refs[g.offsets[i] as usize..g.offsets[i + 1] as usize];
                let cell = layout.cell_box([x, y, z]);
                let own = own_grid(mesh, inserted, cell, g.top.layout.margin, level, &g.params);
                let cell_list = match (own, g.child[i]) {
                    (None, 0) => stored,
                    (Some(l), k) if k != 0 => {
                        if !stored.is_empty() {
                            return Err(format!("cell {i} has a grid and a list"));
                        }
                        children.push((k, inserted, l));
                        inserted
                    }
                    (e, k) => {
                        return Err(format!(
                            "cell {i}: grid {k}, expected {}",
                            if e.is_some() { "one" } else { "none" }
                        ));
                    }
                };
                let occupied = g.occupied[i >> 6] >> (i & 63) & 1 != 0;
                if occupied != (g.child[i] != 0 || !stored.is_empty()) {
                    return Err(format!(
                        "cell {i}: occupancy bit disagrees with its contents"
                    ));
                }
                if cell_list.windows(2).any(|w| w[0] >= w[1]) {
                    return Err(format!("cell {i}: references not strictly ascending"));
                }
                let outer = widened(cell, TOLERANCE);
                for &id in cell_list {
                    if list.binary_search(&id).is_err() {
                        return Err(format!("cell {i}: triangle {id} is not in its parent cell"));
                    }
                    if !TriBox::new(&mesh.triangle(id as usize)).overlaps(outer.0, outer.1) {
                        return Err(format!("cell {i}: triangle {id} does not overlap it"));
                    }
                }
            }
        }
    }
    // Every overlap is listed, over each triangle's candidate cells widened by one.
    for &id in list {
        let tb = TriBox::new(&mesh.triangle(id as usize));
        let (blo, bhi) = tb.bounds();
        let r: [(u32, u32); 3] = std::array::from_fn(|a| {
            let (f, l) = layout.range(a, blo[a] as f32, bhi[a] as f32);
            (f.saturating_sub(1), (l + 1).min(layout.res[a] - 1))
        });
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    let inner = widened(layout.cell_box([x, y, z]), -TOLERANCE);
                    if !tb.overlaps(inner.0, inner.1) {
                        continue;
                    }
                    let c = layout.index([x, y, z]);
                    let i = first + c;
                    let cell_list = if g.child[i] != 0 {
                        expected.list(c)
                    } else {
                        &g.refs[g.offsets[i] as usize..g.offsets[i + 1] as usize]
                    };
                    if cell_list.binary_search(&id).is_err() {
                        return Err(format!("triangle {id} overlaps cell {i} but is not in it"));
                    }
                }
            }
        }
    }
    for (k, inserted, own) in children {
        if k as usize != at.grid + 1 {
            return Err(format!(
                "a cell of grid {name} points at grid {k}, expected {}",
                at.grid + 1
            ));
        }
        check_grid(g, mesh, inserted, &own, level + 1, at)?;
    }
    Ok(())
}
