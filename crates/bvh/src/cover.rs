//! The check that makes duplicated references safe: a tree with spatial splits holds a
//! triangle in several leaves, each leaf's box covering only part of it, and a ray that hits
//! the triangle must still enter one of those leaves. So the union of the boxes of the leaves
//! holding a triangle must contain the whole triangle (a box that contains its whole
//! triangle is the usual case and passes at once).
//!
//! Otherwise the check is exact up to rounding: every face of every one of those boxes that
//! crosses the triangle's box cuts the triangle (Sutherland–Hodgman, in f64) into convex
//! pieces, each inside one cell of the grid the faces make; every cell lies wholly inside or
//! wholly outside each box, so the triangle is covered exactly when each piece's vertex
//! average, a point inside the piece, lies in some box. The containment test allows
//! 1e-6 × the triangle's largest coordinate, far less than any gap a wrong cut would leave
//! but more than the f64 clipping error.

use raybench_geom::{Aabb, Triangle, TriangleMesh};

type P = [f64; 3];

/// Every triangle of `mesh` appears in `pieces` (mesh index and the box of a leaf holding it),
/// every such box overlaps its triangle's box, and each triangle's boxes cover it.
pub(crate) fn check_references(
    mesh: &TriangleMesh,
    mut pieces: Vec<(u32, Aabb)>,
) -> Result<(), String> {
    pieces.sort_by_key(|p| p.0);
    let mut at = 0;
    for id in 0..mesh.len() as u32 {
        let start = at;
        while at < pieces.len() && pieces[at].0 == id {
            at += 1;
        }
        if start == at {
            return Err(format!("mesh triangle {id} is in no leaf"));
        }
        let tri = mesh.triangle(id as usize);
        let boxes: Vec<Aabb> = pieces[start..at].iter().map(|p| p.1).collect();
        let tb = tri.bounds();
        if let Some(b) = boxes.iter().find(|b| !overlaps(b, &tb)) {
            return Err(format!(
                "a leaf holding triangle {id} misses its box: {b:?}"
            ));
        }
        if !covers(&tri, &boxes) {
            return Err(format!(
                "the {} leaves holding triangle {id} do not cover it",
                boxes.len()
            ));
        }
    }
    if at != pieces.len() {
        return Err(format!("prim id {} out of range", pieces[at].0));
    }
    Ok(())
}

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.min[k] <= b.max[k] && b.min[k] <= a.max[k])
}

/// Whether the union of `boxes` contains the triangle.
pub(crate) fn covers(tri: &Triangle, boxes: &[Aabb]) -> bool {
    let tb = tri.bounds();
    if boxes.iter().any(|b| b.contains_box(&tb)) {
        return true;
    }
    let mut planes: Vec<(usize, f64)> = boxes
        .iter()
        .flat_map(|b| (0..3).flat_map(move |k| [(k, b.min[k]), (k, b.max[k])]))
        .filter(|&(k, v)| tb.min[k] < v && v < tb.max[k])
        .map(|(k, v)| (k, v as f64))
        .collect();
    planes.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    planes.dedup();
    let corner = |v: raybench_geom::Vec3| [v.x as f64, v.y as f64, v.z as f64];
    let mut pieces = vec![vec![corner(tri.v0), corner(tri.v1), corner(tri.v2)]];
    for &(axis, at) in &planes {
        pieces = pieces
            .iter()
            .flat_map(|poly| [clip(poly, axis, at, false), clip(poly, axis, at, true)])
            .filter(|poly| !poly.is_empty())
            .collect();
    }
    let scale = (0..3)
        .map(|k| tb.min[k].abs().max(tb.max[k].abs()))
        .fold(0.0f32, f32::max) as f64;
    let tol = 1e-6 * scale;
    pieces.iter().all(|poly| {
        let mut c = [0.0; 3];
        for v in poly {
            (0..3).for_each(|k| c[k] += v[k] / poly.len() as f64);
        }
        boxes
            .iter()
            .any(|b| (0..3).all(|k| b.min[k] as f64 - tol <= c[k] && c[k] <= b.max[k] as f64 + tol))
    })
}

/// The part of the convex polygon `poly` with coordinate `axis` at most (`above` false) or at
/// least (`above` true) `at`.
fn clip(poly: &[P], axis: usize, at: f64, above: bool) -> Vec<P> {
    let inside = |v: &P| if above { v[axis] >= at } else { v[axis] <= at };
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if inside(&a) {
            out.push(a);
        }
        if inside(&a) != inside(&b) && a[axis] != b[axis] {
            let t = (at - a[axis]) / (b[axis] - a[axis]);
            let mut p: P = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]));
            p[axis] = at;
            out.push(p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Vec3;

    fn diagonal() -> Triangle {
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(4.0, 4.0, 0.0),
            Vec3::new(4.0, 4.0, 1.0),
        )
    }

    fn b(lo: [f32; 3], hi: [f32; 3]) -> Aabb {
        Aabb::new(Vec3::from(lo), Vec3::from(hi))
    }

    #[test]
    fn two_halves_cover_and_a_gap_does_not() {
        let t = diagonal();
        let halves = [
            b([0.0, 0.0, 0.0], [1.0, 1.0, 0.25]),
            b([1.0, 1.0, 0.0], [4.0, 4.0, 1.0]),
        ];
        assert!(covers(&t, &halves));
        // A gap between x = 1 and 1.01.
        let gap = [halves[0], b([1.01, 1.0, 0.0], [4.0, 4.0, 1.0])];
        assert!(!covers(&t, &gap));
        // Halves too thin in z: the left one misses the corner at (1, 1, 0.25).
        let thin = [b([0.0, 0.0, 0.0], [1.0, 1.0, 0.2]), halves[1]];
        assert!(!covers(&t, &thin));
    }

    /// Boxes that together contain the triangle's box cover it even when none contains it.
    #[test]
    fn boxes_tiling_the_triangle_box_cover_it() {
        let t = diagonal();
        let tiles: Vec<Aabb> = (0..4)
            .map(|i| b([i as f32, 0.0, 0.0], [i as f32 + 1.0, 4.0, 1.0]))
            .collect();
        assert!(covers(&t, &tiles));
        assert!(!covers(&t, &tiles[1..]));
    }
}
