//! `terrain`: an fBm height field over a square grid, and the pieces `grass` and `city` reuse
//! (the noise, the height grid and a view that fills the frame with a square of ground).
//!
//! The noise is value noise: a pseudo-random value in [-1, 1] at every integer lattice point
//! (an integer hash of the point and a per-octave key), blended with the quintic fade
//! 6t⁵ - 15t⁴ + 10t³ so the surface has no creases at cell borders. Fractional Brownian motion
//! sums octaves, each at twice the frequency and `gain` times the amplitude of the one before,
//! and divides by the sum of the amplitudes, so the result stays in [-1, 1] for every octave
//! count and gain. Each octave's lattice is shifted by a seeded offset, so the octaves' cell
//! corners do not all line up at the origin.
//!
//! Detail is spread evenly over the whole square: the case a uniform grid handles well.

use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::rng;
use crate::{Camera, View};
use rand_core::Rng;
use rand_pcg::Pcg64Mcg;
use raybench_geom::Vec3;
use raybench_geom::rng::{GOLDEN_GAMMA, mix64};

const TERRAIN_STREAM: u64 = u64::from_be_bytes(*b"gen-terr");

/// Side of the terrain square: x and z in [-1, 1].
const TERRAIN_WIDTH: f32 = 2.0;
/// Lattice cells across the square at the first (coarsest) octave.
const TERRAIN_BASE_CELLS: f64 = 3.0;

pub(super) const TERRAIN: GeneratorInfo = GeneratorInfo {
    name: "terrain",
    description: "fBm (value noise) height field over [-1,1]² in x–z, y up: an n × n grid of quads, \
                  two triangles each (2·n² triangles), shared vertices; detail spread evenly",
    params: &[
        triangles(
            "approximate triangle count, rounded to the nearest 2·n² for an n × n grid",
            100_000.0,
        ),
        ParamInfo {
            key: "octaves",
            meaning: "noise octaves, each at twice the frequency of the one before",
            kind: Kind::Count { min: 1, max: 12 },
            default: 6.0,
        },
        ParamInfo {
            key: "roughness",
            meaning: "gain: amplitude of each octave relative to the one before",
            kind: Kind::Real { min: 0.0, max: 1.0 },
            default: 0.5,
        },
        ParamInfo {
            key: "height",
            meaning: "largest possible height above or below y = 0, as a fraction of the width",
            kind: Kind::Real { min: 0.0, max: 2.0 },
            default: 0.15,
        },
    ],
    uses_seed: true,
    build: |p, seed| {
        let quads = terrain_quads(p.count("triangles"));
        let octaves = p.count("octaves") as u32;
        let mut rng = rng::stream(seed, TERRAIN_STREAM);
        let noise = Fbm::new(
            &mut rng,
            octaves,
            p.get("roughness"),
            TERRAIN_BASE_CELLS / f64::from(TERRAIN_WIDTH),
        );
        let amplitude = p.get("height") * f64::from(TERRAIN_WIDTH);
        let half = TERRAIN_WIDTH / 2.0;
        let grid = HeightGrid::new(quads, half, |x, z| (amplitude * noise.at(x, z)) as f32);
        let view = terrain_view(half, grid.max_height());
        Ok(Built::new(grid.positions(), grid.indices(), view))
    },
};

/// Quads per side `n` with `2n²` nearest `target`. At `MAX_TRIANGLES` this is 5000.
fn terrain_quads(target: u64) -> u32 {
    ((target as f64 / 2.0).sqrt().round() as u32).max(1)
}

/// From above the (+x, +z) corner, 45° above the horizon, the square filling the frame.
fn terrain_view(half: f32, max_height: f32) -> View {
    let mut view = view_over_square(half, 45.0, 45.0, 50.0, 1.1, max_height + 0.2 * half);
    // A sun low on the -x side, so ridges cast shadows over the valleys behind them.
    view.light = Vec3::new(-1.5, 2.0, 1.0) * half;
    view
}

/// Fractional Brownian motion over seeded 2D value noise; see the module documentation.
#[derive(Debug)]
pub(super) struct Fbm {
    octaves: Vec<Octave>,
    /// Sum of the octaves' amplitudes: dividing by it keeps the sum in [-1, 1].
    norm: f64,
}

