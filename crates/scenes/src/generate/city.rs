//! `city`: blocks of box buildings on a ground plane.
//!
//! Everything is axis-aligned and on a dyadic grid, so coplanarity is exact: lots are 1 × 1,
//! blocks are 4 × 4 lots, streets are 0.5 wide, heights are multiples of 0.25 and some
//! buildings are set back 0.125 from their lot. Buildings on neighbouring lots share wall
//! planes (and, when of equal height, the wall triangles coincide), whole blocks are often
//! built to one height (coplanar roofs), and street fronts line up across the city. Two large
//! ground triangles lie under everything. Split planes land exactly on thousands of faces:
//! the flat, coplanar case.
//!
//! Some lots stay empty (squares): buildings fill exactly the number the triangle budget asks
//! for, on lots picked at random.

use super::terrain::view_over_square;
use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::View;
use crate::rng;
use rand_pcg::Pcg64Mcg;
use raybench_geom::Vec3;

const CITY_STREAM: u64 = u64::from_be_bytes(*b"gen-city");

/// Lots per block side, and the block pitch (4 lots of 1 plus a 0.5 street).
const LOTS_PER_SIDE: u32 = 4;
const STREET: f32 = 0.5;
const BLOCK_PITCH: f32 = LOTS_PER_SIDE as f32 + STREET;
const HEIGHT_STEP: f32 = 0.25;
const SETBACK: f32 = 0.125;
/// Roof and four walls (no floor: the ground is there).
const TRIANGLES_PER_BUILDING: u64 = 10;
const GROUND_TRIANGLES: u64 = 2;
/// Chance that a block is built to one height throughout (a terrace), and that a building in
/// any other block is set back from its lot.
const UNIFORM_BLOCK_CHANCE: f32 = 0.35;
const SETBACK_CHANCE: f32 = 0.25;

pub(super) const CITY: GeneratorInfo = GeneratorInfo {
    name: "city",
    description: "axis-aligned box buildings (10 triangles: roof and walls) on 4 × 4-lot blocks \
                  with streets, over a 2-triangle ground plane at y = 0; dyadic coordinates, so \
                  walls and roofs of neighbours are exactly coplanar",
    params: &[
        triangles(
            "approximate triangle count: 10 per building plus 2 for the ground",
            100_000.0,
        ),
        ParamInfo {
            key: "max_height",
            meaning: "tallest building in lot widths (a lot is 1 × 1), reached downtown",
            kind: Kind::Real {
                min: 0.25,
                max: 64.0,
            },
            default: 8.0,
        },
    ],
    uses_seed: true,
    build: |p, seed| Ok(city(p.count("triangles"), p.f32("max_height"), seed)),
};

/// Buildings for a budget of `target` triangles: at least one.
fn building_count(target: u64) -> u64 {
    let n =
        (target.saturating_sub(GROUND_TRIANGLES) as f64 / TRIANGLES_PER_BUILDING as f64).round();
    (n as u64).max(1)
}

/// Blocks per side: the smallest square of blocks with a lot for every building.
fn blocks_per_side(buildings: u64) -> u32 {
    let lots_per_block = u64::from(LOTS_PER_SIDE * LOTS_PER_SIDE);
    let mut b = ((buildings as f64 / lots_per_block as f64).sqrt().ceil() as u64).max(1);
    while b * b * lots_per_block < buildings {
        b += 1;
    }
    b as u32
}

fn city(target: u64, max_height: f32, seed: u64) -> Built {
    let buildings = building_count(target);
    let blocks = blocks_per_side(buildings);
    let lots_side = blocks * LOTS_PER_SIDE;
    let lot_count = lots_side as usize * lots_side as usize;
    let mut rng = rng::stream(seed, CITY_STREAM);

    // Which lots are built: the first `buildings` of a partial Fisher–Yates shuffle, in lot
    // order so the triangles run street by street.
    let mut lots: Vec<u32> = (0..lot_count as u32).collect();
    for i in 0..buildings as usize {
        let j = i + below(&mut rng, (lot_count - i) as u32) as usize;
        lots.swap(i, j);
    }
    lots.truncate(buildings as usize);
    lots.sort_unstable();

    // Per block: one height for the whole block, or none (each building draws its own).
    let block_height: Vec<Option<f32>> = (0..blocks * blocks)
        .map(|b| {
            let (bx, bz) = (b % blocks, b / blocks);
            let uniform = rng::unit_f32(&mut rng) < UNIFORM_BLOCK_CHANCE;
            let h = building_height(&mut rng, max_height, downtown(bx, bz, blocks));
            uniform.then_some(h)
        })
        .collect();

    // City centred on the origin: lot column c starts at origin + (c / 4)·4.5 + (c % 4).
    // (9·blocks - 1) / 4 is a multiple of 0.25, so every coordinate is dyadic.
    let half = (BLOCK_PITCH * blocks as f32 - STREET) / 2.0;
    let lot_start =
        |c: u32| -half + (c / LOTS_PER_SIDE) as f32 * BLOCK_PITCH + (c % LOTS_PER_SIDE) as f32;

    let ground = half + STREET;
    let mut positions = vec![
        Vec3::new(-ground, 0.0, -ground),
        Vec3::new(ground, 0.0, -ground),
        Vec3::new(ground, 0.0, ground),
        Vec3::new(-ground, 0.0, ground),
    ];
    let mut indices = vec![[0, 2, 1], [0, 3, 2]];
    positions.reserve(8 * lots.len());
    indices.reserve(TRIANGLES_PER_BUILDING as usize * lots.len());
    let mut tallest = 0.0f32;
    for &lot in &lots {
        let (cx, cz) = (lot % lots_side, lot / lots_side);
        let block = (cz / LOTS_PER_SIDE) * blocks + cx / LOTS_PER_SIDE;
        let (height, inset) = match block_height[block as usize] {
            Some(h) => (h, 0.0),
            None => {
                let h = building_height(
                    &mut rng,
                    max_height,
                    downtown(cx / LOTS_PER_SIDE, cz / LOTS_PER_SIDE, blocks),
                );
                let set_back = rng::unit_f32(&mut rng) < SETBACK_CHANCE;
                (h, if set_back { SETBACK } else { 0.0 })
            }
        };
        let (x0, z0) = (lot_start(cx) + inset, lot_start(cz) + inset);
        let (x1, z1) = (lot_start(cx) + 1.0 - inset, lot_start(cz) + 1.0 - inset);
        tallest = tallest.max(height);
        push_box(
            &mut positions,
            &mut indices,
            [x0, 0.0, z0],
            [x1, height, z1],
        );
    }
    debug_assert_eq!(
        indices.len() as u64,
        GROUND_TRIANGLES + TRIANGLES_PER_BUILDING * buildings
    );

    Built::new(positions, indices, city_view(ground, tallest))
}

