//! Soups that stress cells and leaves: zero-area triangles mixed in (`zero-area-mixed`),
//! blades sharing one vertex (`fan`) and one huge triangle among small ones (`huge-and-small`).

use super::{Built, FAN_STREAM, HUGE_STREAM, ZERO_AREA_STREAM, below, bounds_view, soup_indices};
use crate::{View, rng};
use raybench_geom::{Aabb, Vec3};

/// Lengths of the non-degenerate soup's corner radii and of the degenerate segments: about the
/// size of the `soup` generator's triangles, so both kinds share the same cells and nodes.
const ZERO_AREA_EDGE: (f32, f32) = (0.02, 0.1);
/// Exactly collinear triangles are built on a grid of 2^-12: every coordinate and difference
/// is exact in f32 and their f64 cross products are exactly zero.
const COLLINEAR_GRID: f32 = 1.0 / 4096.0;

/// `n` triangles of which `round(fraction · n)`, chosen uniformly at random (selection
/// sampling), have zero area, cycling through six kinds: three equal points in separate
/// vertices; a tobj point face `[a, a, a]`; a tobj line face `[a, b, b]`; two distinct vertices
/// at one position; three distinct points on an oblique line (middle point between); three on
/// an axis-parallel line (third point beyond). Every one has an f64 area of exactly 0, so
/// `TriangleMesh::new` counts each in `degenerate_kept`. The others are random triangles with
/// corners at about 120° around a random centre (as in `soup`).
pub(super) fn zero_area_mixed(n: u64, fraction: f64, seed: u64) -> Built {
    let mut rng = rng::stream(seed, ZERO_AREA_STREAM);
    let mut degenerate_left = ((fraction * n as f64).round() as u64).min(n);
    let mut positions = Vec::with_capacity(3 * n as usize);
    let mut indices = Vec::with_capacity(n as usize);
    let mut kind = 0u32;
    let margin = 0.11;
    for i in 0..n {
        let base = positions.len() as u32;
        // Selection sampling (Knuth's Algorithm S): exactly `degenerate_left` of the rest.
        let degenerate = u64::from(below(&mut rng, (n - i) as u32)) < degenerate_left;
        let centre = Vec3::new(
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
        );
        if !degenerate {
            let normal = rng::uniform_sphere(&mut rng);
            let (e1, e2) = rng::orthonormal_basis(normal);
            let radius = rng::range_f32(&mut rng, ZERO_AREA_EDGE.0, ZERO_AREA_EDGE.1);
            let spin = std::f32::consts::TAU * rng::unit_f32(&mut rng);
            for k in 0..3 {
                let angle = spin
                    + k as f32 * std::f32::consts::TAU / 3.0
                    + rng::range_f32(&mut rng, -0.3, 0.3);
                positions.push(centre + (e1 * angle.cos() + e2 * angle.sin()) * radius);
            }
            indices.push([base, base + 1, base + 2]);
            continue;
        }
        degenerate_left -= 1;
        let length = rng::range_f32(&mut rng, ZERO_AREA_EDGE.0, ZERO_AREA_EDGE.1);
        let other = centre + rng::uniform_sphere(&mut rng) * length;
        match kind % 6 {
            0 => {
                positions.extend([centre; 3]);
                indices.push([base, base + 1, base + 2]);
            }
            1 => {
                positions.push(centre);
                indices.push([base; 3]);
            }
            2 => {
                positions.extend([centre, other]);
                indices.push([base, base + 1, base + 1]);
            }
            3 => {
                positions.extend([centre, other, centre]);
                indices.push([base, base + 1, base + 2]);
            }
            4 => {
                // a, a + d, a + 2d on the 2^-12 grid: exact in f32 and in the f64 area.
                let snap = |x: f32| (x / COLLINEAR_GRID).round() * COLLINEAR_GRID;
                let a = centre.map(snap);
                let step = ((other - centre) * 0.5).map(snap);
                positions.extend([a, a + step, a + 2.0 * step]);
                indices.push([base, base + 1, base + 2]);
            }
            _ => {
                let axis = Vec3::AXES[(kind / 6 % 3) as usize];
                positions.extend([
                    centre,
                    centre + axis * length,
                    centre + axis * (0.5 * length),
                ]);
                indices.push([base, base + 1, base + 2]);
            }
        }
        kind += 1;
    }
    let view = View::of_bounds(&Aabb::new(Vec3::ZERO, Vec3::ONE));
    Built::new(positions, indices, view)
}

