//! The packet walk rules out a node's children by bounds over the whole packet before testing
//! ray by ray. These packets are built so that a careless bound would rule out a child that one
//! ray does enter: that ray travels in the bottom face plane of its target's box with a `-0`
//! direction component (inverse `-inf`, so `0 * inf` is NaN in the slab test, which then ignores
//! the axis), while the packet's other rays point down the same axis with finite inverses and
//! miss. Its answer must still be the single-ray walk's: a hit on the target's bottom edge.

use raybench_accel::Accel;
use raybench_bvh::{Bvh8, WideParams};
use raybench_geom::{Ray, Triangle, TriangleMesh, Vec3};
use raybench_testkit::{occlusion_packets_against_single_rays, packets_against_single_rays};
use std::sync::Arc;

/// A vertical triangle in the plane `x = 0` whose bottom edge lies on `y = 0`, and a field of
/// small triangles well above it, so the tree has nodes above the target's leaf.
fn scene() -> Arc<TriangleMesh> {
    let mut tris = vec![Triangle::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 0.5),
    )];
    for i in 0..40 {
        for j in 0..40 {
            let (x, z) = (i as f32 * 0.5 - 10.0, j as f32 * 0.5 - 10.0);
            let y = 5.0 + (i * 7 + j * 3) as f32 % 5.0;
            tris.push(Triangle::new(
                Vec3::new(x, y, z),
                Vec3::new(x + 0.3, y, z),
                Vec3::new(x, y + 0.3, z + 0.2),
            ));
        }
    }
    Arc::new(TriangleMesh::from_triangles(&tris).expect("valid").0)
}

/// Packets of sixteen: in every packet, lane `k` of the face-plane rays moves along `+x` in
/// the plane `y = 0` with direction `(1, -0, 0)`; the others start below the target and point
/// down and away. Every lane's direction lies in the same octant (`-0` counts as down).
fn rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    for k in 0..16 {
        for lane in 0..16 {
            rays.push(if lane == k {
                let z = 0.125 + 0.75 * k as f32 / 16.0;
                Ray::new(
                    Vec3::new(-1.0, 0.0, z),
                    Vec3::new(1.0, -0.0, 0.0),
                    0.0,
                    f32::INFINITY,
                )
            } else {
                Ray::new(
                    Vec3::new(-1.0, -1.0 - lane as f32 * 0.01, 0.5),
                    Vec3::new(1.0, -0.5, 0.0),
                    0.0,
                    f32::INFINITY,
                )
            });
        }
    }
    rays
}

fn packet_tree(mesh: &Arc<TriangleMesh>) -> Option<Bvh8> {
    let params = WideParams {
        coherent_packets: true,
        ..WideParams::for_width(8)
    };
    let bvh = Bvh8::build(mesh.clone(), &params).expect("builds");
    bvh.validate(mesh).expect("valid");
    if !bvh.packet_walk() {
        eprintln!("no AVX2 on this CPU: the packet walk is not used, nothing to compare");
        return None;
    }
    Some(bvh)
}

#[test]
fn a_ray_in_a_box_face_plane_keeps_its_hit_in_a_packet() {
    let mesh = scene();
    let Some(bvh) = packet_tree(&mesh) else {
        return;
    };
    let rays = rays();
    let single_hits = rays.iter().filter(|r| bvh.intersect(r).is_some()).count();
    assert_eq!(
        single_hits, 16,
        "each face-plane ray hits the target's bottom edge"
    );
    let (hits, ties) = packets_against_single_rays(&bvh, &mesh, &rays, "face-plane packets");
    assert_eq!((hits, ties), (16, 0));
}

#[test]
fn a_ray_in_a_box_face_plane_stays_occluded_in_a_packet() {
    let mesh = scene();
    let Some(bvh) = packet_tree(&mesh) else {
        return;
    };
    let rays = rays();
    let occluded = occlusion_packets_against_single_rays(&bvh, &rays, "face-plane packets");
    assert_eq!(occluded, 16, "each face-plane ray is stopped by the target");
}
