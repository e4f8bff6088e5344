//! `grass`: blades of grass spread uniformly over gently undulating ground.
//!
//! Many small, thin, slightly curved strips standing close together: dense, evenly spread
//! detail with lots of empty space between blades, and shadow rays that pass through a
//! thicket. Sizes are absolute (think metres): blades are 0.15–0.45 tall and 0.008–0.016 wide
//! at the base, so the default 200 blades per unit area leave about 0.07 between neighbours.
//!
//! Layout (relied on by tests): the ground grid's `2·g²` triangles come first, then each
//! blade's `2·segments - 1` triangles, blade after blade.

use super::terrain::{Fbm, HeightGrid, view_over_square};
use super::{Built, GeneratorInfo, Kind, MAX_TRIANGLES, ParamInfo};
use crate::{View, rng};
use raybench_geom::Vec3;
use std::f32::consts::TAU;

const GRASS_STREAM: u64 = u64::from_be_bytes(*b"gen-gras");
const GRASS_GROUND_STREAM: u64 = u64::from_be_bytes(*b"gen-grgd");

/// Ground quads per unit of field side, and the limits on quads per side: 16 × 16 quads
/// (512 triangles) on the default 10 × 10 field.
const GROUND_QUADS_PER_UNIT: f32 = 1.6;
const GROUND_QUADS: (u32, u32) = (4, 256);
/// Largest height of the ground above or below y = 0, as a fraction of the field side.
const GROUND_AMPLITUDE: f32 = 0.02;
/// Two octaves, the first with 2 lattice cells across the field: bumps a few units wide.
const GROUND_OCTAVES: u32 = 2;
const GROUND_BASE_CELLS: f64 = 2.0;

/// Blade height, base width and total bend (radians between the base and tip directions).
const BLADE_HEIGHT: (f32, f32) = (0.15, 0.45);
const BLADE_WIDTH: (f32, f32) = (0.008, 0.016);
const BLADE_BEND: (f32, f32) = (0.1, 1.0);
/// How far blade centres keep from the field's edge: half the widest base.
const EDGE_MARGIN: f32 = BLADE_WIDTH.1 / 2.0;

pub(super) const GRASS: GeneratorInfo = GeneratorInfo {
    name: "grass",
    description: "blades of grass (tapered, bent strips of 2·segments - 1 triangles) at uniform \
                  random positions on gently undulating ground, y up: round(density·field²) \
                  blades plus 2·g² ground triangles (g = 1.6·field, 4 to 256); the defaults make \
                  20,000 blades, 140,512 triangles",
    params: &[
        ParamInfo {
            key: "density",
            meaning: "blades per unit area (about 1,200 triangles at 1 to 4,000,000 at 5,700 \
                      with the default field and segments)",
            kind: Kind::Real {
                min: 0.1,
                max: 100_000.0,
            },
            default: 200.0,
        },
        ParamInfo {
            key: "field",
            meaning: "side of the square field, centred at the origin",
            kind: Kind::Real {
                min: 0.5,
                max: 1000.0,
            },
            default: 10.0,
        },
        ParamInfo {
            key: "segments",
            meaning: "segments per blade (2·segments - 1 triangles, the last one the tip)",
            kind: Kind::Count { min: 2, max: 8 },
            default: 4.0,
        },
    ],
    uses_seed: true,
    build: |p, seed| {
        grass(
            p.get("density"),
            p.f32("field"),
            p.count("segments") as u32,
            seed,
        )
    },
};

fn ground_quads(field: f32) -> u32 {
    ((field * GROUND_QUADS_PER_UNIT).round() as u32).clamp(GROUND_QUADS.0, GROUND_QUADS.1)
}

