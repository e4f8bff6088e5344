//! `teapot-in-stadium`: a small glass teapot on the centre spot of a 1 km stadium, the classic
//! "teapot in a stadium" case that defeats uniform grids: almost all the space is empty, the
//! stadium's triangles are spread thinly over a huge box, and the teapot's thousands of
//! triangles sit in one of its cells.
//!
//! Geometry, in metres, y up, centred on the origin:
//! * field: a flat grid of quads over the rectangle `±330 × ±230` at y = 0 (about 10 % of the
//!   stadium's triangles). Its corners reach under the stands.
//! * stands: rows of steps around an oval, the inner oval being the ellipse with semi-axes
//!   330 × 230, the outer one 500 × 400; each step an open box (10 triangles: no bottom, it
//!   stands on the ground) from y = 0 up to its row's height, rising from 2 m at the front to
//!   60 m at the back (about 78 % of the triangles). Columns of steps come in blocks of 8 to
//!   20 separated by one-column aisles, and each block's heights are scaled by a factor in
//!   `1 ± 0.06`, all drawn from the seed; the seed never changes the triangle count.
//! * roof: a ring of slanted panels (closed boxes, 12 triangles) over the back 55 % of the
//!   stands, 92 m high at its inner edge and 76 m at the outer one, with one pillar (an open
//!   box) per column of panels on the outer edge (about 12 %).
//!
//! The stadium's triangle count is within 5 % of `stadium_triangles` from the smallest allowed
//! value, 1,000, up (see [`Layout`]). The teapot is [`teapot_mesh`] scaled to
//! `size_ratio × 1000 m` wide, centred on the origin and standing on the field: the centre of
//! its bottom is on y = 0 and the bottom curves up from there (to 2.3 % of the width at the
//! body's edge), so the glass and the field nearly touch without being coplanar. Stadium
//! triangles come first (material 0, [`Material::DEFAULT`]), then the teapot's (material 1,
//! [`Material::GLASS`]).
//!
//! Precision: the teapot is at the origin, where f32 is finest, so even at `size_ratio = 1e-6`
//! (a 1 mm teapot, 1e6 times smaller than the scene) its vertices keep f32's full relative
//! precision (about 1e-10 m here) and its shape is exact to rounding. What suffers is any
//! structure that divides space uniformly: a grid would need about 10^6 cells per axis to
//! separate the teapot's triangles. Had the teapot been placed near the stands instead (500 m,
//! where an f32 step is 3e-5 m) a 1 mm teapot would have been only about 30 steps wide.

use super::teapot::teapot_mesh;
use super::{Built, GeneratorInfo, Kind, ParamInfo};
use crate::rng::{self, range_f32, unit_f32};
use crate::{Camera, Material, NamedView, View};
use raybench_geom::Vec3;
use std::f32::consts::TAU;

/// Random stream for the stands' blocks, aisles and heights.
const STADIUM_STREAM: u64 = u64::from_be_bytes(*b"gen-stad");

pub(super) const TEAPOT_IN_STADIUM: GeneratorInfo = GeneratorInfo {
    name: "teapot-in-stadium",
    description: "glass Utah teapot on the centre spot of a 1 km stadium (field, tiered stands with aisles, roof ring): the teapot-in-a-stadium problem",
    params: &[
        // The two counts together stay within MAX_TRIANGLES (50 million).
        ParamInfo {
            key: "stadium_triangles",
            meaning: "triangles in the stadium (field, stands, roof), within 5 %",
            kind: Kind::Count {
                min: 1_000,
                max: 40_000_000,
            },
            default: 200_000.0,
        },
        ParamInfo {
            key: "teapot_triangles",
            meaning: "triangles in the teapot, as for `teapot` (within 5 %)",
            kind: Kind::Count {
                min: 64,
                max: 10_000_000,
            },
            default: 20_000.0,
        },
        ParamInfo {
            key: "size_ratio",
            meaning: "teapot width / stadium width (1000 m): 3e-4 is a 0.3 m teapot",
            kind: Kind::Real {
                min: 1e-6,
                max: 0.5,
            },
            default: 3e-4,
        },
    ],
    uses_seed: true,
    build: |p, seed| {
        build(
            p.count("stadium_triangles"),
            p.count("teapot_triangles"),
            p.get("size_ratio"),
            seed,
        )
    },
};

