//! `offset`: a watertight UV sphere far from the origin, for f32 precision there.

use super::Built;
use crate::{Camera, NamedView, View};
use raybench_geom::{DVec3, Vec3};

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
pub(super) fn offset_sphere(target: u64, offset: f64, radius: f64) -> Built {
    let (stacks, slices) = sphere_grid(target);
    let center = DVec3::ONE.normalize() * offset;
    let (positions, indices) =
        crate::generate::basic::uv_sphere(stacks, slices, |p| (center + p * radius).as_vec3());
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
    // From the centre, looking out through the sphere (docs/validation.md, G15: every ray must hit,
    // no cracks).
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
