//! Seeded scenes and rays for the Embree tests, from the workspace's SplitMix64, so the tests
//! depend on no scene crate and every case replays from its seed.
#![allow(dead_code)] // each test binary uses a different part

use raybench_embree::EmbreeParams;
use raybench_geom::{Ray, Triangle, TriangleMesh, Vec3};
use std::sync::Arc;

pub use raybench_geom::SplitMix64;

pub fn mesh_of(triangles: &[Triangle]) -> Arc<TriangleMesh> {
    let (mesh, removed) = TriangleMesh::from_triangles(triangles).unwrap();
    assert_eq!(removed.total(), 0);
    Arc::new(mesh)
}

/// `n` random triangles with centres in the unit cube and edges up to ~0.2 long: overlapping,
/// all orientations, separate vertices.
pub fn random_triangles(seed: u64, n: usize) -> Arc<TriangleMesh> {
    let mut rng = SplitMix64::new(seed);
    let half = Vec3::splat(0.1);
    let triangles: Vec<Triangle> = (0..n)
        .map(|_| {
            let c = rng.point_in(Vec3::ZERO, Vec3::ONE);
            let mut corner = || c + rng.point_in(-half, half);
            Triangle::new(corner(), corner(), corner())
        })
        .collect();
    mesh_of(&triangles)
}

/// An `n`×`n` grid of quads over the unit square, two triangles each, on a seeded bumpy
/// height field: shared vertices and shared edges, as in a real mesh.
pub fn height_field(seed: u64, n: u32) -> Arc<TriangleMesh> {
    let mut rng = SplitMix64::new(seed);
    let side = n + 1;
    let positions: Vec<Vec3> = (0..side * side)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            Vec3::new(
                i as f32 / n as f32,
                j as f32 / n as f32,
                rng.range(0.0, 0.1),
            )
        })
        .collect();
    let at = |i: u32, j: u32| j * side + i;
    let indices: Vec<[u32; 3]> = (0..n * n)
        .flat_map(|k| {
            let (i, j) = (k % n, k / n);
            [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ]
        })
        .collect();
    let (mesh, removed) = TriangleMesh::new(positions, indices).unwrap();
    assert_eq!(removed.total(), 0);
    Arc::new(mesh)
}

/// `n` rays with origins in the mesh bounds enlarged by half their size on every side and
/// directions uniform on the sphere, plus one ray per triangle aimed at its centroid from such
/// an origin. A quarter of the random rays get a finite `t_max`, an eighth a positive `t_min`,
/// so the interval ends are exercised too.
pub fn workload(mesh: &TriangleMesh, seed: u64, n: usize) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    let bounds = mesh.bounds();
    let margin = (bounds.max - bounds.min) * 0.5;
    let (lo, hi) = (bounds.min - margin, bounds.max + margin);
    let mut rays = Vec::with_capacity(n + mesh.len());
    for k in 0..n {
        let origin = rng.point_in(lo, hi);
        let dir = rng.direction();
        let t_min = if k % 8 == 3 { rng.range(0.0, 0.5) } else { 0.0 };
        let t_max = if k % 4 == 1 {
            rng.range(0.6, 2.0)
        } else {
            f32::INFINITY
        };
        rays.push(Ray::new(origin, dir, t_min, t_max));
    }
    for tri in mesh.triangles() {
        let origin = rng.point_in(lo, hi);
        rays.push(Ray::infinite(origin, tri.centroid() - origin));
    }
    rays
}

pub fn presets() -> [EmbreeParams; 4] {
    [
        EmbreeParams::low(),
        EmbreeParams::medium(),
        EmbreeParams::high(),
        EmbreeParams::robust(),
    ]
}