/// Half extents of the field, which are also the semi-axes of the stands' inner oval.
const FIELD: (f32, f32) = (330.0, 230.0);
/// From the inner to the outer oval (semi-axes 500 × 400).
const STAND_DEPTH: f32 = 170.0;
/// Outer width along x, the stadium size that `size_ratio` refers to.
const STADIUM_WIDTH: f32 = 2.0 * (FIELD.0 + STAND_DEPTH);
/// Height of the first row of steps' front wall and of the back row.
const STAND_HEIGHTS: (f32, f32) = (2.0, 60.0);
/// Each block's heights are scaled by `1 ± HEIGHT_JITTER`.
const HEIGHT_JITTER: f32 = 0.06;
/// Columns of steps per block between two aisles.
const BLOCK_COLUMNS: (u32, u32) = (8, 20);
/// The roof covers the stands from this fraction of their depth to the back.
const ROOF_FROM: f32 = 0.45;
/// Height of the roof's top surface at its inner and outer edges: above the back row (at most
/// 60 · 1.06 = 63.6 m) everywhere.
const ROOF_HEIGHTS: (f32, f32) = (92.0, 76.0);
const ROOF_THICKNESS: f32 = 1.0;
/// Radial depth of a pillar; its width is a quarter of a roof column's angle.
const PILLAR_DEPTH: f32 = 3.0;
/// Shares of the triangle budget; the stands take the rest.
const FIELD_SHARE: f64 = 0.10;
const ROOF_SHARE: f64 = 0.12;

/// A point above the field, inside the roof's opening, so it lights the teapot and the stands
/// like a floodlight (nothing lies between it and the centre spot).
const LIGHT: Vec3 = Vec3::new(150.0, 320.0, 250.0);

fn build(
    stadium_triangles: u64,
    teapot_triangles: u64,
    size_ratio: f64,
    seed: u64,
) -> Result<Built, String> {
    // The parameter table checks this too; repeated so no caller can make a NaN-sized teapot.
    if !(1e-6..=0.5).contains(&size_ratio) {
        return Err(format!(
            "size_ratio = {size_ratio}: must be between 1e-6 and 0.5"
        ));
    }
    let layout = Layout::for_target(stadium_triangles);
    let mut mesh = Mesh::default();
    mesh.field(layout.field);
    mesh.stands(&layout, seed);
    mesh.roof(&layout);
    debug_assert_eq!(mesh.indices.len() as u64, layout.triangles());
    let stadium = mesh.indices.len();

    let width = (size_ratio * f64::from(STADIUM_WIDTH)) as f32;
    let (teapot, teapot_indices) = teapot_mesh(teapot_triangles);
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(teapot.iter().map(|&p| p * width));
    mesh.indices
        .extend(teapot_indices.iter().map(|t| t.map(|i| i + base)));
    let mut triangle_materials = vec![0; stadium];
    triangle_materials.resize(mesh.indices.len(), 1);
    Ok(Built {
        positions: mesh.positions,
        indices: mesh.indices,
        views: vec![
            NamedView {
                name: "closeup".into(),
                view: closeup_view(width),
            },
            NamedView {
                name: "stadium".into(),
                view: stadium_view(),
            },
        ],
        materials: vec![Material::DEFAULT, Material::GLASS],
        triangle_materials,
    })
}

