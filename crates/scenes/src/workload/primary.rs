//! Rays made from the view and the bounds alone: camera rays through pixel centres, and
//! random rays in the scene box.

use crate::View;
use crate::rng::{self, RANDOM_RAYS_STREAM};
use raybench_geom::{Aabb, Ray, Vec3};

/// Pinhole camera rays, one through the centre of each pixel of a `W × H` image with
/// `W × H ≈ n` and aspect 4:3, row-major from the top-left pixel, `t` in `(0, inf]`.
///
/// `bounds` is used only when `view` is unusable (eye on the target, up parallel to the view
/// direction, non-finite values, field of view outside (0°, 180°)): then the default view of
/// `bounds` is used, so every ray passes [`Ray::check`]. `n == 0` gives no rays and a 0 × 0 image.
pub fn primary_rays(view: &View, bounds: &Aabb, n: usize) -> (Vec<Ray>, u32, u32) {
    let view = if view.is_usable() {
        *view
    } else {
        View::of_bounds(bounds)
    };
    let (width, height) = image_size(n);
    (
        primary_rays_sized(&view, bounds, width, height),
        width,
        height,
    )
}

/// The camera rays of [`primary_rays`] for an exact `width × height` image (the same view,
/// pixel centres and order), for pictures drawn at another size than the timed workload's.
/// Either side 0 gives no rays.
pub fn primary_rays_sized(view: &View, bounds: &Aabb, width: u32, height: u32) -> Vec<Ray> {
    let view = if view.is_usable() {
        *view
    } else {
        View::of_bounds(bounds)
    };
    let frame = CameraFrame::new(&view, width, height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| frame.ray(x, y))
        .collect()
}

/// The 4:3 image with about `n` pixels: `W = round(sqrt(4n/3))`, `H = round(n / W)`.
fn image_size(n: usize) -> (u32, u32) {
    if n == 0 {
        return (0, 0);
    }
    let n = n as f64;
    let width = (n * 4.0 / 3.0).sqrt().round().max(1.0);
    let height = (n / width).round().max(1.0);
    (
        width.min(f64::from(u32::MAX)) as u32,
        height.min(f64::from(u32::MAX)) as u32,
    )
}

/// The camera's orthonormal frame, scaled so that image-plane offsets are in units of the
/// distance to the image plane.
struct CameraFrame {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: f32,
    height: f32,
}

impl CameraFrame {
    fn new(view: &View, width: u32, height: u32) -> CameraFrame {
        let c = &view.camera;
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let half_height = (c.fov_y_deg.to_radians() * 0.5).tan();
        // Square pixels: the horizontal half-extent follows the pixel grid's real aspect.
        let half_width = half_height * width.max(1) as f32 / height.max(1) as f32;
        CameraFrame {
            eye: c.eye,
            forward,
            right: right * half_width,
            up: up * half_height,
            width: width.max(1) as f32,
            height: height.max(1) as f32,
        }
    }

    fn ray(&self, x: u32, y: u32) -> Ray {
        // Pixel centres in [-1, 1]. A division, not a multiplication by 1/W, so the middle
        // pixel of an odd-sized image maps to exactly 0 (W * fl(1/W) need not be 1).
        let sx = (2 * u64::from(x) + 1) as f32 / self.width - 1.0;
        let sy = 1.0 - (2 * u64::from(y) + 1) as f32 / self.height;
        Ray::infinite(self.eye, self.forward + self.right * sx + self.up * sy)
    }
}

/// `n` rays with origins uniform in `bounds.enlarged(0.05)` and directions uniform on the unit
/// sphere. An empty or non-finite box is replaced by `[-1, 1]³`.
pub fn random_rays(bounds: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let usable = !bounds.is_empty() && bounds.min.is_finite() && bounds.max.is_finite();
    let region = if usable {
        bounds.enlarged(0.05)
    } else {
        Aabb::new(Vec3::splat(-1.0), Vec3::ONE)
    };
    let mut rng = rng::stream(seed, RANDOM_RAYS_STREAM);
    (0..n)
        .map(|_| {
            let origin = Vec3::new(
                rng::range_f32(&mut rng, region.min.x, region.max.x),
                rng::range_f32(&mut rng, region.min.y, region.max.y),
                rng::range_f32(&mut rng, region.min.z, region.max.z),
            );
            Ray::infinite(origin, rng::uniform_sphere(&mut rng))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_is_about_n_pixels_at_four_to_three() {
        for n in [1usize, 2, 100, 20_000, 100_000, 1_000_003] {
            let (w, h) = image_size(n);
            let pixels = (w * h) as f64;
            assert!(
                (pixels - n as f64).abs() <= 0.5 * w.max(h) as f64 + 1.0,
                "{n}: {w}x{h}"
            );
            if n >= 20_000 {
                assert!(
                    (w as f64 / h as f64 - 4.0 / 3.0).abs() < 0.05,
                    "{n}: {w}x{h}"
                );
            }
        }
        assert_eq!(image_size(0), (0, 0));
    }

    #[test]
    fn sized_rays_match_the_workload_rays_at_the_same_size() {
        let bounds = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let view = View::of_bounds(&bounds);
        let (rays, w, h) = primary_rays(&view, &bounds, 20_000);
        assert_eq!(primary_rays_sized(&view, &bounds, w, h), rays);
        let big = primary_rays_sized(&view, &bounds, 640, 480);
        assert_eq!(big.len(), 640 * 480);
        assert!(big.iter().all(|r| r.check().is_ok()));
        assert!(primary_rays_sized(&view, &bounds, 0, 480).is_empty());
    }
}
