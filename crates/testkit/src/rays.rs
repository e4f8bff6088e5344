//! Seeded ray sets for conformance cases.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::{Aabb, Ray, TriangleMesh, Vec3};

/// The generator every testkit case uses (portable, documented algorithm; never `StdRng`).
pub fn seeded_rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

fn unit_f32(rng: &mut Pcg64Mcg) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

fn on_sphere(rng: &mut Pcg64Mcg) -> Vec3 {
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