#[derive(Debug)]
struct Octave {
    key: u64,
    frequency: f64,
    amplitude: f64,
    offset: [f64; 2],
}

impl Fbm {
    /// `octaves` octaves, the first at `frequency` lattice cells per unit length, each next one
    /// at twice the frequency and `gain` times the amplitude.
    pub(super) fn new(rng: &mut Pcg64Mcg, octaves: u32, gain: f64, frequency: f64) -> Fbm {
        let mut amplitude = 1.0;
        let mut frequency = frequency;
        let mut list = Vec::with_capacity(octaves as usize);
        for _ in 0..octaves {
            list.push(Octave {
                key: rng.next_u64(),
                frequency,
                amplitude,
                // Whole lattice cells would change nothing: the fraction is what shifts.
                offset: [
                    1024.0 * f64::from(rng::unit_f32(rng)),
                    1024.0 * f64::from(rng::unit_f32(rng)),
                ],
            });
            amplitude *= gain;
            frequency *= 2.0;
        }
        let norm = list
            .iter()
            .map(|o| o.amplitude)
            .sum::<f64>()
            .max(f64::MIN_POSITIVE);
        Fbm {
            octaves: list,
            norm,
        }
    }

    /// The height at `(x, z)`, in [-1, 1].
    pub(super) fn at(&self, x: f32, z: f32) -> f64 {
        let (x, z) = (f64::from(x), f64::from(z));
        let sum: f64 = self
            .octaves
            .iter()
            .map(|o| {
                o.amplitude
                    * value_noise(
                        o.key,
                        x * o.frequency + o.offset[0],
                        z * o.frequency + o.offset[1],
                    )
            })
            .sum();
        (sum / self.norm).clamp(-1.0, 1.0)
    }
}

