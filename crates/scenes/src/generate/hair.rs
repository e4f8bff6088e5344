//! `hair`: long, thin, heavily overlapping triangles in the unit box.
//!
//! Each triangle is a needle: a root edge 0.001–0.005 wide and a tip a long way off in a
//! random direction, so its bounding box is huge for its area and crosses the boxes of a large
//! fraction of all the others. Object partitioning (a plain BVH) cannot separate them; this is
//! the case spatial splits exist for.

use super::{Built, GeneratorInfo, Kind, ParamInfo, triangles};
use crate::rng;
use crate::{Camera, View};
use raybench_geom::{Aabb, Ray, Vec3};
use std::f32::consts::TAU;

const HAIR_STREAM: u64 = u64::from_be_bytes(*b"gen-hair");

/// Width of the root edge.
const HAIR_WIDTH: (f32, f32) = (0.001, 0.005);
/// Strand length relative to the `length` parameter, before shortening to fit the box.
const HAIR_LENGTH_SPREAD: (f32, f32) = (0.6, 1.4);
/// Distance every vertex keeps from the faces of the unit box: more than half the widest root.
const HAIR_MARGIN: f32 = 0.003;

pub(super) const HAIR: GeneratorInfo = GeneratorInfo {
    name: "hair",
    description: "needle triangles in the unit cube [0,1]³: random direction, length 0.6–1.4 × \
                  `length` (shortened to fit), root 0.001–0.005 wide; long, thin and crossing \
                  each other (the case for spatial splits)",
    params: &[
        triangles("number of strands, one triangle each", 50_000.0),
        ParamInfo {
            key: "length",
            meaning: "mean strand length as a fraction of the box side",
            kind: Kind::Real {
                min: 0.02,
                max: 1.0,
            },
            default: 0.5,
        },
    ],
    uses_seed: true,
    build: |p, seed| {
        let (positions, indices) = hair(p.count("triangles"), p.f32("length"), seed);
        Ok(Built::new(positions, indices, hair_view()))
    },
};

fn hair(n: u64, mean_length: f32, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut rng = rng::stream(seed, HAIR_STREAM);
    let room = 1.0 - 2.0 * HAIR_MARGIN;
    let mut positions = Vec::with_capacity(3 * n as usize);
    for _ in 0..n {
        let dir = rng::uniform_sphere(&mut rng);
        let wanted =
            mean_length * rng::range_f32(&mut rng, HAIR_LENGTH_SPREAD.0, HAIR_LENGTH_SPREAD.1);
        // Longest strand along `dir` that fits: |dir_i| · length <= room on every axis.
        let length = wanted.min(0.999 * room / dir.abs().max_element());
        let reach = dir.abs() * (0.5 * length);
        let center = Vec3::new(
            rng::range_f32(&mut rng, HAIR_MARGIN + reach.x, 1.0 - HAIR_MARGIN - reach.x),
            rng::range_f32(&mut rng, HAIR_MARGIN + reach.y, 1.0 - HAIR_MARGIN - reach.y),
            rng::range_f32(&mut rng, HAIR_MARGIN + reach.z, 1.0 - HAIR_MARGIN - reach.z),
        );
        let (e1, e2) = rng::orthonormal_basis(dir);
        let spin = TAU * rng::unit_f32(&mut rng);
        let half_width = 0.5 * rng::range_f32(&mut rng, HAIR_WIDTH.0, HAIR_WIDTH.1);
        let side = (e1 * spin.cos() + e2 * spin.sin()) * half_width;
        let root = center - dir * (0.5 * length);
        positions.extend([root - side, root + side, center + dir * (0.5 * length)]);
    }
    let indices = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    (positions, indices)
}

/// Looking at the cube from in front, a little to the right and above, close enough that the
/// whole 4:3 image lies inside the cube's outline (shrunk by 2 %), so every primary ray crosses
/// the hair volume.
fn hair_view() -> View {
    let center = Vec3::splat(0.5);
    let back = Vec3::new(0.35, 0.3, 1.0).normalize();
    let fov_y_deg = 50.0;
    let inner = Aabb::new(Vec3::splat(0.02), Vec3::splat(0.98));
    let covered = |distance: f32| {
        let eye = center + back * distance;
        let forward = -back;
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let tan_y = (f32::to_radians(fov_y_deg) * 0.5).tan();
        let tan_x = tan_y * 4.0 / 3.0;
        [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .into_iter()
            .all(|(sx, sy)| {
                let dir = forward + right * (sx * tan_x) + up * (sy * tan_y);
                inner.intersect(&Ray::infinite(eye, dir)).is_some()
            })
    };
    // The eye leaves the cube at distance ≤ √3/2 from the centre; the image and the cube's
    // outline are convex, so checking the corner rays is enough, and coverage only shrinks
    // as the eye moves back.
    let (mut lo, mut hi) = (0.9f32, 4.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if covered(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    View {
        camera: Camera {
            eye: center + back * lo,
            target: center,
            up: Vec3::Y,
            fov_y_deg,
        },
        light: center + Vec3::new(0.6, 1.5, 1.2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strands_stay_in_the_box_and_the_view_is_outside() {
        let (p, _) = hair(5000, 1.0, 4);
        assert!(
            p.iter()
                .all(|&v| v.min_element() > 0.0 && v.max_element() < 1.0)
        );
        let view = hair_view();
        assert!(!Aabb::new(Vec3::ZERO, Vec3::ONE).contains(view.camera.eye));
        assert!(view.camera.eye.z > 1.2, "{}", view.camera.eye);
    }
}
