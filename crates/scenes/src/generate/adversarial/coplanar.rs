//! `coplanar`: axis-aligned triangle grids on dyadic planes, so triangles lie exactly on split
//! planes, grid lines and octree cell faces, with exact and half-shifted duplicates.

use super::Built;
use crate::{Camera, NamedView, View};
use raybench_geom::{Aabb, Vec3};

/// The five planes, as (axis, coordinate). Every coordinate is a dyadic rational, so it lies
/// exactly on the midpoint splits of the scene box [-1, 1]³ (0, ±0.5, ±0.25, …) and on the
/// grid lines of power-of-two grids; z = ±1 are the box's own faces.
const COPLANAR_PLANES: [(usize, f32); 5] = [
    (2, -1.0),
    (2, 0.0),
    (2, 1.0),
    (0, COPLANAR_X),
    (1, COPLANAR_Y),
];
const COPLANAR_X: f32 = 0.5;
const COPLANAR_Y: f32 = 0.25;

/// A point on the plane `axis = level` with in-plane coordinates `(u, v)` along the next two
/// axes in cyclic order, so `u × v` is the plane's +axis normal.
fn on_plane(axis: usize, level: f32, u: f32, v: f32) -> Vec3 {
    let mut p = [0.0; 3];
    p[axis] = level;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    Vec3::from_array(p)
}

/// The quad grid of a plane holding `count` triangles: `cols` quads per row, quads `h` wide
/// with `h` the largest power of two for which the row fits in 2 (the scene box's width).
fn grid_shape(count: u64) -> (u32, f32) {
    let cols = ((count as f64 / 2.0).sqrt().ceil() as u32).max(1);
    let mut h = 2.0f32;
    while h * cols as f32 > 2.0 {
        h *= 0.5;
    }
    (cols, h)
}

/// Appends `count` triangles of the grid of `grid_shape(count)` (or of an explicit shape) on
/// plane `axis = level`, starting at `(start, start)`, row by row, two per quad, facing +axis.
/// Vertices are shared within the grid. Every coordinate is `start + i·h`: exact in f32.
#[allow(clippy::too_many_arguments)]
fn push_grid(
    positions: &mut Vec<Vec3>,
    indices: &mut Vec<[u32; 3]>,
    axis: usize,
    level: f32,
    start: f32,
    (cols, h): (u32, f32),
    count: u64,
) {
    if count == 0 {
        return;
    }
    let rows = count.div_ceil(2 * u64::from(cols)) as u32;
    let base = positions.len() as u32;
    for row in 0..=rows {
        for col in 0..=cols {
            let (u, v) = (start + col as f32 * h, start + row as f32 * h);
            positions.push(on_plane(axis, level, u, v));
        }
    }
    let at = |row: u32, col: u32| base + row * (cols + 1) + col;
    let mut left = count;
    'rows: for row in 0..rows {
        for col in 0..cols {
            let (a, b) = (at(row, col), at(row, col + 1));
            let (c, d) = (at(row + 1, col), at(row + 1, col + 1));
            for tri in [[a, b, d], [a, d, c]] {
                if left == 0 {
                    break 'rows;
                }
                indices.push(tri);
                left -= 1;
            }
        }
    }
}

/// `n` triangles: 1/8 exact duplicates of grid triangles (every other one with reversed
/// winding), 1/8 a grid on z = 0 shifted by half a quad (partly overlapping the z = 0 grid:
/// z-fighting), and the rest split evenly over the five planes of [`COPLANAR_PLANES`].
/// Every triangle is axis-aligned; every coordinate is a multiple of a power of two in [-1, 1]
/// (the shifted grid may reach half a quad past 1).
pub(super) fn coplanar(n: u64) -> Built {
    let duplicates = n / 8;
    let shifted = n / 8;
    let on_planes = n - duplicates - shifted;
    let mut positions = Vec::new();
    let mut indices = Vec::with_capacity(n as usize);
    let planes = COPLANAR_PLANES.len() as u64;
    let mut z0_shape = grid_shape(1);
    for (k, &(axis, level)) in COPLANAR_PLANES.iter().enumerate() {
        let count = on_planes / planes + u64::from((k as u64) < on_planes % planes);
        let shape = grid_shape(count);
        if (axis, level) == (2, 0.0) {
            z0_shape = shape;
        }
        push_grid(
            &mut positions,
            &mut indices,
            axis,
            level,
            -1.0,
            shape,
            count,
        );
    }
    let plane_triangles = indices.len() as u64;
    push_grid(
        &mut positions,
        &mut indices,
        2,
        0.0,
        -1.0 + 0.5 * z0_shape.1,
        z0_shape,
        shifted,
    );
    for j in 0..duplicates {
        let [a, b, c] = indices[(j * plane_triangles / duplicates) as usize];
        indices.push(if j % 2 == 0 { [b, c, a] } else { [a, c, b] });
    }
    let default = View::of_bounds(&Aabb::new(Vec3::splat(-1.0), Vec3::ONE));
    let mut built = Built::new(positions, indices, default);
    built.views.push(NamedView {
        name: "grazing".into(),
        view: coplanar_grazing_view(),
    });
    built
}

/// The eye lies in the planes z = 0 and y = 0.25, outside the triangles (x = -3), looking along +x:
/// every ray meets the triangles of those two planes only at its origin, t = 0, so none of them may
/// be hit (docs/validation.md, R9: grazing rays; a traversal that rounds the plane distance to a
/// tiny positive t reports a false hit).
fn coplanar_grazing_view() -> View {
    View {
        camera: Camera {
            eye: Vec3::new(-3.0, COPLANAR_Y, 0.0),
            target: Vec3::new(0.0, COPLANAR_Y, 0.0),
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: Vec3::new(-2.0, 3.0, 2.5),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_shape_fits_the_box_with_power_of_two_quads() {
        for count in [1, 2, 3, 7, 100, 1_601, 2_000_000] {
            let (cols, h) = grid_shape(count);
            assert!(2 * u64::from(cols) * u64::from(cols) >= count, "{count}");
            assert!(cols as f32 * h <= 2.0 && cols as f32 * h > 1.0, "{count}");
            assert_eq!(h, 2f32.powi(h.log2() as i32), "{count}: {h}");
        }
    }
}
