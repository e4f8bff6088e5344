//! Seeded ray sets for conformance cases.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::{Aabb, Ray, TriangleMesh, Vec3};

/// The generator every testkit case uses (portable, documented algorithm; never `StdRng`).
pub fn seeded_rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

/// Uniform in [0, 1): the top 24 bits of one draw, scaled exactly.
pub(crate) fn unit_f32(rng: &mut impl Rng) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Uniform on the unit sphere.
pub(crate) fn on_sphere(rng: &mut impl Rng) -> Vec3 {
    let z = 2.0 * unit_f32(rng) - 1.0;
    let phi = std::f32::consts::TAU * unit_f32(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` rays with origins uniform in `bounds` and directions uniform on the sphere.
pub fn random_rays_in(bounds: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = seeded_rng(seed);
    let e = bounds.extent();
    (0..n)
        .map(|_| {
            let o = bounds.min
                + Vec3::new(unit_f32(&mut rng), unit_f32(&mut rng), unit_f32(&mut rng)) * e;
            Ray::infinite(o, on_sphere(&mut rng))
        })
        .collect()
}

/// Rays from random points outside the mesh aimed at triangle centroids (every one should hit
/// something), for up to `n` triangles.
pub fn centroid_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = seeded_rng(seed);
    let b = mesh.bounds();
    let reach = b.diagonal().max(1.0);
    let step = (mesh.len() / n.max(1)).max(1);
    mesh.triangles()
        .step_by(step)
        .take(n)
        .map(|t| {
            let c = t.centroid();
            let o = c + on_sphere(&mut rng) * reach;
            Ray::infinite(o, c - o)
        })
        .collect()
}

/// A direction in the cube [-0.5, 0.5]³ from three full 32-bit draws (not normalised; the zero
/// vector is possible in principle).
pub(crate) fn centred_direction(rng: &mut impl Rng) -> Vec3 {
    Vec3::new(
        rng.next_u32() as f32,
        rng.next_u32() as f32,
        rng.next_u32() as f32,
    ) / u32::MAX as f32
        - 0.5
}

/// Rays [`Ray::check`] refuses (a NaN origin, a NaN direction, a zero direction, a NaN
/// interval): never sent to Embree, and every structure must still answer them, with a miss,
/// in bounded time.
pub fn refused_rays() -> [Ray; 4] {
    [
        Ray::infinite(Vec3::new(f32::NAN, 1.0, 1.0), Vec3::X),
        Ray::infinite(Vec3::splat(1.0), Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::infinite(Vec3::splat(1.0), Vec3::ZERO),
        Ray::new(Vec3::splat(1.0), Vec3::X, f32::NAN, f32::NAN),
    ]
}

/// Camera rays in scanline order (as the `primary` workload makes them), about `n` per view,
/// from two views of `scene`: its own, and an eye at the centre of its bounds looking along -z,
/// so rays start inside the scene and a packet of neighbouring rays spans several direction
/// octants. For packet walks, which treat octants and rays starting inside specially.
pub fn camera_ray_sets(scene: &raybench_scenes::Scene, n: usize) -> [Vec<Ray>; 2] {
    use raybench_scenes::{Camera, View, primary_rays};
    let b = scene.mesh.bounds();
    let inside = View {
        camera: Camera {
            eye: b.center(),
            target: b.center() + Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            fov_y_deg: 90.0,
        },
        light: scene.view.light,
    };
    [scene.view, inside].map(|view| primary_rays(&view, &b, n).0)
}
