//! Adversarial scenes: the inputs that break naive builders and traversals.
//!
//! Each generator exists for one failure class of `reference/reliability.md` (bug classes B*,
//! geometry cases G*) and says which in its description. They are small, deterministic and exact
//! where exactness is the point: coordinates are chosen so that the property under test holds
//! in f32 after rounding (an exactly shared centroid, triangles exactly on dyadic planes, areas
//! exactly zero), not merely "almost".
//!
//! | scene | for | what it is |
//! |---|---|---|
//! | `one-centroid` | B5, G8 | triangles of many sizes and orientations, centroid and box centre exactly the origin |
//! | `coplanar` | B4, G9, G11, G16, R9 | axis-aligned grids on dyadic planes, exact and overlapping duplicates |
//! | `offset` | R15, G15, B21 | a watertight sphere far from the origin |
//! | `zero-area-mixed` | B7, G3 | a soup with points, lines, repeated vertices and collinear triangles mixed in |
//! | `single-triangle` | B18, G2 | one triangle (flat bounds) |
//! | `empty` | B18, G1 | no triangles at all |
//! | `identical` | B6, G7, G10 | N copies of one triangle (`size=0`: one point) |
//! | `fan` | B15, G13 | thin triangles all sharing one vertex |
//! | `huge-and-small` | G12, B11 | one huge triangle through a soup of small ones |
//! | `deep` | B17, G14 | exponentially shrinking triangles that force deep trees |

use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::rng;
use crate::{Camera, NamedView, View};
use rand_core::Rng;
use rand_pcg::Pcg64Mcg;
use raybench_geom::{Aabb, DVec3, TriangleMesh, Vec3};

/// Stream tags, one per seeded generator (see `rng.rs`): adding one never shifts another.
const ONE_CENTROID_STREAM: u64 = u64::from_be_bytes(*b"gen-1cen");
const ZERO_AREA_STREAM: u64 = u64::from_be_bytes(*b"gen-zero");
const FAN_STREAM: u64 = u64::from_be_bytes(*b"gen-fan_");
const HUGE_STREAM: u64 = u64::from_be_bytes(*b"gen-huge");

pub(super) const ONE_CENTROID: GeneratorInfo = GeneratorInfo {
    name: "one-centroid",
    description: "triangles of many sizes and orientations whose vertex centroid and bounding-box centre are both exactly the origin in f32 (degenerate SAH / centroid split; B5, G8)",
    params: &[triangles("number of triangles", 1_000.0)],
    uses_seed: true,
    build: |p, seed| Ok(one_centroid(p.count("triangles"), seed)),
};

pub(super) const COPLANAR: GeneratorInfo = GeneratorInfo {
    name: "coplanar",
    description: "axis-aligned triangle grids on the planes z = -1, 0, 1, x = 0.5, y = 0.25 with dyadic coordinates (exactly on split planes, grid lines and octree faces), plus exact and half-shifted duplicates (G9, G11, G16); view=grazing puts the eye in two of the planes",
    params: &[triangles("number of triangles", 10_000.0)],
    uses_seed: false,
    build: |p, _| Ok(coplanar(p.count("triangles"))),
};

pub(super) const OFFSET: GeneratorInfo = GeneratorInfo {
    name: "offset",
    description: "watertight UV sphere whose centre is `offset` from the origin along (1,1,1), vertices rounded once from f64 (far-from-origin precision; R15, G15); view=inside looks out from the centre",
    params: &[
        triangles(
            "approximate triangle count, 2·slices·(stacks-1) for the nearest grid",
            20_000.0,
        ),
        ParamInfo {
            key: "offset",
            meaning: "distance of the sphere's centre from the origin",
            kind: Kind::Real { min: 0.0, max: 1e7 },
            default: 1e5,
        },
        ParamInfo {
            key: "radius",
            meaning: "sphere radius (at offset 1e7, where f32 spacing is 0.5, a radius-1 sphere is a few ulps across: use about 1000 there)",
            kind: Kind::Real {
                min: 1e-3,
                max: 1e6,
            },
            default: 1.0,
        },
    ],
    uses_seed: false,
    build: |p, _| {
        Ok(offset_sphere(
            p.count("triangles"),
            p.get("offset"),
            p.get("radius"),
        ))
    },
};

