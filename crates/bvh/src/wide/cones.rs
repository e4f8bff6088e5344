//! Batches not marked coherent, searched for packets: a group of sixteen consecutive rays whose
//! directions lie in one octant and within a narrow cone is traced as one packet
//! (`packets.rs`), every other ray by the single-ray walk. Mirror reflections off a flat
//! surface, from neighbouring pixels, are such groups: they leave one surface side by side, in
//! nearly one direction, and meet the same nodes, as camera rays do. Diffuse bounces never are,
//! and pay only the check, which rejects a scattered group at its second ray.
//!
//! The groups are the batch's own runs of sixteen, in its order, from the batch's start (the
//! harness's chunks are multiples of sixteen), so which rays go as packets does not depend on
//! the thread count; nothing is reordered. Each ray's answer is its single-ray walk's, as for
//! every packet (`packets.rs`, "Exactness").

use super::BvhWide;
use super::packets::{PacketStack, intersect_blocks};
use raybench_accel::Hit;
use raybench_geom::Ray;
use raybench_geom::packet::{Avx512Packets, PACKET, RayBlock};

/// The direction's sign bits, one per axis: the octant as the packet walk reads it from the
/// inverse direction (`1 / -0` is `-inf`, so `-0` counts as negative either way).
#[inline(always)]
fn signs(d: raybench_geom::Vec3) -> u32 {
    d.x.to_bits() >> 31 | (d.y.to_bits() >> 31) << 1 | (d.z.to_bits() >> 31) << 2
}

/// Whether every ray of `group` points into the first ray's octant and within the cone of
/// cosine `cos` (in `(0, 1]`) around its direction. Squared, so no root is taken:
/// `d0 · d >= cos |d0| |d|` with a positive dot product. The three conditions are combined
/// without branches: a scattered group fails at its second ray, on one branch.
pub(crate) fn within_cone(group: &[Ray], cos: f32) -> bool {
    let Some((first, rest)) = group.split_first() else {
        return false;
    };
    let d0 = first.dir();
    let (oct, bound) = (signs(d0), cos * cos * d0.length_squared());
    rest.iter().all(|r| {
        let d = r.dir();
        let dot = d0.dot(d);
        (signs(d) == oct) & (dot > 0.0) & (dot * dot >= bound * d.length_squared())
    })
}

/// The longest run handed to the single-ray walk at once, so the walk finds the rays the check
/// has just read still in cache: checking a whole batch before tracing any of it made
/// Sponza's diffuse rays (7 ns a ray, no group within the cone) 11 % slower than the plain
/// loop, runs of 256 rays 6 %, runs of 1,024 5 % (medians of 15 alternated passes).
const RUN: usize = 64 * PACKET;

