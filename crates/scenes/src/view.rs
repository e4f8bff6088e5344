use raybench_geom::{Aabb, Vec3};
use serde::{Deserialize, Serialize};

/// Where primary rays come from and where shadow rays go.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct View {
    pub camera: Camera,
    /// A point light; shadow rays end just before it.
    pub light: Vec3,
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
}

/// Direction from the centre of a box towards the default eye: oblique, so no face of an
/// axis-aligned model is seen edge-on.
const OBLIQUE_EYE_DIR: Vec3 = Vec3::new(0.6, 0.5, 1.0);
/// Eye distance in box diagonals: at 1.2 the bounding sphere (radius 0.5 diagonal) subtends
/// asin(0.5 / 1.2) = 24.6°, just inside the 25° half-angle of the 50° field of view.
const EYE_DISTANCE_IN_DIAGONALS: f32 = 1.2;
const LIGHT_OFFSET_IN_DIAGONALS: Vec3 = Vec3::new(0.5, 1.5, 0.8);
pub(crate) const DEFAULT_FOV_Y_DEG: f32 = 50.0;

impl View {
    /// The default view of a box: look at its centre from outside, along a fixed oblique
    /// direction, with the light above and beside the camera. Works for flat and point boxes
    /// (a floor keeps the eye away from the target) and, for an empty box, looks at the origin.
    pub fn of_bounds(bounds: &Aabb) -> View {
        let (center, diagonal) = if bounds.is_empty() || !bounds.min.is_finite() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.diagonal())
        };
        let scale = usable_scale(center, diagonal);
        View {
            camera: Camera {
                eye: center + OBLIQUE_EYE_DIR.normalize() * (EYE_DISTANCE_IN_DIAGONALS * scale),
                target: center,
                up: Vec3::Y,
                fov_y_deg: DEFAULT_FOV_Y_DEG,
            },
            light: center + LIGHT_OFFSET_IN_DIAGONALS * scale,
        }
    }

    /// True when primary rays can be made from this view: finite, eye away from the target,
    /// an up vector not parallel to the view direction, and a field of view in (0°, 180°).
    pub fn is_usable(&self) -> bool {
        let c = &self.camera;
        let forward = c.target - c.eye;
        let finite = c.eye.is_finite() && c.target.is_finite() && c.up.is_finite();
        let fov_ok = c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0;
        finite
            && fov_ok
            && forward.length_squared() > 0.0
            && forward.cross(c.up).length_squared() > 0.0
            && self.light.is_finite()
    }
}

/// The size used to place the eye: the diagonal, or for a point-like box a small length that is
/// still representable next to the centre (`|center| * 2^-10` keeps ~13 bits of separation).
fn usable_scale(center: Vec3, diagonal: f32) -> f32 {
    let floor = (center.abs().max_element() * (1.0 / 1024.0)).max(1e-3);
    diagonal.max(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_of_point_box_is_usable() {
        let point = Aabb::new(Vec3::splat(1e6), Vec3::splat(1e6));
        assert!(View::of_bounds(&point).is_usable());
        assert!(View::of_bounds(&Aabb::EMPTY).is_usable());
    }

    #[test]
    fn eye_is_outside_the_box() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 3.0));
        let v = View::of_bounds(&b);
        assert!(!b.contains(v.camera.eye));
        assert_eq!(v.camera.target, b.center());
    }
}