pub(super) const ZERO_AREA_MIXED: GeneratorInfo = GeneratorInfo {
    name: "zero-area-mixed",
    description: "random triangles in the unit cube with zero-area ones mixed in at random places: three equal points, tobj point [a,a,a] and line [a,b,b] faces, a repeated position, exactly collinear (B7, G3)",
    params: &[
        triangles("number of triangles, degenerate ones included", 10_000.0),
        ParamInfo {
            key: "degenerate_fraction",
            meaning: "fraction of the triangles that have zero area (rounded to a whole count)",
            kind: Kind::Real { min: 0.0, max: 1.0 },
            default: 0.2,
        },
    ],
    uses_seed: true,
    build: |p, seed| {
        Ok(zero_area_mixed(
            p.count("triangles"),
            p.get("degenerate_fraction"),
            seed,
        ))
    },
};

pub(super) const SINGLE_TRIANGLE: GeneratorInfo = GeneratorInfo {
    name: "single-triangle",
    description: "one triangle in the plane z = 0 (flat bounds; B18, G2)",
    params: &[ParamInfo {
        key: "size",
        meaning: "longest edge of the triangle, about",
        kind: Kind::Real {
            min: 1e-6,
            max: 1e6,
        },
        default: 1.0,
    }],
    uses_seed: false,
    build: |p, _| Ok(single_triangle(p.f32("size"))),
};

pub(super) const EMPTY: GeneratorInfo = GeneratorInfo {
    name: "empty",
    description: "no triangles at all: every structure must build and miss (B18, G1); the view looks at the origin",
    params: &[],
    uses_seed: false,
    build: |_, _| {
        Ok(Built::new(
            Vec::new(),
            Vec::new(),
            View::of_bounds(&Aabb::EMPTY),
        ))
    },
};

// The four below are written and tested here but not yet in the table of `mod.rs`; the lead
// registers them (then the `allow` can go).

pub(super) const IDENTICAL: GeneratorInfo = GeneratorInfo {
    name: "identical",
    description: "N copies of one triangle, each with its own vertices (same-centroid leaf overflow at 256, 65 536; B6, G7); size=0 makes every vertex the same point (G10)",
    params: &[
        triangles("number of copies", 1_000.0),
        ParamInfo {
            key: "size",
            meaning: "edge length of the triangle (0: a single point, zero area)",
            kind: Kind::Real { min: 0.0, max: 1e6 },
            default: 1.0,
        },
    ],
    uses_seed: false,
    build: |p, _| Ok(identical(p.count("triangles"), p.f32("size"))),
};

pub(super) const FAN: GeneratorInfo = GeneratorInfo {
    name: "fan",
    description: "thin triangles from one shared vertex at the origin out to random directions at distance 1 (octree/grid subdivision around one point; B15, G13)",
    params: &[triangles("number of triangles", 10_000.0)],
    uses_seed: true,
    build: |p, seed| Ok(fan(p.count("triangles"), seed)),
};

pub(super) const HUGE_AND_SMALL: GeneratorInfo = GeneratorInfo {
    name: "huge-and-small",
    description: "one huge oblique triangle cutting through a soup of small triangles in the unit cube (reference duplication, hits beyond the current cell; G12, B11)",
    params: &[
        triangles("number of triangles, the huge one included", 10_000.0),
        ParamInfo {
            key: "size",
            meaning: "extent of the huge triangle in unit-cube widths",
            kind: Kind::Real { min: 1.0, max: 1e6 },
            default: 100.0,
        },
    ],
    uses_seed: true,
    build: |p, seed| Ok(huge_and_small(p.count("triangles"), p.f32("size"), seed)),
};

