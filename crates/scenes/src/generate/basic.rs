//! The starter scenes: `sphere`, `soup`, `plane`.

use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::rng::{self, SOUP_STREAM};
use crate::{Camera, View};
use raybench_geom::{DVec3, Vec3};

pub(super) const SPHERE: GeneratorInfo = GeneratorInfo {
    name: "sphere",
    description: "UV sphere centred at the origin, watertight (shared vertices, one vertex per pole)",
    params: &[
        triangles(
            "approximate triangle count, rounded to the nearest 4·s·(s-1) for s stacks and 2s slices",
            20_000.0,
        ),
        ParamInfo {
            key: "radius",
            meaning: "sphere radius",
            kind: Kind::Real {
                min: 1e-6,
                max: 1e6,
            },
            default: 1.0,
        },
    ],
    uses_seed: false,
    build: |p, _| {
        let (positions, indices, view) = sphere(p.count("triangles"), p.f32("radius"));
        Ok(Built::new(positions, indices, view))
    },
};

pub(super) const SOUP: GeneratorInfo = GeneratorInfo {
    name: "soup",
    description: "unconnected random triangles in the unit cube [0,1]³, edges about 0.02–0.1 long",
    params: &[triangles("number of triangles", 10_000.0)],
    uses_seed: true,
    build: |p, seed| {
        let (positions, indices, view) = soup(p.count("triangles"), seed);
        Ok(Built::new(positions, indices, view))
    },
};

pub(super) const PLANE: GeneratorInfo = GeneratorInfo {
    name: "plane",
    description: "square grid over [-1,1]² of quads split into two triangles, shared vertices, tilted about the x axis",
    params: &[
        // 2 · 5000² = MAX_TRIANGLES.
        ParamInfo {
            key: "quads",
            meaning: "quads per side, so 2·quads² triangles",
            kind: Kind::Count { min: 1, max: 5000 },
            default: 64.0,
        },
        ParamInfo {
            key: "tilt_deg",
            meaning: "tilt about the x axis in degrees (0: flat, axis-aligned)",
            kind: Kind::Real {
                min: 0.0,
                max: 80.0,
            },
            default: 10.0,
        },
    ],
    uses_seed: false,
    build: |p, _| {
        let (positions, indices, view) = plane(p.count("quads"), p.f32("tilt_deg"));
        Ok(Built::new(positions, indices, view))
    },
};

type Mesh = (Vec<Vec3>, Vec<[u32; 3]>, View);

/// UV sphere with `s` stacks and `2s` slices: `2s` triangles in each polar cap, `4s` in each of
/// the `s - 2` bands, `4s(s-1)` in all. Rings are shared between neighbouring bands and the seam
/// wraps by index, so every edge belongs to exactly two triangles. Counter-clockwise seen from
/// outside.
fn sphere(target_triangles: u64, radius: f32) -> Mesh {
    let stacks = sphere_stacks(target_triangles);
    let (positions, indices) = uv_sphere(stacks, 2 * stacks, |p| p.as_vec3() * radius);
    (positions, indices, sphere_view(radius))
}

/// The UV-sphere mesh shared by `sphere` and the adversarial `offset` sphere: a pole vertex, then
/// `stacks - 1` rings of `slices` vertices from north to south, then the other pole; `vertex`
/// maps each exact unit-sphere point (f64) to its stored position, so callers choose how to
/// scale, move and round. Rings are shared and the seam wraps by index, so every edge belongs
/// to exactly two triangles; counter-clockwise seen from outside.
pub(super) fn uv_sphere(
    stacks: u32,
    slices: u32,
    vertex: impl Fn(DVec3) -> Vec3,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = vec![vertex(DVec3::Y)];
    for ring in 1..stacks {
        let theta = std::f64::consts::PI * f64::from(ring) / f64::from(stacks);
        for j in 0..slices {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(slices);
            positions.push(vertex(DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )));
        }
    }
    positions.push(vertex(-DVec3::Y));
    let south = positions.len() as u32 - 1;
    let at = |ring: u32, j: u32| 1 + (ring - 1) * slices + j % slices;
    let mut indices = Vec::with_capacity(2 * (slices * (stacks - 1)) as usize);
    for j in 0..slices {
        indices.push([0, at(1, j + 1), at(1, j)]);
        indices.push([south, at(stacks - 1, j), at(stacks - 1, j + 1)]);
    }
    for ring in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b) = (at(ring, j), at(ring, j + 1));
            let (c, d) = (at(ring + 1, j), at(ring + 1, j + 1));
            indices.push([a, b, d]);
            indices.push([a, d, c]);
        }
    }
    (positions, indices)
}

/// Stacks `s` such that `4s(s-1)` is nearest `target`: `s ≈ (1 + sqrt(1 + target)) / 2`.
fn sphere_stacks(target: u64) -> u32 {
    let s = ((1.0 + (1.0 + target as f64).sqrt()) / 2.0).round();
    s.max(2.0) as u32
}