/// Near the teapot (lengths in teapot widths `w`): in front of it and to the right, at the
/// height of its shoulder, looking slightly down at its middle. The body fills most of the
/// image (the handle and the spout's tip are cut by the edges) and the field, stands, pillars
/// and roof show behind it along the top. Measured: 53 % of primary rays hit the teapot and
/// 45 % the stadium at 2,000 + 2,000 triangles, 54 % and 43 % at the defaults. The eye is
/// 0.8 w from the teapot's axis: for `size_ratio` above about 0.3 it is among the stands,
/// which then hide part of the view.
fn closeup_view(w: f32) -> View {
    View {
        camera: Camera {
            eye: CLOSEUP_EYE * w,
            target: CLOSEUP_TARGET * w,
            up: Vec3::Y,
            fov_y_deg: 45.0,
        },
        light: LIGHT,
    }
}

const CLOSEUP_EYE: Vec3 = Vec3::new(0.37, 0.31, 0.69);
const CLOSEUP_TARGET: Vec3 = Vec3::new(0.0, 0.21, 0.0);

/// The whole stadium from high above its +z side, looking down at about 62°: every stadium
/// vertex projects within 95 % of the image's half-extent; 64 % of primary rays hit at 2,000
/// stadium triangles, 66 % at the default 200,000. The teapot, a fraction of a pixel, is not
/// seen.
fn stadium_view() -> View {
    View {
        camera: Camera {
            eye: Vec3::new(0.0, 800.0, 480.0),
            target: Vec3::new(0.0, 0.0, 60.0),
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: LIGHT,
    }
}

/// How the stadium's budget is spent: a `field.0 × field.1` grid of quads, `rows × columns`
/// steps (10 triangles each), `roof_rows × roof_columns` panels (12) and `roof_columns`
/// pillars (10).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    field: (u32, u32),
    rows: u32,
    columns: u32,
    roof_rows: u32,
    roof_columns: u32,
}

impl Layout {
    /// Field and roof first, each about its share; the stands absorb the rest, with about 20
    /// columns per row, so the total is off by at most `5 · rows` triangles plus rounding.
    fn for_target(target: u64) -> Layout {
        let t = target as f64;
        let quads = (t * FIELD_SHARE / 2.0).max(1.0);
        let fx = (quads * f64::from(FIELD.0 / FIELD.1))
            .sqrt()
            .round()
            .max(1.0);
        let fz = (quads / fx).round().max(1.0);
        let roof_boxes = (t * ROOF_SHARE / 12.0).max(1.0);
        let roof_rows = (roof_boxes / 40.0).sqrt().round().max(1.0);
        let roof_columns = (roof_boxes / (roof_rows + 1.0)).round().max(4.0);
        let mut layout = Layout {
            field: (fx as u32, fz as u32),
            rows: 0,
            columns: 0,
            roof_rows: roof_rows as u32,
            roof_columns: roof_columns as u32,
        };
        let steps = ((t - layout.triangles() as f64) / 10.0).max(1.0);
        let rows = (steps / 20.0).sqrt().round().max(1.0);
        layout.rows = rows as u32;
        layout.columns = (steps / rows).round().max(f64::from(BLOCK_COLUMNS.0)) as u32;
        layout
    }

    fn triangles(&self) -> u64 {
        let field = 2 * u64::from(self.field.0) * u64::from(self.field.1);
        let stands = 10 * u64::from(self.rows) * u64::from(self.columns);
        let roof = u64::from(self.roof_columns) * (12 * u64::from(self.roof_rows) + 10);
        field + stands + roof
    }
}