pub(super) const DEEP: GeneratorInfo = GeneratorInfo {
    name: "deep",
    description: "triangle i spans x in [2^-i, 2^(1-i)]: binned SAH and spatial-median builders peel one triangle per level, forcing depth ≈ levels (stack overflow; B17, G14)",
    params: &[ParamInfo {
        key: "levels",
        meaning: "number of triangles, each half the size of the previous (120 keeps every coordinate a normal f32)",
        kind: Kind::Count { min: 1, max: 120 },
        default: 100.0,
    }],
    uses_seed: false,
    build: |p, _| Ok(deep(p.count("levels"))),
};

/// Separate triangles: triangle `i` uses vertices `3i, 3i+1, 3i+2`.
fn soup_indices(n: usize) -> Vec<[u32; 3]> {
    (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect()
}

/// The default view of everything in `positions` (an empty list looks at the origin).
fn bounds_view(positions: &[Vec3]) -> View {
    View::of_bounds(&Aabb::from_points(positions.iter().copied()))
}

/// Uniform in `0..n` (`n > 0`), by the multiply-shift map; the bias is below 2^-32 · n.
fn below(rng: &mut Pcg64Mcg, n: u32) -> u32 {
    ((u64::from(rng.next_u32()) * u64::from(n)) >> 32) as u32
}

// ---------------------------------------------------------------------------------------------
// one-centroid

/// The six orders of `(+1, -1, 0)`: one per axis gives the three vertices' signs on that axis.
const SIGN_ORDERS: [[f32; 3]; 6] = [
    [1.0, -1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, 1.0],
];

/// Sizes span 2^-6 .. 1: six octaves, so SAH costs differ while the centroids do not.
const ONE_CENTROID_OCTAVES: f32 = 6.0;

/// `n` triangles whose three vertices have, on each axis `k`, the coordinates `+s_k`, `-s_k` and
/// `0` in an order drawn per axis and triangle, with `s_k` drawn per axis and triangle.
///
/// Why this shape and not "random triangles recentred in f64": on every axis the three
/// coordinates are `s`, `-s` and `0`, so their f32 sum is exactly 0 in any evaluation order
/// (`s + -s` and `s + 0` are exact) and `min/2 + max/2` is exactly 0 too. Both definitions of a
/// triangle's "centroid" builders use (vertex mean; bounding-box centre, as in pbrt and
/// Embree) are therefore exactly the origin, not within an ulp of it; recentring arbitrary
/// triangles in f64 and rounding leaves them up to an ulp apart. Orientations still vary
/// continuously with the three scales, and a triangle is degenerate only when the 0 sits at the
/// same vertex on all three axes (all columns parallel), which is redrawn. Every triangle
/// contains the origin (a triangle contains its centroid), so rays through the origin hit all
/// of them at the same `t`.
fn one_centroid(n: u64, seed: u64) -> Built {
    let mut rng = rng::stream(seed, ONE_CENTROID_STREAM);
    let mut positions = Vec::with_capacity(3 * n as usize);
    for _ in 0..n {
        let orders = loop {
            let o = [0; 3].map(|_| SIGN_ORDERS[below(&mut rng, 6) as usize]);
            let zero_at = o.map(|signs| signs.iter().position(|&s| s == 0.0));
            if !(zero_at[0] == zero_at[1] && zero_at[1] == zero_at[2]) {
                break o;
            }
        };
        let size = rng::range_f32(&mut rng, -ONE_CENTROID_OCTAVES, 0.0).exp2();
        let scale = [0; 3].map(|_| size * rng::range_f32(&mut rng, 0.15, 1.0));
        let [xs, ys, zs] = orders;
        positions.extend((0..3).map(|v| Vec3::new(xs[v], ys[v], zs[v]) * Vec3::from_array(scale)));
    }
    let view = bounds_view(&positions);
    Built::new(positions, soup_indices(n as usize), view)
}

// ---------------------------------------------------------------------------------------------
// coplanar

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
fn coplanar(n: u64) -> Built {
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

/// The eye lies in the planes z = 0 and y = 0.25, outside the triangles (x = -3), looking along
/// +x: every ray meets the triangles of those two planes only at its origin, t = 0, so none of
/// them may be hit (R9 grazing rays; a traversal that rounds the plane distance to a tiny
/// positive t reports a false hit).
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

// ---------------------------------------------------------------------------------------------
// offset

/// Stacks `s` and slices `m` for about `target` triangles (`2m(s-1)` of them) with `m ≈ 2s`.
fn sphere_grid(target: u64) -> (u32, u32) {
    let stacks = ((target as f64 / 4.0).sqrt().round() as u32).max(2);
    let slices = ((target as f64 / (2.0 * (stacks - 1) as f64)).round() as u32).max(3);
    (stacks, slices)
}

/// A UV sphere of `stacks × slices` around `center` (f64), every vertex rounded to f32 once
/// from its exact f64 position. Rings are shared and the seam wraps by index, so every edge
/// belongs to exactly two triangles (watertight as a mesh; at large offsets f32 rounding can
/// still merge neighbouring vertices, which makes zero-area triangles, not holes).
/// Counter-clockwise seen from outside.
fn offset_sphere(target: u64, offset: f64, radius: f64) -> Built {
    let (stacks, slices) = sphere_grid(target);
    let center = DVec3::ONE.normalize() * offset;
    let (positions, indices) =
        super::basic::uv_sphere(stacks, slices, |p| (center + p * radius).as_vec3());
    // From outside: at r / sin 20° the sphere subtends 40° of the 50° field of view. Placed in
    // f64 and rounded once, so at 1e7 (f32 spacing 0.5–1) the eye is as near the intended spot
    // as f32 allows; the default box-based view would back off to |centre|/1024 there.
    let back = DVec3::new(0.3, 0.4, 1.0).normalize();
    let outside = View {
        camera: Camera {
            eye: (center + back * (radius / 20f64.to_radians().sin())).as_vec3(),
            target: center.as_vec3(),
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: (center + DVec3::new(2.0, 4.0, 3.0) * radius).as_vec3(),
    };
    // From the centre, looking out through the sphere (G15: every ray must hit, no cracks).
    let inside = View {
        camera: Camera {
            eye: center.as_vec3(),
            target: (center + DVec3::new(0.2, 0.3, 1.0) * radius).as_vec3(),
            up: Vec3::Y,
            fov_y_deg: 90.0,
        },
        light: center.as_vec3(),
    };
    let mut built = Built::new(positions, indices, outside);
    built.views.push(NamedView {
        name: "inside".into(),
        view: inside,
    });
    built
}

// ---------------------------------------------------------------------------------------------
// zero-area-mixed

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
fn zero_area_mixed(n: u64, fraction: f64, seed: u64) -> Built {
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

// ---------------------------------------------------------------------------------------------
// single-triangle, identical

/// One scalene triangle in z = 0, about `size` across, around the origin.
fn single_triangle(size: f32) -> Built {
    let positions = vec![
        Vec3::new(-0.5, -0.375, 0.0) * size,
        Vec3::new(0.5, -0.375, 0.0) * size,
        Vec3::new(0.125, 0.5, 0.0) * size,
    ];
    let indices = vec![[0, 1, 2]];
    Built::new(
        positions.clone(),
        indices.clone(),
        mesh_view(positions, indices),
    )
}

/// The tight default view of a small mesh (every vertex fitted, see `View::of_mesh`).
fn mesh_view(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> View {
    match TriangleMesh::new(positions, indices) {
        Ok((mesh, _)) => View::of_mesh(&mesh),
        Err(_) => View::of_bounds(&Aabb::EMPTY),
    }
}

/// `n` copies of one triangle tilted out of every axis plane, each copy with its own three
/// vertices (so nothing can deduplicate them by index).
fn identical(n: u64, size: f32) -> Built {
    let tri = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.25, 0.125),
        Vec3::new(0.25, 1.0, 0.5),
    ]
    .map(|v| v * size);
    let positions: Vec<Vec3> = (0..n).flat_map(|_| tri).collect();
    let view = mesh_view(tri.to_vec(), vec![[0, 1, 2]]);
    Built::new(positions, soup_indices(n as usize), view)
}

// ---------------------------------------------------------------------------------------------
// fan, huge-and-small, deep

/// Angular width of a fan blade at its far end, in radians.
const FAN_BLADE: f32 = 0.02;

/// `n` triangles `[0, a_i, b_i]` sharing vertex 0 at the origin: `a_i` uniform on the unit
/// sphere, `b_i` a step of [`FAN_BLADE`] from it in a random tangent direction.
fn fan(n: u64, seed: u64) -> Built {
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
fn huge_and_small(n: u64, size: f32, seed: u64) -> Built {
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

/// Triangle `i` (0-based) has vertices `h·(1, 0, 0)`, `h·(2, 0, 1)`, `h·(1.5, 1, 0)` with
/// `h = 2^-i`: x ranges `[2^-i, 2^(1-i)]` touch end to end, every coordinate is an exact power
/// of two times a small integer, and the smallest is `2^-119`, above f32's normal minimum.
fn deep(levels: u64) -> Built {
    let positions: Vec<Vec3> = (0..levels as i32)
        .flat_map(|i| {
            let h = 2f32.powi(-i);
            [
                Vec3::new(1.0, 0.0, 0.0) * h,
                Vec3::new(2.0, 0.0, 1.0) * h,
                Vec3::new(1.5, 1.0, 0.0) * h,
            ]
        })
        .collect();
    let view = bounds_view(&positions);
    Built::new(positions, soup_indices(levels as usize), view)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(b: &Built) -> TriangleMesh {
        TriangleMesh::new(b.positions.clone(), b.indices.clone())
            .unwrap()
            .0
    }

    #[test]
    fn grid_shape_fits_the_box_with_power_of_two_quads() {
        for count in [1, 2, 3, 7, 100, 1_601, 2_000_000] {
            let (cols, h) = grid_shape(count);
            assert!(2 * u64::from(cols) * u64::from(cols) >= count, "{count}");
            assert!(cols as f32 * h <= 2.0 && cols as f32 * h > 1.0, "{count}");
            assert_eq!(h, 2f32.powi(h.log2() as i32), "{count}: {h}");
        }
    }

    #[test]
    fn sphere_grid_tracks_the_target() {
        for target in [1u64, 100, 1_000, 20_000, 1_000_000] {
            let (s, m) = sphere_grid(target);
            let made = 2 * u64::from(m) * u64::from(s - 1);
            if target >= 100 {
                assert!(made.abs_diff(target) * 20 <= target, "{target}: {made}");
            }
            assert!(s >= 2 && m >= 3);
        }
    }

    #[test]
    fn identical_copies_and_the_point_scene() {
        let m = mesh(&identical(300, 1.0));
        assert_eq!(m.len(), 300);
        let first = m.triangle(0);
        assert!(m.triangles().all(|t| t == first) && first.area() > 0.0);
        let point = identical(10, 0.0);
        let (m, removed) = TriangleMesh::new(point.positions, point.indices).unwrap();
        assert_eq!((m.len(), removed.degenerate_kept), (10, 10));
        assert!(point.views[0].view.is_usable());
    }

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

    #[test]
    fn deep_triangles_halve_and_stay_normal() {
        let b = deep(120);
        let m = mesh(&b);
        assert_eq!(m.len(), 120);
        for (i, t) in m.triangles().enumerate() {
            let h = 2f64.powi(-(i as i32));
            assert_eq!(f64::from(t.v0.x), h);
            assert!(t.area() > 0.0, "{i}");
            let coords = [t.v0, t.v1, t.v2].map(|v| v.to_array());
            assert!(
                coords.iter().flatten().all(|c| *c == 0.0 || c.is_normal()),
                "{i}"
            );
        }
    }
}