/// Traces `rays` (closest hit) into `out`: each group of [`PACKET`] consecutive rays that is
/// [`within_cone`] as a packet, the runs between them through `single`, at most [`RUN`] rays a
/// call.
pub(crate) fn intersect_with_cones<const W: usize>(
    k: Avx512Packets,
    bvh: &BvhWide<W>,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    cos: f32,
    mut single: impl FnMut(&[Ray], &mut [Option<Hit>]),
) {
    let n = out.len().min(rays.len());
    let mut stack: Option<Box<PacketStack>> = None;
    // Rays before `run` are answered; groups start at multiples of PACKET.
    let mut run = 0;
    let mut at = 0;
    while at + PACKET <= n {
        let group = &rays[at..at + PACKET];
        if at - run >= RUN {
            single(&rays[run..at], &mut out[run..at]);
            run = at;
        }
        if within_cone(group, cos) {
            single(&rays[run..at], &mut out[run..at]);
            let stack = stack.get_or_insert_with(super::packets::new_packet_stack);
            // Written row by row and loaded back: faster than gathering each row from the
            // rays (Sponza's Whitted rays 0.96 against 0.88 of the plain loop's rate,
            // conference 1.68 against 1.61).
            let block = RayBlock::new(group);
            let out = &mut out[at..at + PACKET];
            intersect_blocks(k, bvh, std::slice::from_ref(&block), out, stack);
            run = at + PACKET;
        }
        at += PACKET;
    }
    single(&rays[run..n], &mut out[run..n]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wide::{Bvh8, WideParams};
    use raybench_accel::Accel;
    use raybench_geom::Vec3;
    use std::sync::Arc;

    fn ray(dir: [f32; 3]) -> Ray {
        Ray::infinite(Vec3::ZERO, Vec3::from(dir))
    }

    /// Sixteen rays spread evenly around `axis`, each `deg` degrees off it.
    fn cone(axis: Vec3, deg: f32) -> Vec<Ray> {
        let side = axis.any_orthonormal_vector();
        let up = axis.cross(side);
        (0..PACKET)
            .map(|i| {
                let turn = i as f32 / PACKET as f32 * std::f32::consts::TAU;
                let off = (side * turn.cos() + up * turn.sin()) * deg.to_radians().tan();
                Ray::infinite(
                    Vec3::new(i as f32, 0.0, 0.0),
                    (axis + off) * (1.0 + i as f32),
                )
            })
            .collect()
    }

    #[test]
    fn a_cone_is_judged_by_its_angle_and_octant() {
        let axis = Vec3::new(0.3, 0.5, 0.8).normalize();
        // cos 5.7 degrees = 0.99506; two rays on opposite sides of the axis are twice that
        // apart, so the group's spread around its first ray is what counts.
        assert!(within_cone(&cone(axis, 2.0), 0.995));
        assert!(!within_cone(&cone(axis, 4.0), 0.995));
        assert!(within_cone(&cone(axis, 4.0), 0.98));
        // Lengths do not matter, only directions.
        let mut scaled = cone(axis, 1.0);
        scaled[7] = Ray::infinite(Vec3::ZERO, scaled[7].dir() * 1e-3);
        assert!(within_cone(&scaled, 0.995));
        // One ray pointing the other way, or into another octant, breaks the group.
        let mut back = cone(axis, 1.0);
        back[15] = Ray::infinite(Vec3::ZERO, -axis);
        assert!(!within_cone(&back, 0.5));
        let mut across = vec![ray([1.0, 1e-3, 1.0]); PACKET];
        assert!(within_cone(&across, 0.995));
        across[3] = ray([1.0, -1e-3, 1.0]);
        assert!(
            !within_cone(&across, 0.995),
            "another octant, however close"
        );
        across[3] = ray([1.0, -0.0, 1.0]);
        assert!(
            !within_cone(&across, 0.995),
            "-0 points down, as the packet walk reads it"
        );
        assert!(!within_cone(&[], 0.995));
    }

    /// The groups within the cone go to the packet walk, every other ray to `single` in runs
    /// between them, each ray answered once and as its single-ray walk answers it.
    #[test]
    fn only_the_groups_within_the_cone_go_as_packets() {
        let Some(k) = Avx512Packets::detect() else {
            eprintln!("no AVX-512F on this CPU: no packets to route");
            return;
        };
        let (mesh, _) =
            raybench_geom::TriangleMesh::from_triangles(&[raybench_geom::Triangle::new(
                Vec3::new(-100.0, -100.0, 10.0),
                Vec3::new(100.0, -100.0, 10.0),
                Vec3::new(0.0, 100.0, 10.0),
            )])
            .expect("a valid triangle");
        let mesh = Arc::new(mesh);
        let bvh = Bvh8::build(mesh, &WideParams::for_width(8).with_packets()).expect("builds");
        // Inside one octant, so that the cones' rays share it.
        let z = Vec3::new(0.2, 0.3, 1.0).normalize();
        let scattered: Vec<Ray> = (0..PACKET)
            .map(|i| ray([(i as f32 * 0.7).sin(), (i as f32 * 1.3).cos(), 0.5]))
            .collect();
        // Groups: cone, scattered, scattered, cone, cone, then a tail of five rays.
        let mut rays = cone(z, 1.0);
        rays.extend(&scattered);
        rays.extend(&scattered);
        rays.extend(cone(z, 0.5));
        rays.extend(cone(z, 2.0));
        rays.extend(&cone(z, 0.1)[..5]);
        let mut out = vec![None; rays.len()];
        let mut runs = Vec::new();
        intersect_with_cones(k, &bvh, &rays, &mut out, 0.995, |r, o| {
            runs.push(r.len());
            for (o, r) in o.iter_mut().zip(r) {
                *o = bvh.intersect(r);
            }
        });
        // Before the first cone (empty), the two scattered groups, nothing between the two
        // cones, and the tail too short for a packet.
        assert_eq!(runs, vec![0, 2 * PACKET, 0, 5]);
        for (i, (r, o)) in rays.iter().zip(&out).enumerate() {
            assert_eq!(*o, bvh.intersect(r), "ray {i}");
        }
        assert!(
            out[..PACKET].iter().all(Option::is_some),
            "the cone hits the triangle"
        );
    }
}
