//! The distance field's invariants, checked exhaustively and independently of how it was
//! computed: with a summed-area table of the occupancy bits, the number of non-empty cells in
//! any block is eight lookups, so every cell is checked against the definition.

use super::SkipGrid;
use super::field::CAP;

/// One entry per field cell; `0` exactly for non-empty cells; for an empty cell of value `k`,
/// no non-empty cell within Chebyshev distance `k − 1` (what makes a jump safe) and, unless
/// `k` is the cap, one at distance `k` (the field is not needlessly small).
pub(crate) fn validate(s: &SkipGrid) -> Result<(), String> {
    let grid = &s.grid;
    let cells = grid.layout.cells();
    if s.distance.len() != cells {
        return Err(format!("{} distances for {cells} cells", s.distance.len()));
    }
    let sat = Sat::new(grid.res, |i| grid.occupied(i));
    let [nx, ny, nz] = grid.res;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let c = [x, y, z];
                let i = grid.layout.index(c);
                let k = s.distance[i];
                let occupied = grid.occupied(i);
                if occupied != (k == 0) {
                    return Err(format!(
                        "cell ({x},{y},{z}): distance {k} for a cell that is {}",
                        if occupied { "non-empty" } else { "empty" }
                    ));
                }
                if k == 0 {
                    continue;
                }
                if sat.count_within(c, k as u32 - 1) != 0 {
                    return Err(format!(
                        "cell ({x},{y},{z}): distance {k}, but a non-empty cell lies within {}",
                        k - 1
                    ));
                }
                if k < CAP && sat.count_within(c, k as u32) == 0 {
                    return Err(format!(
                        "cell ({x},{y},{z}): distance {k}, but no non-empty cell lies within {k}"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Summed-area table: `s[x + (nx+1)·(y + (ny+1)·z)]` counts the non-empty cells in
/// `[0, x) × [0, y) × [0, z)`.
struct Sat {
    res: [u32; 3],
    s: Vec<u32>,
}

impl Sat {
    fn new(res: [u32; 3], occupied: impl Fn(usize) -> bool) -> Sat {
        let [nx, ny, nz] = res.map(|r| r as usize);
        let (sx, sy) = (nx + 1, ny + 1);
        let mut s = vec![0u32; sx * sy * (nz + 1)];
        let at = |x: usize, y: usize, z: usize| x + sx * (y + sy * z);
        for z in 1..=nz {
            for y in 1..=ny {
                for x in 1..=nx {
                    let own = occupied((x - 1) + nx * ((y - 1) + ny * (z - 1))) as u32;
                    // Inclusion–exclusion over the seven smaller boxes, in i64: the signed
                    // terms pass below zero on the way.
                    let v = own as i64
                        + s[at(x - 1, y, z)] as i64
                        + s[at(x, y - 1, z)] as i64
                        + s[at(x, y, z - 1)] as i64
                        - s[at(x - 1, y - 1, z)] as i64
                        - s[at(x - 1, y, z - 1)] as i64
                        - s[at(x, y - 1, z - 1)] as i64
                        + s[at(x - 1, y - 1, z - 1)] as i64;
                    s[at(x, y, z)] = v as u32;
                }
            }
        }
        Sat { res, s }
    }

    /// Non-empty cells within Chebyshev distance `r` of cell `c` (the block clipped to the
    /// grid).
    fn count_within(&self, c: [u32; 3], r: u32) -> u64 {
        let lo: [usize; 3] = std::array::from_fn(|a| c[a].saturating_sub(r) as usize);
        let hi: [usize; 3] =
            std::array::from_fn(|a| (c[a] as u64 + r as u64 + 1).min(self.res[a] as u64) as usize);
        let (sx, sy) = (self.res[0] as usize + 1, self.res[1] as usize + 1);
        let at = |x: usize, y: usize, z: usize| self.s[x + sx * (y + sy * z)] as i64;
        let v = at(hi[0], hi[1], hi[2])
            - at(lo[0], hi[1], hi[2])
            - at(hi[0], lo[1], hi[2])
            - at(hi[0], hi[1], lo[2])
            + at(lo[0], lo[1], hi[2])
            + at(lo[0], hi[1], lo[2])
            + at(hi[0], lo[1], lo[2])
            - at(lo[0], lo[1], lo[2]);
        v as u64
    }
}

#[cfg(test)]
mod tests {
    use crate::{SkipGrid, SkipGridParams};
    use raybench_accel::Accel;

    fn built() -> (SkipGrid, std::sync::Arc<raybench_geom::TriangleMesh>) {
        // A sparse scene: few triangles spread in a box, many cells far from any.
        let mesh = raybench_testkit::generated(
            "teapot-in-stadium:stadium_triangles=2000,teapot_triangles=200",
            5,
        );
        (
            SkipGrid::build(mesh.clone(), &SkipGridParams::default()).unwrap(),
            mesh,
        )
    }

    #[test]
    fn a_sound_field_passes() {
        let (s, mesh) = built();
        assert_eq!(s.validate(&mesh), Ok(()));
        assert!(
            s.distance.iter().any(|&k| k >= 3),
            "the scene must have room to jump"
        );
    }

    #[test]
    fn a_distance_too_large_is_caught() {
        let (mut s, mesh) = built();
        let i = s.distance.iter().position(|&k| k == 1).unwrap();
        s.distance[i] = 2;
        let err = s.validate(&mesh).unwrap_err();
        assert!(err.contains("lies within 1"), "{err}");
    }

    #[test]
    fn a_distance_too_small_is_caught() {
        let (mut s, mesh) = built();
        let i = s.distance.iter().position(|&k| k >= 3).unwrap();
        s.distance[i] -= 1;
        let err = s.validate(&mesh).unwrap_err();
        assert!(err.contains("no non-empty cell lies within"), "{err}");
    }

    #[test]
    fn a_wrong_zero_or_length_is_caught() {
        let (mut s, mesh) = built();
        let i = s.distance.iter().position(|&k| k == 0).unwrap();
        s.distance[i] = 1;
        assert!(s.validate(&mesh).unwrap_err().contains("non-empty"));
        let (mut s, mesh) = built();
        let i = s.distance.iter().position(|&k| k == 1).unwrap();
        s.distance[i] = 0;
        assert!(s.validate(&mesh).unwrap_err().contains("empty"));
        let (mut s, mesh) = built();
        s.distance.pop();
        assert!(s.validate(&mesh).unwrap_err().contains("distances for"));
    }
}
