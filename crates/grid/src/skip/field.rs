//! The distance field: per cell, the Chebyshev (chessboard) distance in cells to the nearest
//! non-empty cell, capped at [`CAP`].
//!
//! Two raster passes of the 3×3×3 chamfer mask with unit weights (Rosenfeld and Pfaltz 1966,
//! in 3D Borgefors 1984), which is exact for the chessboard distance: the forward pass takes
//! each cell's minimum over its 13 neighbours already visited plus one, the backward pass the
//! same over the other 13. The grid is padded by one cell of [`CAP`] on every side so the inner
//! loops have no bounds tests, and each row is done in two steps: the minimum over the three
//! neighbouring rows of the previous plane and the previous row of this plane (12 neighbours,
//! independent across the row, so the compiler vectorises it), then a sequential scan for the
//! neighbour before it in the row. Cost: about 30 byte operations per cell, single threaded
//! (the passes are sequential by nature).

use std::collections::BTreeMap;

/// The largest distance stored (a u8); farther cells store it, which is conservative (a
/// smaller block is still empty).
pub(crate) const CAP: u8 = u8::MAX;

/// Bytes the build needs beyond the grid: the field and its padded working copy.
pub(crate) fn build_bytes(res: [u32; 3]) -> u64 {
    let cells: u64 = res.iter().map(|&r| r as u64).product();
    let padded: u64 = res.iter().map(|&r| r as u64 + 2).product();
    cells + padded + 2 * (res[0] as u64 + 2)
}

/// The distance field of a grid of `res` cells whose cell `i` (linear index
/// `x + nx·(y + ny·z)`) is non-empty when `occupied(i)`.
pub(crate) fn distance_field(res: [u32; 3], occupied: impl Fn(usize) -> bool) -> Vec<u8> {
    let [nx, ny, nz] = res.map(|r| r as usize);
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    let row = |y: usize, z: usize| (y + py * z) * px;
    let mut d = vec![CAP; px * py * pz];
    for z in 0..nz {
        for y in 0..ny {
            let r = row(y + 1, z + 1) + 1;
            let i = nx * (y + ny * z);
            for x in 0..nx {
                if occupied(i + x) {
                    d[r + x] = 0;
                }
            }
        }
    }
    let mut m = vec![CAP; px];
    // Forward: neighbours at (y − 1, z) and (y − 1 ..= y + 1, z − 1), then x − 1.
    for z in 1..=nz {
        for y in 1..=ny {
            let rows = [
                row(y - 1, z),
                row(y - 1, z - 1),
                row(y, z - 1),
                row(y + 1, z - 1),
            ];
            pass_row(&mut d, &mut m, row(y, z), rows, px, true);
        }
    }
    // Backward: neighbours at (y + 1, z) and (y − 1 ..= y + 1, z + 1), then x + 1.
    for z in (1..=nz).rev() {
        for y in (1..=ny).rev() {
            let rows = [
                row(y + 1, z),
                row(y - 1, z + 1),
                row(y, z + 1),
                row(y + 1, z + 1),
            ];
            pass_row(&mut d, &mut m, row(y, z), rows, px, false);
        }
    }
    let mut out = Vec::with_capacity(nx * ny * nz);
    for z in 1..=nz {
        for y in 1..=ny {
            let r = row(y, z);
            out.extend_from_slice(&d[r + 1..r + 1 + nx]);
        }
    }
    out
}

/// One row of a pass: `cur` starts at index `cur` of `d`, the neighbouring rows at `rows`
/// (each of `px` cells, padding included); `m` is scratch of `px` cells.
#[inline]
fn pass_row(d: &mut [u8], m: &mut [u8], cur: usize, rows: [usize; 4], px: usize, forward: bool) {
    for x in 1..px - 1 {
        let mut v = CAP;
        for &r in &rows {
            v = v.min(d[r + x - 1]).min(d[r + x]).min(d[r + x + 1]);
        }
        m[x] = d[cur + x].min(v.saturating_add(1));
    }
    let line = &mut d[cur..cur + px];
    if forward {
        for x in 1..px - 1 {
            line[x] = m[x].min(line[x - 1].saturating_add(1));
        }
    } else {
        for x in (1..px - 1).rev() {
            line[x] = m[x].min(line[x + 1].saturating_add(1));
        }
    }
}

/// The field's figures for the report: the largest distance, the mean over empty cells, and
/// the share of cells a walk may jump from.
pub(crate) fn add_stats(distance: &[u8], min_jump: u8, extra: &mut BTreeMap<String, f64>) {
    let (mut empty, mut sum, mut jumpable, mut max) = (0u64, 0u64, 0u64, 0u8);
    for &k in distance {
        if k > 0 {
            empty += 1;
            sum += k as u64;
        }
        jumpable += (k >= min_jump) as u64;
        max = max.max(k);
    }
    let n = distance.len().max(1) as f64;
    extra.insert("skip_max_distance".into(), max as f64);
    extra.insert(
        "skip_mean_empty_distance".into(),
        if empty == 0 {
            0.0
        } else {
            sum as f64 / empty as f64
        },
    );
    extra.insert("skip_jump_cell_fraction".into(), jumpable as f64 / n);
    extra.insert("skip_min_jump".into(), min_jump as f64);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition, by brute force.
    fn brute(res: [u32; 3], occ: &[bool]) -> Vec<u8> {
        let [nx, ny, nz] = res.map(|r| r as i64);
        let at = |x: i64, y: i64, z: i64| (x + nx * (y + ny * z)) as usize;
        let mut out = vec![CAP; occ.len()];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let mut best = CAP as i64;
                    for (j, _) in occ.iter().enumerate().filter(|(_, o)| **o) {
                        let j = j as i64;
                        let (qx, qy, qz) = (j % nx, j / nx % ny, j / (nx * ny));
                        let dist = (qx - x).abs().max((qy - y).abs()).max((qz - z).abs());
                        best = best.min(dist);
                    }
                    out[at(x, y, z)] = best as u8;
                }
            }
        }
        out
    }

    #[test]
    fn the_passes_give_the_chessboard_distance() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for res in [
            [1, 1, 1],
            [7, 1, 1],
            [1, 9, 1],
            [5, 6, 1],
            [9, 7, 5],
            [4, 13, 6],
            [17, 3, 11],
        ] {
            let cells: usize = res.iter().map(|&r| r as usize).product();
            for density in [0u64, 1, 5, 30] {
                let occ: Vec<bool> = (0..cells).map(|_| rnd() % 100 < density).collect();
                let got = distance_field(res, |i| occ[i]);
                assert_eq!(got, brute(res, &occ), "{res:?}, density {density} %");
            }
        }
    }

    #[test]
    fn distances_are_capped() {
        // One occupied cell at the end of a row of 300: the far end is 299 away.
        let got = distance_field([300, 1, 1], |i| i == 0);
        assert_eq!(got[0], 0);
        assert_eq!(got[254], 254);
        assert_eq!(got[255], CAP);
        assert_eq!(got[299], CAP);
    }
}