/// Angular width of a fan blade at its far end, in radians.
const FAN_BLADE: f32 = 0.02;

/// `n` triangles `[0, a_i, b_i]` sharing vertex 0 at the origin: `a_i` uniform on the unit
/// sphere, `b_i` a step of [`FAN_BLADE`] from it in a random tangent direction.
pub(super) fn fan(n: u64, seed: u64) -> Built {
    let mut rng = rng::stream(seed, FAN_STREAM);
    let mut positions = Vec::with_capacity(1 + 2 * n as usize);
    positions.push(Vec3::ZERO);
    for _ in 0..n {
        let a = rng::uniform_sphere(&mut rng);
        let (e1, e2) = rng::orthonormal_basis(a);
        let turn = std::f32::consts::TAU * rng::unit_f32(&mut rng);
        let b = (a + (e1 * turn.cos() + e2 * turn.sin()) * FAN_BLADE).normalize();
        positions.extend([a, b]);
    }
    let indices = (0..n as u32).map(|i| [0, 1 + 2 * i, 2 + 2 * i]).collect();
    let view = bounds_view(&positions);
    Built::new(positions, indices, view)
}

/// Triangle 0 is huge (`size` unit-cube widths across, through the cube's centre, oblique);
/// triangles 1.. are a soup in the unit cube. The default view frames the cube, not the huge
/// triangle, so primary rays see the soup in front of it.
pub(super) fn huge_and_small(n: u64, size: f32, seed: u64) -> Built {
    let mut rng = rng::stream(seed, HUGE_STREAM);
    let c = Vec3::splat(0.5);
    let (e1, e2) = rng::orthonormal_basis(Vec3::new(0.3, 0.5, 0.8).normalize());
    let mut positions = vec![
        c + (e1 * -0.5 - e2 * 0.4) * size,
        c + (e1 * 0.5 - e2 * 0.4) * size,
        c + e2 * (0.6 * size),
    ];
    let margin = 0.06;
    for _ in 1..n {
        let centre = Vec3::new(
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
        );
        let (t, b) = rng::orthonormal_basis(rng::uniform_sphere(&mut rng));
        let r = rng::range_f32(&mut rng, 0.01, 0.05);
        positions.extend([
            centre + t * r,
            centre - t * (0.5 * r) + b * r,
            centre - b * r,
        ]);
    }
    let view = View::of_bounds(&Aabb::new(Vec3::ZERO, Vec3::ONE));
    Built::new(positions, soup_indices(n as usize), view)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::adversarial::mesh;
    #[test]
    fn fan_blades_share_one_vertex() {
        let b = fan(2_000, 3);
        assert_eq!(b.indices.len(), 2_000);
        assert!(b.indices.iter().all(|t| t[0] == 0));
        let m = mesh(&b);
        assert!(m.triangles().all(|t| t.area() > 0.0));
        assert_eq!(fan(50, 3).positions, fan(50, 3).positions);
    }

    #[test]
    fn huge_triangle_dwarfs_the_soup() {
        let b = huge_and_small(1_000, 100.0, 1);
        let m = mesh(&b);
        assert_eq!(m.len(), 1_000);
        let huge = m.triangle(0).area();
        assert!(huge > 1_000.0, "{huge}");
        assert!(
            m.triangles()
                .skip(1)
                .all(|t| t.area() > 0.0 && t.area() < 0.01)
        );
        let cube = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!(
            m.triangles()
                .skip(1)
                .all(|t| [t.v0, t.v1, t.v2].iter().all(|&v| cube.contains(v)))
        );
    }
}