#[derive(Default)]
struct Mesh {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

/// The point at parameter angle `phi` on the oval `depth` metres outside the stands' inner
/// oval (semi-axes `FIELD + depth`), as (x, z).
fn oval(phi: f32, depth: f32) -> (f32, f32) {
    ((FIELD.0 + depth) * phi.cos(), (FIELD.1 + depth) * phi.sin())
}

impl Mesh {
    /// The field: `nx × nz` quads at y = 0, facing up.
    fn field(&mut self, (nx, nz): (u32, u32)) {
        let first = self.positions.len() as u32;
        for k in 0..=nz {
            let z = FIELD.1 * (2.0 * k as f32 / nz as f32 - 1.0);
            for i in 0..=nx {
                let x = FIELD.0 * (2.0 * i as f32 / nx as f32 - 1.0);
                self.positions.push(Vec3::new(x, 0.0, z));
            }
        }
        let at = |i: u32, k: u32| first + k * (nx + 1) + i;
        for k in 0..nz {
            for i in 0..nx {
                // +z then +x: (z × x) = +y.
                let (a, b) = (at(i, k), at(i + 1, k));
                let (c, d) = (at(i, k + 1), at(i + 1, k + 1));
                self.indices.push([a, c, d]);
                self.indices.push([a, d, b]);
            }
        }
    }

    /// Rows of steps around the oval, in blocks separated by aisles (one column wide), with a
    /// height factor per block.
    fn stands(&mut self, layout: &Layout, seed: u64) {
        let mut rng = rng::stream(seed, STADIUM_STREAM);
        let mut blocks = Vec::new();
        let mut left = layout.columns;
        while left > 0 {
            let span = BLOCK_COLUMNS.1 - BLOCK_COLUMNS.0 + 1;
            let len = BLOCK_COLUMNS.0 + (unit_f32(&mut rng) * span as f32) as u32;
            let len = len.min(BLOCK_COLUMNS.1).min(left);
            let scale = 1.0 + range_f32(&mut rng, -HEIGHT_JITTER, HEIGHT_JITTER);
            blocks.push((len, scale));
            left -= len;
        }
        // Every block is followed by an aisle, including the last (the seam at angle 0).
        let slots = layout.columns + blocks.len() as u32;
        let angle = |slot: u32| TAU * slot as f32 / slots as f32;
        let rows = layout.rows;
        let depth = |r: u32| STAND_DEPTH * r as f32 / rows as f32;
        let (front, back) = STAND_HEIGHTS;
        let height = |r: u32| match rows {
            1 => back,
            _ => front + (back - front) * r as f32 / (rows - 1) as f32,
        };
        let mut slot = 0;
        for (len, scale) in blocks {
            for _ in 0..len {
                for r in 0..rows {
                    let top = height(r) * scale;
                    self.oval_block(
                        (angle(slot), angle(slot + 1)),
                        (depth(r), depth(r + 1)),
                        [(0.0, top), (0.0, top)],
                        false,
                    );
                }
                slot += 1;
            }
            slot += 1;
        }
    }

    /// Slanted panels over the back of the stands, and a pillar under the outer edge at the
    /// start of every column of panels.
    fn roof(&mut self, layout: &Layout) {
        let columns = layout.roof_columns;
        let rows = layout.roof_rows;
        let angle = |c: u32| TAU * c as f32 / columns as f32;
        let inner = ROOF_FROM * STAND_DEPTH;
        let depth = |r: u32| inner + (STAND_DEPTH - inner) * r as f32 / rows as f32;
        let height = |d: f32| {
            let f = (d - inner) / (STAND_DEPTH - inner);
            ROOF_HEIGHTS.0 + (ROOF_HEIGHTS.1 - ROOF_HEIGHTS.0) * f
        };
        let slab = |d: f32| (height(d) - ROOF_THICKNESS, height(d));
        for c in 0..columns {
            for r in 0..rows {
                let (d0, d1) = (depth(r), depth(r + 1));
                self.oval_block(
                    (angle(c), angle(c + 1)),
                    (d0, d1),
                    [slab(d0), slab(d1)],
                    true,
                );
            }
            let width = (angle(c + 1) - angle(c)) * 0.25;
            let under = height(STAND_DEPTH) - ROOF_THICKNESS;
            self.oval_block(
                (angle(c), angle(c) + width),
                (STAND_DEPTH - PILLAR_DEPTH, STAND_DEPTH),
                [(0.0, under), (0.0, under)],
                false,
            );
        }
    }

