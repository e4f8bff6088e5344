//! The invariants of a built grid, checked by tests after every build.

use crate::Grid;
use crate::build::Layout;
use raybench_geom::tri4::{LANES, NO_PRIM};
use raybench_geom::tribox::{MARGIN_REL, TriBox};
use raybench_geom::{DVec3, MollerTriangle, Triangle, TriangleMesh, Vec3};

/// The checks use the full 13-axis test on each cell's enlarged box, moved out (for "only in
/// cells it overlaps") or in (for "in every cell it overlaps") by this fraction of the margin:
/// insertion decides with shortcuts and its own arithmetic, which may round differently when a
/// triangle touches an enlarged box within f64 rounding; a broken structure is wrong by far
/// more than 1/1000 of the margin.
const TOLERANCE: f64 = 1e-3;

/// The enlarged cell `(lo, hi)` grown by `f` times its margin (shrunk for negative `f`).
fn widened((lo, hi): (DVec3, DVec3), f: f64) -> (DVec3, DVec3) {
    let m = lo.abs().max(hi.abs()).max_element() * MARGIN_REL * f;
    (lo - DVec3::splat(m), hi + DVec3::splat(m))
}

/// The layout is the one the mesh and parameters call for; the Tri4s hold every mesh
/// triangle exactly once as an exact copy (empty lanes only past the last); the offsets tile
/// the reference array and agree with the occupancy bits; every cell's list is strictly
/// ascending (no duplicates); and every triangle is in
/// exactly the cells whose enlarged box it overlaps by the full 13-axis test — checked both
/// ways (up to [`TOLERANCE`]), over each triangle's bounding-box cells widened by one cell on
/// every side (so a wrong candidate range is caught too).
pub(crate) fn validate(grid: &Grid, mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.len();
    let expected = Layout::new(&mesh.bounds(), n, &grid.params);
    if grid.layout != expected {
        return Err(format!(
            "layout {:?} is not the one the mesh calls for ({:?})",
            grid.layout.res, expected.res
        ));
    }
    if grid.res != grid.layout.res {
        return Err(format!(
            "resolution {:?} differs from the layout's {:?}",
            grid.res, grid.layout.res
        ));
    }
    for a in 0..3 {
        let f32_planes = grid.layout.f32_planes(a);
        if grid.planes[a] != f32_planes {
            return Err(format!(
                "axis {a}: traversal planes differ from insertion's"
            ));
        }
    }
    // The Tri4s: internal ids 0..n name every mesh triangle once, each lane an exact copy.
    if grid.triangles.len() != n.div_ceil(LANES) {
        return Err(format!(
            "{} Tri4s for a mesh of {n} triangles",
            grid.triangles.len()
        ));
    }
    let empty_lane = MollerTriangle::new(&Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
    let mut internal_of = vec![u32::MAX; n];
    for (k, p) in grid.triangles.iter().enumerate() {
        for l in 0..LANES {
            let internal = k * LANES + l;
            let id = p.ids[l];
            if internal >= n {
                if id != NO_PRIM || p.lane(l) != empty_lane {
                    return Err(format!("lane {internal} past the mesh is not empty"));
                }
                continue;
            }
            let slot = internal_of
                .get_mut(id as usize)
                .ok_or(format!("lane {internal}: triangle id {id} out of range"))?;
            if *slot != u32::MAX {
                return Err(format!("triangle {id} is stored twice"));
            }
            *slot = internal as u32;
            if p.lane(l) != MollerTriangle::new(&mesh.triangle(id as usize)) {
                return Err(format!(
                    "lane {internal}: the copy of triangle {id} differs from the mesh"
                ));
            }
        }
    }
    let cells = grid.layout.cells();
    if grid.occupied.len() != cells.div_ceil(64) {
        return Err(format!(
            "{} occupancy words for {cells} cells",
            grid.occupied.len()
        ));
    }
    if grid.offsets.len() != cells + 1 {
        return Err(format!("{} offsets for {cells} cells", grid.offsets.len()));
    }
    if grid.offsets[0] != 0 || grid.offsets[cells] as usize != grid.refs.len() {
        return Err(format!(
            "offsets run from {} to {}, references {}",
            grid.offsets[0],
            grid.offsets[cells],
            grid.refs.len()
        ));
    }
    let [nx, ny, nz] = grid.res;
    // Every reference: a valid internal id, strictly ascending in its cell (so no duplicate),
    // overlapping the cell (with the tolerance band, see `TOLERANCE`).
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = grid.layout.index([x, y, z]);
                let (first, last) = (grid.offsets[i], grid.offsets[i + 1]);
                if first > last {
                    return Err(format!("cell ({x},{y},{z}): offsets decrease"));
                }
                let list = &grid.refs[first as usize..last as usize];
                if let Some(w) = list.windows(2).find(|w| w[0] >= w[1]) {
                    return Err(format!(
                        "cell ({x},{y},{z}): references not strictly ascending ({} then {}): \
                         a duplicate or a corrupt list",
                        w[0], w[1]
                    ));
                }
                let occupied = grid.occupied[i >> 6] >> (i & 63) & 1 != 0;
                if occupied == list.is_empty() {
                    return Err(format!(
                        "cell ({x},{y},{z}): occupancy bit {occupied} for {} references",
                        list.len()
                    ));
                }
                let (lo, hi) = widened(grid.layout.cell_box([x, y, z]), TOLERANCE);
                for &internal in list {
                    if internal as usize >= n {
                        return Err(format!(
                            "cell ({x},{y},{z}): internal id {internal} out of range"
                        ));
                    }
                    let id = grid.mesh_id(internal);
                    if !TriBox::new(&mesh.triangle(id as usize)).overlaps(lo, hi) {
                        return Err(format!(
                            "triangle {id} is in cell ({x},{y},{z}), which it does not overlap"
                        ));
                    }
                }
            }
        }
    }
    // Every overlap is referenced.
    #[allow(clippy::needless_range_loop)] // `prim` is also the mesh index
    for prim in 0..n {
        let tri = mesh.triangle(prim);
        let tb = TriBox::new(&tri);
        let (blo, bhi) = tb.bounds();
        if !blo.cmple(bhi).all() {
            continue; // NaN: overlaps nothing (the mesh never holds one)
        }
        let r: [(u32, u32); 3] = std::array::from_fn(|a| {
            let (f, l) = grid.layout.range(a, blo[a] as f32, bhi[a] as f32);
            (f.saturating_sub(1), (l + 1).min(grid.res[a] - 1))
        });
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    let (lo, hi) = widened(grid.layout.cell_box([x, y, z]), -TOLERANCE);
                    let i = grid.layout.index([x, y, z]);
                    let list = &grid.refs[grid.offsets[i] as usize..grid.offsets[i + 1] as usize];
                    if tb.overlaps(lo, hi) && list.binary_search(&internal_of[prim]).is_err() {
                        return Err(format!(
                            "triangle {prim} overlaps cell ({x},{y},{z}) but is not in it"
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{Grid, GridParams};
    use raybench_accel::Accel;
    use std::sync::Arc;

    fn built() -> (Grid, Arc<raybench_geom::TriangleMesh>) {
        let mesh = raybench_testkit::generated("soup:triangles=500", 3);
        (
            Grid::build(mesh.clone(), &GridParams::default()).unwrap(),
            mesh,
        )
    }

    /// A cell with at least `k` references.
    fn cell_with(grid: &Grid, k: u32) -> usize {
        (0..grid.offsets.len() - 1)
            .find(|&i| grid.offsets[i + 1] - grid.offsets[i] >= k)
            .expect("a populated cell")
    }

    #[test]
    fn a_sound_grid_passes() {
        let (grid, mesh) = built();
        assert_eq!(grid.validate(&mesh), Ok(()));
    }

    #[test]
    fn a_dropped_reference_is_caught() {
        let (mut grid, mesh) = built();
        let i = cell_with(&grid, 1);
        grid.refs.remove(grid.offsets[i] as usize);
        for o in &mut grid.offsets[i + 1..] {
            *o -= 1;
        }
        let err = grid.validate(&mesh).unwrap_err();
        assert!(err.contains("but is not in it"), "{err}");
    }

    #[test]
    fn a_reference_in_the_wrong_cell_is_caught() {
        let (mut grid, mesh) = built();
        // The last reference of a cell replaced by the last internal id (met last, far away).
        let i = cell_with(&grid, 1);
        let at = grid.offsets[i + 1] as usize - 1;
        grid.refs[at] = 499;
        let err = grid.validate(&mesh).unwrap_err();
        assert!(
            err.contains("does not overlap") || err.contains("not strictly ascending"),
            "{err}"
        );
    }

    #[test]
    fn a_duplicate_is_caught() {
        let (mut grid, mesh) = built();
        let i = cell_with(&grid, 2);
        let at = grid.offsets[i] as usize;
        grid.refs[at + 1] = grid.refs[at];
        assert!(
            grid.validate(&mesh)
                .unwrap_err()
                .contains("strictly ascending")
        );
    }

    #[test]
    fn broken_offsets_are_caught() {
        let (mut grid, mesh) = built();
        let last = grid.offsets.len() - 1;
        grid.offsets[last] -= 1;
        assert!(grid.validate(&mesh).is_err());
    }

    #[test]
    fn a_corrupt_copy_or_id_is_caught() {
        let (mut grid, mesh) = built();
        grid.triangles[7].v0[1][2] += 0.25;
        assert!(
            grid.validate(&mesh)
                .unwrap_err()
                .contains("differs from the mesh")
        );
        let (mut grid, mesh) = built();
        grid.triangles[3].ids.swap(0, 1);
        assert!(
            grid.validate(&mesh)
                .unwrap_err()
                .contains("differs from the mesh")
        );
        let (mut grid, mesh) = built();
        let (id, copy) = (grid.triangles[4].ids[0], grid.triangles[4].lane(0));
        grid.triangles[3].set_lane(0, id, &copy);
        assert!(grid.validate(&mesh).unwrap_err().contains("stored twice"));
    }

    #[test]
    fn a_wrong_resolution_planes_or_occupancy_is_caught() {
        let (mut grid, mesh) = built();
        grid.res[0] += 1;
        assert!(grid.validate(&mesh).unwrap_err().contains("resolution"));
        let (mut grid, mesh) = built();
        grid.planes[1][1] += 1e-3;
        assert!(grid.validate(&mesh).unwrap_err().contains("planes"));
        let (mut grid, mesh) = built();
        let i = cell_with(&grid, 1);
        grid.occupied[i >> 6] &= !(1 << (i & 63));
        assert!(grid.validate(&mesh).unwrap_err().contains("occupancy"));
    }
}