fn grass(density: f64, field: f32, segments: u32, seed: u64) -> Result<Built, String> {
    let blades = (density * f64::from(field) * f64::from(field)).round() as u64;
    if blades == 0 {
        return Err(format!(
            "density {density} on a {field} × {field} field makes no blades"
        ));
    }
    let quads = ground_quads(field);
    let per_blade = u64::from(2 * segments - 1);
    let total = HeightGrid::triangle_count(quads) + blades * per_blade;
    if total > MAX_TRIANGLES {
        return Err(format!(
            "density {density} on a {field} × {field} field makes {blades} blades, {total} \
             triangles: more than the limit {MAX_TRIANGLES} (memory)"
        ));
    }

    let half = field / 2.0;
    let mut rng = rng::stream(seed, GRASS_GROUND_STREAM);
    let noise = Fbm::new(
        &mut rng,
        GROUND_OCTAVES,
        0.5,
        GROUND_BASE_CELLS / f64::from(field),
    );
    let amplitude = GROUND_AMPLITUDE * field;
    let ground = HeightGrid::new(quads, half, |x, z| amplitude * noise.at(x, z) as f32);

    let mut positions = ground.positions();
    let mut indices = ground.indices();
    let blade_vertices = 2 * segments as usize + 1;
    positions.reserve(blades as usize * blade_vertices);
    indices.reserve(blades as usize * per_blade as usize);
    for i in 0..blades {
        // One stream per blade: blade i is the same whatever the density.
        let mut rng = rng::item_stream(seed, GRASS_STREAM, i);
        let place = half - EDGE_MARGIN;
        let x = rng::range_f32(&mut rng, -place, place);
        let z = rng::range_f32(&mut rng, -place, place);
        let blade = Blade {
            root: Vec3::new(x, ground.surface_height(x, z), z),
            yaw: TAU * rng::unit_f32(&mut rng),
            height: rng::range_f32(&mut rng, BLADE_HEIGHT.0, BLADE_HEIGHT.1),
            width: rng::range_f32(&mut rng, BLADE_WIDTH.0, BLADE_WIDTH.1),
            bend: rng::range_f32(&mut rng, BLADE_BEND.0, BLADE_BEND.1),
            bend_azimuth: TAU * rng::unit_f32(&mut rng),
        };
        let base = positions.len() as u32;
        blade.push(segments, &ground, &mut positions, &mut indices, base);
    }
    debug_assert_eq!(indices.len() as u64, total);

    let view = grass_view(half, ground.max_height());
    Ok(Built::new(positions, indices, view))
}

/// One blade: a strip whose centre line starts at `root` and curves, at a constant rate, from
/// straight up towards `bend_azimuth` until it leans `bend` radians at the tip; it is `width`
/// wide at the root (across the direction `yaw`) and narrows linearly to a point.
struct Blade {
    root: Vec3,
    yaw: f32,
    height: f32,
    width: f32,
    bend: f32,
    bend_azimuth: f32,
}

impl Blade {
    /// Appends `2·segments + 1` vertices (left and right at each level below the tip, then the
    /// tip) and `2·segments - 1` triangles. The two root vertices sit on the ground surface.
    fn push(
        &self,
        segments: u32,
        ground: &HeightGrid,
        positions: &mut Vec<Vec3>,
        indices: &mut Vec<[u32; 3]>,
        base: u32,
    ) {
        let across = Vec3::new(self.yaw.cos(), 0.0, self.yaw.sin());
        let lean = Vec3::new(self.bend_azimuth.cos(), 0.0, self.bend_azimuth.sin());
        let step = self.height / segments as f32;
        let mut center = self.root;
        for k in 0..=segments {
            if k > 0 {
                // Direction at the middle of segment k: the lean grows linearly along the blade.
                let angle = self.bend * (k as f32 - 0.5) / segments as f32;
                center += (lean * angle.sin() + Vec3::Y * angle.cos()) * step;
            }
            if k == segments {
                positions.push(center);
                break;
            }
            let half_width = 0.5 * self.width * (1.0 - k as f32 / segments as f32);
            let (mut left, mut right) =
                (center - across * half_width, center + across * half_width);
            if k == 0 {
                left.y = ground.surface_height(left.x, left.z);
                right.y = ground.surface_height(right.x, right.z);
            }
            positions.push(left);
            positions.push(right);
        }
        let left = |k: u32| base + 2 * k;
        let right = |k: u32| base + 2 * k + 1;
        for k in 0..segments - 1 {
            indices.push([left(k), right(k), right(k + 1)]);
            indices.push([left(k), right(k + 1), left(k + 1)]);
        }
        let tip = base + 2 * segments;
        indices.push([left(segments - 1), right(segments - 1), tip]);
    }
}

/// Low over the (+x, +z) side, looking across the field through a 25° lens, 16° or more down: the top of the
/// image just reaches the far edge, so blades and ground fill the frame. The eye stays above
/// the tallest blade.
fn grass_view(half: f32, max_ground: f32) -> View {
    let mut view = view_over_square(
        half,
        30.0,
        16.0,
        25.0,
        0.92,
        max_ground + BLADE_HEIGHT.1 + 0.1,
    );
    // A high sun to one side: shadow rays cross the neighbouring blades.
    view.light = Vec3::new(-0.6, 1.5, 0.4) * half;
    view
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_counts_match_the_description() {
        assert_eq!(ground_quads(10.0), 16);
        let built = grass(200.0, 10.0, 4, 1).unwrap();
        assert_eq!(built.indices.len(), 140_512);
    }

    #[test]
    fn blades_have_no_zero_area_triangles() {
        let built = grass(5.0, 10.0, 8, 2).unwrap();
        for t in &built.indices {
            let [a, b, c] = t.map(|i| built.positions[i as usize]);
            assert!((b - a).cross(c - a).length() > 1e-9, "{a} {b} {c}");
        }
    }
}
