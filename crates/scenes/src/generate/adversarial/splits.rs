//! Inputs that defeat a builder's split choice: every centroid at one point (`one-centroid`),
//! identical copies (`identical`) and exponentially shrinking triangles (`deep`).

use super::{Built, ONE_CENTROID_STREAM, below, bounds_view, mesh_view, soup_indices};
use crate::rng;
use raybench_geom::Vec3;

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
pub(super) fn one_centroid(n: u64, seed: u64) -> Built {
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

/// `n` copies of one triangle tilted out of every axis plane, each copy with its own three
/// vertices (so nothing can deduplicate them by index).
pub(super) fn identical(n: u64, size: f32) -> Built {
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

/// Triangle `i` (0-based) has vertices `h·(1, 0, 0)`, `h·(2, 0, 1)`, `h·(1.5, 1, 0)` with
/// `h = 2^-i`: x ranges `[2^-i, 2^(1-i)]` touch end to end, every coordinate is an exact power
/// of two times a small integer, and the smallest is `2^-119`, above f32's normal minimum.
pub(super) fn deep(levels: u64) -> Built {
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
    use crate::generate::adversarial::mesh;
    use raybench_geom::TriangleMesh;
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