    /// A six-sided block between parameter angles `phi` and oval depths `depth`, spanning
    /// `heights[0]` (low, high) at the inner depth and `heights[1]` at the outer one: 12
    /// triangles, or 10 without the bottom. Faces wind outwards.
    fn oval_block(
        &mut self,
        phi: (f32, f32),
        depth: (f32, f32),
        heights: [(f32, f32); 2],
        bottom: bool,
    ) {
        let first = self.positions.len() as u32;
        // Corner k: bit 0 picks the angle, bit 1 the depth (outer), bit 2 the top.
        for k in 0..8u32 {
            let a = if k & 1 == 0 { phi.0 } else { phi.1 };
            let outer = k & 2 != 0;
            let (x, z) = oval(a, if outer { depth.1 } else { depth.0 });
            let (lo, hi) = heights[usize::from(outer)];
            self.positions
                .push(Vec3::new(x, if k & 4 == 0 { lo } else { hi }, z));
        }
        let corners = &self.positions[first as usize..];
        let centre = corners.iter().copied().sum::<Vec3>() / 8.0;
        let faces: &[[u32; 4]] = if bottom {
            &[
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 3, 7, 6],
                [0, 2, 6, 4],
                [1, 3, 7, 5],
                [0, 1, 3, 2],
            ]
        } else {
            &[
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 3, 7, 6],
                [0, 2, 6, 4],
                [1, 3, 7, 5],
            ]
        };
        let mut triangles = Vec::with_capacity(2 * faces.len());
        for q in faces {
            let p = q.map(|k| corners[k as usize]);
            let face_centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
            let normal = (p[1] - p[0]).cross(p[2] - p[0]) + (p[2] - p[0]).cross(p[3] - p[0]);
            let q = q.map(|k| first + k);
            if normal.dot(face_centre - centre) >= 0.0 {
                triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
            } else {
                triangles.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
            }
        }
        self.indices.extend(triangles);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_lands_within_5_percent() {
        let mut t = 1_000u64;
        while t <= 40_000_000 {
            let got = Layout::for_target(t).triangles();
            assert!(got.abs_diff(t) * 20 <= t, "{t}: {got}");
            t = t * 9 / 8 + 7;
        }
        for t in 1_000..3_000 {
            let got = Layout::for_target(t).triangles();
            assert!(got.abs_diff(t) * 20 <= t, "{t}: {got}");
        }
    }

    #[test]
    fn stadium_counts_match_the_layout_and_stay_in_bounds() {
        for (t, seed) in [(1_000, 1), (2_000, 2), (50_000, 3)] {
            let layout = Layout::for_target(t);
            let mut mesh = Mesh::default();
            mesh.field(layout.field);
            mesh.stands(&layout, seed);
            mesh.roof(&layout);
            assert_eq!(mesh.indices.len() as u64, layout.triangles(), "{t}");
            for p in &mesh.positions {
                assert!(p.x.abs() <= 500.001 && p.z.abs() <= 400.001, "{p}");
                assert!(p.y >= 0.0 && p.y <= ROOF_HEIGHTS.0, "{p}");
            }
            for tri in &mesh.indices {
                let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
                assert!(
                    (b - a).cross(c - a).length() > 0.0,
                    "zero area at {t}: {tri:?}"
                );
            }
        }
    }

    #[test]
    fn blocks_face_outwards() {
        let mut mesh = Mesh::default();
        mesh.oval_block((0.1, 0.2), (10.0, 20.0), [(0.0, 5.0), (1.0, 9.0)], true);
        let centre = mesh.positions.iter().copied().sum::<Vec3>() / 8.0;
        for t in &mesh.indices {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            assert!((b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) > 0.0);
        }
    }
}
