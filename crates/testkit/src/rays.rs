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

/// Rays for space-partitioning structures over the cube [0, 4]³ cut at multiples of 0.5 (grid
/// cells, octants, split planes): along cell planes and edges and through cell corners,
/// axis-parallel with ±0 components, starting outside, inside, on planes and at vertices —
/// where an off-by-one in a cell walk or a strict comparison loses a hit.
pub fn lattice_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    let lines: Vec<f32> = (0..=8).map(|k| k as f32 * 0.5).collect();
    let signs = [(1.0f32, 0.0f32), (-1.0, -0.0)];
    for &a in &lines {
        for &b in &lines {
            for (s, z) in signs {
                // Along the z axis on the cell edge x = a, y = b: from outside and from inside.
                rays.push(Ray::infinite(
                    Vec3::new(a, b, 2.0 - 3.0 * s),
                    Vec3::new(z, -z, s),
                ));
                rays.push(Ray::infinite(Vec3::new(a, b, 2.25), Vec3::new(z, z, s)));
                // Along x on y = a, z = b, and along y on z = a, x = b.
                rays.push(Ray::infinite(
                    Vec3::new(2.0 - 3.0 * s, a, b),
                    Vec3::new(s, z, z),
                ));
                rays.push(Ray::infinite(Vec3::new(b, 1.75, a), Vec3::new(-z, s, z)));
            }
            // In the plane x = a (d.x = ±0), oblique in y and z, through cell corners.
            rays.push(Ray::infinite(
                Vec3::new(a, -1.0, b - 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ));
            rays.push(Ray::infinite(
                Vec3::new(a, 5.0, b + 1.0),
                Vec3::new(-0.0, -1.0, -1.0),
            ));
            // Diagonals through grid vertices, from inside with t_min > 0.
            rays.push(Ray::new(
                Vec3::new(a, b, 0.0),
                Vec3::new(1.0, 1.0, 1.0),
                0.25,
                100.0,
            ));
            rays.push(Ray::new(
                Vec3::new(a, b, 4.0),
                Vec3::new(-1.0, 1.0, -1.0),
                0.0,
                3.0,
            ));
        }
    }
    // From every grid vertex (origin exactly on three planes) in seeded directions.
    let mut rng = seeded_rng(0x5eed_6002);
    for &x in lines.iter().step_by(2) {
        for &y in lines.iter().step_by(2) {
            for &z in lines.iter().step_by(2) {
                let d = Vec3::new(
                    rng.next_u32() as f32,
                    rng.next_u32() as f32,
                    rng.next_u32() as f32,
                ) / u32::MAX as f32
                    - 0.5;
                rays.push(Ray::infinite(Vec3::new(x, y, z), d));
                rays.push(Ray::infinite(Vec3::new(x, y, z), -d));
            }
        }
    }
    rays
}
