//! Adversarial scenes: the inputs that break naive builders and traversals.
//!
//! Each generator exists for one failure class of docs/validation.md (the bug classes B… and
//! the adversarial checklist's G… and R… items) and says which in its description. They are
//! small, deterministic and exact where exactness is the point: coordinates are chosen so that
//! the property under test holds in f32 after rounding (an exactly shared centroid, triangles
//! exactly on dyadic planes, areas exactly zero), not merely "almost".
//!
//! | scene | docs/validation.md | what it is |
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

mod coplanar;
mod offset;
mod soups;
mod splits;

use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::View;
use coplanar::coplanar;
use offset::offset_sphere;
use rand_core::Rng;
use rand_pcg::Pcg64Mcg;
use raybench_geom::{Aabb, TriangleMesh, Vec3};
use soups::{fan, huge_and_small, zero_area_mixed};
use splits::{deep, identical, one_centroid};

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

/// The mesh of a generator's output, for the tests of the generators.
#[cfg(test)]
fn mesh(b: &Built) -> TriangleMesh {
    TriangleMesh::new(b.positions.clone(), b.indices.clone())
        .unwrap()
        .0
}