/// Smooth value noise in [-1, 1]: the lattice values of the cell's four corners, blended with
/// the quintic fade (zero first and second derivative at the corners).
fn value_noise(key: u64, x: f64, z: f64) -> f64 {
    let (x0, z0) = (x.floor(), z.floor());
    let (fx, fz) = (fade(x - x0), fade(z - z0));
    let (i, j) = (x0 as i64, z0 as i64);
    let corner = |di: i64, dj: i64| lattice_value(key, i + di, j + dj);
    let near = lerp(corner(0, 0), corner(1, 0), fx);
    let far = lerp(corner(0, 1), corner(1, 1), fx);
    lerp(near, far, fz)
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// A value in [-1, 1) for lattice point `(i, j)`: the two coordinates are multiplied by
/// different odd constants, combined with the key, and mixed by SplitMix64's finaliser, whose
/// top 53 bits make the value.
fn lattice_value(key: u64, i: i64, j: i64) -> f64 {
    let h = mix64(
        key ^ (i as u64).wrapping_mul(GOLDEN_GAMMA)
            ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
    );
    (h >> 11) as f64 * (2.0 / (1u64 << 53) as f64) - 1.0
}

/// Heights on the `(quads + 1)²` vertices of a square grid over `[-half, half]²` in x–z,
/// row-major with z along the rows. Each quad is split along its diagonal from the (-x, -z)
/// corner to the (+x, +z) corner; both triangles face +y.
#[derive(Debug)]
pub(super) struct HeightGrid {
    quads: u32,
    half: f32,
    heights: Vec<f32>,
}

impl HeightGrid {
    pub(super) fn new(quads: u32, half: f32, height: impl Fn(f32, f32) -> f32) -> HeightGrid {
        let mut grid = HeightGrid {
            quads,
            half,
            heights: Vec::with_capacity(((quads + 1) * (quads + 1)) as usize),
        };
        for row in 0..=quads {
            let z = grid.coord(row);
            for col in 0..=quads {
                let h = height(grid.coord(col), z);
                grid.heights.push(h);
            }
        }
        grid
    }

    /// Coordinate of grid line `i`, the same expression for x and z (and in `surface_height`).
    fn coord(&self, i: u32) -> f32 {
        -self.half + 2.0 * self.half * (i as f32 / self.quads as f32)
    }

    fn height_at(&self, row: u32, col: u32) -> f32 {
        self.heights[(row * (self.quads + 1) + col) as usize]
    }

    pub(super) fn triangle_count(quads: u32) -> u64 {
        2 * u64::from(quads) * u64::from(quads)
    }

    pub(super) fn max_height(&self) -> f32 {
        self.heights
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max)
    }

    pub(super) fn positions(&self) -> Vec<Vec3> {
        let n = self.quads;
        let mut positions = Vec::with_capacity(self.heights.len());
        for row in 0..=n {
            let z = self.coord(row);
            for col in 0..=n {
                positions.push(Vec3::new(self.coord(col), self.height_at(row, col), z));
            }
        }
        positions
    }

    /// Indices into [`HeightGrid::positions`].
    pub(super) fn indices(&self) -> Vec<[u32; 3]> {
        super::basic::quad_grid_indices(self.quads)
    }

    /// The height of the triangulated surface (not of the noise) at `(x, z)`, clamped to the
    /// square: a point placed at this height lies on the mesh up to rounding.
    pub(super) fn surface_height(&self, x: f32, z: f32) -> f32 {
        let n = self.quads;
        let cell = |v: f32| {
            let i = ((v + self.half) / (2.0 * self.half) * n as f32).floor();
            (i.max(0.0) as u32).min(n - 1)
        };
        let (col, row) = (cell(x), cell(z));
        let (x0, x1) = (self.coord(col), self.coord(col + 1));
        let (z0, z1) = (self.coord(row), self.coord(row + 1));
        let fx = ((x - x0) / (x1 - x0)).clamp(0.0, 1.0);
        let fz = ((z - z0) / (z1 - z0)).clamp(0.0, 1.0);
        let ha = self.height_at(row, col);
        let hb = self.height_at(row, col + 1);
        let hc = self.height_at(row + 1, col);
        let hd = self.height_at(row + 1, col + 1);
        if fz >= fx {
            // Triangle a (0,0), c (0,1), d (1,1).
            ha + (hc - ha) * fz + (hd - hc) * fx
        } else {
            // Triangle a (0,0), d (1,1), b (1,0).
            ha + (hb - ha) * fx + (hd - hb) * fz
        }
    }
}

/// A view of the square `|x|, |z| <= half` around the origin (y up), seen from `azimuth_deg`
/// (0: from +z, 90: from +x) and `elevation_deg` above the horizon, with a vertical field of
/// view `fov_y_deg`: the eye is placed so that the rays through the four corners of the 4:3
/// image meet the plane y = 0 inside the square shrunk to `fill` of its size, so the square
/// covers the whole frame. If that puts the eye lower than `min_eye_height` (inside tall
/// geometry), the camera tilts up a degree at a time, which raises the eye for the same
/// footprint; at 85° it moves back along its line of sight instead. The light is left above
/// the centre; callers usually move it.
pub(super) fn view_over_square(
    half: f32,
    azimuth_deg: f32,
    elevation_deg: f32,
    fov_y_deg: f32,
    fill: f32,
    min_eye_height: f32,
) -> View {
    let mut elevation = elevation_deg;
    loop {
        let (eye, target) = fit_over_square(half, azimuth_deg, elevation, fov_y_deg, fill);
        let steepest = elevation >= 85.0;
        if eye.y >= min_eye_height || steepest {
            let eye = if eye.y >= min_eye_height {
                eye
            } else {
                target + (eye - target) * (min_eye_height / eye.y)
            };
            return View {
                camera: Camera {
                    eye,
                    target,
                    up: Vec3::Y,
                    fov_y_deg,
                },
                light: Vec3::new(0.0, 2.0 * half, 0.0),
            };
        }
        elevation = (elevation + 1.0).min(85.0);
    }
}