/// The sphere seen from outside: at `r / sin 20°` it subtends 40° of the 50° field of view.
fn sphere_view(radius: f32) -> View {
    let distance = radius / 20f32.to_radians().sin();
    View {
        camera: Camera {
            eye: Vec3::new(0.3, 0.4, 1.0).normalize() * distance,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: Vec3::new(2.0, 4.0, 3.0) * radius,
    }
}

/// Edge lengths of soup triangles before the angle jitter.
const SOUP_EDGE: (f32, f32) = (0.02, 0.1);

/// `n` independent triangles: a random centre, a random plane through it, and three corners at
/// about 120° around the centre (±0.3 rad jitter). Corners stay inside the unit cube because the
/// centre keeps a margin of the largest corner radius, 0.1 / √3.
fn soup(n: u64, seed: u64) -> Mesh {
    let mut rng = rng::stream(seed, SOUP_STREAM);
    let margin = SOUP_EDGE.1 / 3f32.sqrt() + 1e-3;
    let mut positions = Vec::with_capacity(3 * n as usize);
    for _ in 0..n {
        let center = Vec3::new(
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
        );
        let normal = rng::uniform_sphere(&mut rng);
        let (e1, e2) = rng::orthonormal_basis(normal);
        let radius = rng::range_f32(&mut rng, SOUP_EDGE.0, SOUP_EDGE.1) / 3f32.sqrt();
        let spin = std::f32::consts::TAU * rng::unit_f32(&mut rng);
        for k in 0..3 {
            let angle =
                spin + k as f32 * std::f32::consts::TAU / 3.0 + rng::range_f32(&mut rng, -0.3, 0.3);
            positions.push(center + (e1 * angle.cos() + e2 * angle.sin()) * radius);
        }
    }
    let indices = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let view = View::of_bounds(&raybench_geom::Aabb::new(Vec3::ZERO, Vec3::ONE));
    (positions, indices, view)
}

/// A `quads × quads` grid over `[-1, 1]²`, the x–z plane tilted about the x axis by `tilt_deg`
/// (the point (x, z) goes to (x, z·sin t, z·cos t)), normals facing +y.
fn plane(quads: u64, tilt_deg: f32) -> Mesh {
    let n = quads as u32;
    let (sin_t, cos_t) = tilt_deg.to_radians().sin_cos();
    let coord = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for row in 0..=n {
        let z = coord(row);
        for col in 0..=n {
            positions.push(Vec3::new(coord(col), z * sin_t, z * cos_t));
        }
    }
    (positions, quad_grid_indices(n), plane_view())
}

/// The triangles of an `n × n` grid of quads over `(n + 1)²` vertices stored row by row: two
/// per quad, `[a, c, d]` and `[a, d, b]` with `a`, `b` the quad's corners on its first row and
/// `c`, `d` those on the next.
pub(super) fn quad_grid_indices(n: u32) -> Vec<[u32; 3]> {
    let at = |row: u32, col: u32| row * (n + 1) + col;
    let mut indices = Vec::with_capacity(2 * (n as usize) * (n as usize));
    for row in 0..n {
        for col in 0..n {
            let (a, b) = (at(row, col), at(row, col + 1));
            let (c, d) = (at(row + 1, col), at(row + 1, col + 1));
            indices.push([a, c, d]);
            indices.push([a, d, b]);
        }
    }
    indices
}

/// From above and in front of the plane, which spans about ±1 around the origin.
fn plane_view() -> View {
    View {
        camera: Camera {
            eye: Vec3::new(0.0, 1.6, 2.2),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: Vec3::new(0.6, 2.5, 0.8),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_TRIANGLES;

    #[test]
    fn sphere_stacks_track_the_target() {
        assert_eq!(sphere_stacks(1), 2);
        let s = sphere_stacks(20_000) as u64;
        assert_eq!(4 * s * (s - 1), 19_880);
        let s = sphere_stacks(MAX_TRIANGLES) as u64;
        assert!(4 * s * (s - 1) <= MAX_TRIANGLES + MAX_TRIANGLES / 1000);
    }

    #[test]
    fn sphere_and_plane_face_outwards_and_up() {
        let (p, idx, _) = sphere(500, 2.0);
        for t in &idx {
            let [a, b, c] = t.map(|i| p[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "{t:?}");
        }
        let (p, idx, _) = plane(4, 10.0);
        for t in &idx {
            let [a, b, c] = t.map(|i| p[i as usize]);
            assert!((b - a).cross(c - a).y > 0.0, "{t:?}");
        }
    }

    #[test]
    fn soup_triangles_stay_in_the_unit_cube() {
        let (p, _, _) = soup(2000, 3);
        let cube = raybench_geom::Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!(p.iter().all(|&v| cube.contains(v)));
    }
}
