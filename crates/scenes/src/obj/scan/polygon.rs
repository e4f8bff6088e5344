//! Whether a polygon is convex: tobj fan-triangulates every polygon, which covers the wrong
//! area when one is not.

use raybench_geom::DVec3;

/// True when some corner turns the other way from the polygon's overall orientation (Newell
/// normal). Collinear corners are allowed; degenerate or non-finite polygons are not judged.
pub(super) fn polygon_is_non_convex(points: &[DVec3]) -> bool {
    let n = points.len();
    let normal = newell_normal(points);
    if !normal.is_finite() || normal.length_squared() == 0.0 {
        return false;
    }
    // The corners were rounded to f32: each is only known to a few f32 ulps of the largest
    // coordinate. A dent smaller than that is rounding, not shape (a finely tessellated disc,
    // 100k corners on a circle, has such dents everywhere and is convex).
    let scale = points
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let position_slack = 4.0 * f64::from(f32::EPSILON) * scale;
    (0..n).any(|i| {
        let a = points[i];
        let b = points[(i + 1) % n];
        let c = points[(i + 2) % n];
        let (e1, e2) = (b - a, c - b);
        let turn = e1.cross(e2).dot(normal);
        // Moving a corner by `position_slack` changes the cross product by about
        // slack × (|e1| + |e2|); the relative 1e-9 covers f64 rounding in the product itself.
        let slack =
            (position_slack * (e1.length() + e2.length())).max(1e-9 * e1.length() * e2.length());
        turn < -slack * normal.length()
    })
}

fn newell_normal(points: &[DVec3]) -> DVec3 {
    let n = points.len();
    (0..n).fold(DVec3::ZERO, |acc, i| {
        let (p, q) = (points[i], points[(i + 1) % n]);
        acc + DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_non_convex_polygons() {
        let square = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)];
        let arrow = [(0., 0.), (2., 0.), (1., 0.5), (2., 2.), (0., 2.)];
        let to3 = |p: &[(f64, f64)]| {
            p.iter()
                .map(|&(x, y)| DVec3::new(x, y, 0.0))
                .collect::<Vec<_>>()
        };
        assert!(!polygon_is_non_convex(&to3(&square)));
        assert!(polygon_is_non_convex(&to3(&arrow)));
        // Orientation does not matter.
        let mut reversed = to3(&arrow);
        reversed.reverse();
        assert!(polygon_is_non_convex(&reversed));
        // A 100k-corner disc rounded to f32 has dents of rounding size only: convex.
        let n = 100_000;
        let disc: Vec<DVec3> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                DVec3::new(f64::from(a.cos() as f32), f64::from(a.sin() as f32), 0.0)
            })
            .collect();
        assert!(!polygon_is_non_convex(&disc));
        // A real dent in a fine polygon is still found: one corner pulled in by 1 %.
        let mut dented = disc;
        dented[500] *= 0.99;
        assert!(polygon_is_non_convex(&dented));
    }
}