/// Uniform in `0..n` (n ≥ 1), by rejection so that no value is favoured.
fn below(rng: &mut Pcg64Mcg, n: u32) -> u32 {
    use rand_core::Rng;
    let zone = u32::MAX - u32::MAX % n;
    loop {
        let v = rng.next_u32();
        if v < zone {
            return v % n;
        }
    }
}

/// 1 in the central blocks, falling to 0.25 at the city's corners.
fn downtown(bx: u32, bz: u32, blocks: u32) -> f32 {
    let mid = (blocks as f32 - 1.0) / 2.0;
    let r = if blocks > 1 {
        ((bx as f32 - mid).powi(2) + (bz as f32 - mid).powi(2)).sqrt() / (mid * 2f32.sqrt())
    } else {
        0.0
    };
    0.25 + 0.75 * (1.0 - r).max(0.0).powi(2)
}

/// A height in multiples of 0.25 between 0.25 and `max_height`: mostly low (flat boxes),
/// tall ones downtown.
fn building_height(rng: &mut Pcg64Mcg, max_height: f32, downtown: f32) -> f32 {
    let u = rng::unit_f32(rng);
    let h = max_height * downtown * u * u;
    let steps = (h / HEIGHT_STEP).round().max(1.0);
    let top = (max_height / HEIGHT_STEP).floor().max(1.0);
    steps.min(top) * HEIGHT_STEP
}

/// An axis-aligned box without a floor: 8 vertices, 10 triangles, counter-clockwise from
/// outside.
fn push_box(positions: &mut Vec<Vec3>, indices: &mut Vec<[u32; 3]>, lo: [f32; 3], hi: [f32; 3]) {
    let base = positions.len() as u32;
    // Corner k: bit 0 picks x, bit 1 picks y, bit 2 picks z.
    for k in 0..8u32 {
        let pick = |bit: u32, axis: usize| if k & bit == 0 { lo[axis] } else { hi[axis] };
        positions.push(Vec3::new(pick(1, 0), pick(2, 1), pick(4, 2)));
    }
    let quads: [[u32; 4]; 5] = [
        [2, 6, 7, 3], // +y roof
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    for [a, b, c, d] in quads {
        indices.push([base + a, base + b, base + c]);
        indices.push([base + a, base + c, base + d]);
    }
}

/// From above the (+x, +z) side, 50° above the horizon: the ground square fills the frame.
/// The eye stays above the tallest roof (`tallest`): for a small city of tall towers the
/// camera tilts down towards the vertical, then backs off (see `view_over_square`).
fn city_view(ground_half: f32, tallest: f32) -> View {
    let mut view = view_over_square(ground_half, 35.0, 50.0, 50.0, 1.0, tallest + 1.0);
    // Afternoon sun: buildings shade their neighbours and the streets.
    view.light = Vec3::new(
        -0.5 * ground_half,
        1.5 * ground_half + 2.0 * tallest,
        0.8 * ground_half,
    );
    view
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_and_blocks() {
        assert_eq!(building_count(1), 1);
        assert_eq!(building_count(100_000), 10_000);
        assert_eq!(blocks_per_side(1), 1);
        assert_eq!(blocks_per_side(16), 1);
        assert_eq!(blocks_per_side(17), 2);
        assert_eq!(blocks_per_side(10_000), 25);
    }

    #[test]
    fn heights_are_steps_within_the_maximum() {
        let mut rng = rng::stream(1, CITY_STREAM);
        for max in [0.25, 0.3, 8.0, 64.0] {
            for _ in 0..1000 {
                let h = building_height(&mut rng, max, 1.0);
                assert!(
                    h >= HEIGHT_STEP && h <= max.max(HEIGHT_STEP),
                    "{h} for {max}"
                );
                assert_eq!((h / HEIGHT_STEP).fract(), 0.0);
            }
        }
    }

    #[test]
    fn boxes_face_outwards() {
        let (mut p, mut idx) = (Vec::new(), Vec::new());
        push_box(&mut p, &mut idx, [0.0, 0.0, 0.0], [1.0, 2.0, 3.0]);
        let center = Vec3::new(0.5, 1.0, 1.5);
        for t in &idx {
            let [a, b, c] = t.map(|i| p[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot((a + b + c) / 3.0 - center) > 0.0, "{t:?}");
        }
    }
}