/// Eye and target for [`view_over_square`] at one elevation, which must exceed the angle of
/// the image's top corners above the view direction (about 29° for a 50° field of view).
fn fit_over_square(
    half: f32,
    azimuth_deg: f32,
    elevation_deg: f32,
    fov_y_deg: f32,
    fill: f32,
) -> (Vec3, Vec3) {
    let (sin_az, cos_az) = azimuth_deg.to_radians().sin_cos();
    let (sin_el, cos_el) = elevation_deg.to_radians().sin_cos();
    let back = Vec3::new(cos_el * sin_az, sin_el, cos_el * cos_az);
    let forward = -back;
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan_y = (fov_y_deg.to_radians() * 0.5).tan();
    let tan_x = tan_y * 4.0 / 3.0;
    // With the target at the origin and the eye at `back · D`, corner ray `d` meets y = 0 at
    // `D · (back + d · t)` with `t = -back.y / d.y`: the footprint scales with D.
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
        let d = forward + right * (sx * tan_x) + up * (sy * tan_y);
        assert!(
            d.y < 0.0,
            "view_over_square: elevation {elevation_deg}° is too low for a {fov_y_deg}° view"
        );
        let p = back + d * (-back.y / d.y);
        for (k, v) in [p.x, p.z].into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    let extent = ((hi[0] - lo[0]).max(hi[1] - lo[1])) * 0.5;
    let distance = half * fill / extent;
    // Shift the target so the footprint is centred on the square.
    let target = -Vec3::new(lo[0] + hi[0], 0.0, lo[1] + hi[1]) * (0.5 * distance);
    (target + back * distance, target)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_stays_in_range_and_is_smooth() {
        let mut rng = rng::stream(3, TERRAIN_STREAM);
        let fbm = Fbm::new(&mut rng, 6, 0.5, 1.5);
        let mut prev = fbm.at(-1.0, 0.3);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 1..=2000 {
            let x = -1.0 + 2.0 * i as f32 / 2000.0;
            let h = fbm.at(x, 0.3);
            assert!((-1.0..=1.0).contains(&h));
            // Continuous: a step of 0.001 moves the height only a little.
            assert!((h - prev).abs() < 0.05, "jump at {x}: {prev} -> {h}");
            (lo, hi, prev) = (lo.min(h), hi.max(h), h);
        }
        assert!(hi - lo > 0.2, "flat noise: {lo}..{hi}");
    }

    #[test]
    fn surface_height_matches_the_vertices_and_interpolates() {
        let grid = HeightGrid::new(4, 1.0, |x, z| x * x + 0.5 * z);
        let positions = grid.positions();
        for p in &positions {
            assert!((grid.surface_height(p.x, p.z) - p.y).abs() < 1e-6, "{p}");
        }
        // Midpoint of a diagonal edge: the mean of its two ends.
        let (a, d) = (positions[0], positions[6]);
        let m = (a + d) * 0.5;
        assert!((grid.surface_height(m.x, m.z) - m.y).abs() < 1e-6);
    }

    /// The rays through the image corners (as `primary_rays` makes them, 4:3) meet y = 0
    /// inside the square, and at least one of them near its edge.
    #[test]
    fn square_views_put_the_frame_inside_the_square() {
        for (az, el, fov) in [(45.0, 45.0, 50.0), (30.0, 16.0, 25.0), (35.0, 50.0, 50.0)] {
            let v = view_over_square(2.0, az, el, fov, 0.9, 0.0);
            assert!(v.is_usable());
            let c = v.camera;
            let forward = (c.target - c.eye).normalize();
            let right = forward.cross(c.up).normalize();
            let up = right.cross(forward);
            let tan_y = (c.fov_y_deg.to_radians() * 0.5).tan();
            let mut reach = 0.0f32;
            for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let d = forward + right * (sx * tan_y * 4.0 / 3.0) + up * (sy * tan_y);
                let p = c.eye + d * (-c.eye.y / d.y);
                assert!(
                    d.y < 0.0 && p.x.abs() <= 1.801 && p.z.abs() <= 1.801,
                    "{az}: {p}"
                );
                reach = reach.max(p.x.abs()).max(p.z.abs());
            }
            assert!(reach > 1.79, "{az}: {reach}");
            println!("{az} {el} {fov}: eye {} target {}", c.eye, c.target);
        }
    }
}
