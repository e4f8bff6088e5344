//! `kd-packets` on CPUs with AVX2 but not AVX-512F: each block of sixteen coherent rays walked
//! as two packets of eight, one ray per AVX2 lane, with `packets.rs`'s walk in every respect
//! (one octant at a time, each lane's own interval cut at each plane exactly as its single-ray
//! walk cuts it, near with the lanes that need it and far pushed with the lanes that need that,
//! a popped subtree kept only by the lanes whose interval starts at or before their closest
//! hit). Leaves test their triangles with [`raybench_geom::packet8::Best8::test_tri4`], bit for
//! bit the scalar test, so every lane's answer is its single-ray walk's, as in `packets.rs`.
#![allow(unsafe_code)]

use crate::KdTree;
use crate::node::MAX_DEPTH;
use raybench_accel::Hit;
use raybench_geom::packet::{RayBlock, each_block};
use raybench_geom::packet8::{self, Avx2Packets, Best8, LANES, Packet8, bits};
use raybench_geom::{NO_PRIM, Ray};
use std::arch::x86_64::*;

/// A subtree still to visit: the lanes that need it and their intervals.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Entry {
    t0: [f32; LANES],
    t1: [f32; LANES],
    node: u32,
    lanes: u8,
}

/// One entry per level: the walk pushes at most one per node on its path.
type PacketStack = [Entry; MAX_DEPTH + 1];

/// Traces a coherent batch (closest hit), one block of two packets at a time: `rays` are the
/// batch's rays from the first block's first one, `out` gets the first `out.len()` of them.
pub(crate) fn intersect_coherent(
    _k: Avx2Packets,
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 and POPCNT on this CPU.
        unsafe { intersect_packets(kd, rays, blocks, out, stack) }
    })
}

#[target_feature(enable = "avx2,popcnt")]
fn intersect_packets(
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
    stack: &mut PacketStack,
) {
    each_packet(rays, blocks, out, |block, half, rays, out| {
        let (p, mut best) = packet8::load(block, half);
        walk_packet::<false>(kd, &p, rays, out.len(), &mut best, stack);
        for (o, (prim, h)) in out.iter_mut().zip(best.hits()) {
            *o = (prim != NO_PRIM).then(|| Hit::from_tri_hit(prim, h));
        }
    });
}

/// Traces a coherent batch (any hit), as [`intersect_coherent`].
pub(crate) fn occluded_coherent(
    _k: Avx2Packets,
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [bool],
) {
    with_packet_stack(|stack| {
        // SAFETY: an `Avx2Packets` exists only after `detect` saw AVX2 and POPCNT on this CPU.
        unsafe { occluded_packets(kd, rays, blocks, out, stack) }
    })
}

#[target_feature(enable = "avx2,popcnt")]
fn occluded_packets(
    kd: &KdTree,
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [bool],
    stack: &mut PacketStack,
) {
    each_packet(rays, blocks, out, |block, half, rays, out| {
        let (p, mut best) = packet8::load(block, half);
        let done = walk_packet::<true>(kd, &p, rays, out.len(), &mut best, stack);
        for (lane, o) in out.iter_mut().enumerate() {
            *o = done >> lane & 1 == 1;
        }
    });
}

/// Each block's two packets of eight: `packet` gets the block, which half, that half's rays
/// and their outputs (fewer than eight in a batch's last block).
#[inline(always)]
fn each_packet<T>(
    rays: &[Ray],
    blocks: &[RayBlock],
    out: &mut [T],
    mut packet: impl FnMut(&RayBlock, usize, &[Ray], &mut [T]),
) {
    for (block, rays, out) in each_block(blocks, rays, out) {
        for (half, (out, rays)) in out.chunks_mut(LANES).zip(rays.chunks(LANES)).enumerate() {
            packet(block, half, rays, out);
        }
    }
}

/// One packet of the first `len` of `rays`, walked once per direction octant present; returns
/// the lanes that found a hit (any hit) or 0 (closest hit, whose answers are in `best`).
#[target_feature(enable = "avx2,popcnt")]
fn walk_packet<const ANY_HIT: bool>(
    kd: &KdTree,
    p: &Packet8,
    rays: &[Ray],
    len: usize,
    best: &mut Best8,
    stack: &mut PacketStack,
) -> u8 {
    let mut done = 0;
    if kd.nodes.is_empty() {
        return done;
    }
    // Each lane's segment in the root cell: its single-ray walk's own slab test.
    let (mut t0, mut t1, mut inside) = ([0.0f32; LANES], [0.0f32; LANES], 0u8);
    for (lane, ray) in rays.iter().enumerate().take(len) {
        if let Some((enter, exit)) = kd.bounds.intersect(ray) {
            (t0[lane], t1[lane]) = (enter, exit);
            inside |= 1 << lane;
        }
    }
    packet8::octant_groups(p, len, |lanes, octant| {
        if lanes & inside != 0 {
            done |= walk::<ANY_HIT>(kd, p, lanes & inside, octant, (&t0, &t1), best, stack);
        }
    });
    done
}

raybench_accel::per_thread_stack!(
    /// Runs `f` with this thread's packet stack (a fresh one inside another walk).
    fn with_packet_stack -> PacketStack = new_stack()
);

fn new_stack() -> Box<PacketStack> {
    let empty = Entry {
        t0: [0.0; LANES],
        t1: [0.0; LANES],
        node: 0,
        lanes: 0,
    };
    Box::new([empty; MAX_DEPTH + 1])
}

/// The walk of the `active` lanes, whose directions all lie in `octant`, from their root
/// intervals `start`; with `ANY_HIT`, returns the lanes that found a hit (each done at its
/// first), else 0.
#[target_feature(enable = "avx2,popcnt")]
fn walk<const ANY_HIT: bool>(
    kd: &KdTree,
    p: &Packet8,
    active: u8,
    octant: u8,
    start: (&[f32; LANES], &[f32; LANES]),
    best: &mut Best8,
    stack: &mut PacketStack,
) -> u8 {
    // SAFETY: `start`'s arrays and every entry's are 8 initialised f32s; `loadu` and
    // `storeu` need no alignment.
    let load = |a: &[f32; LANES]| unsafe { _mm256_loadu_ps(a.as_ptr()) };
    let store = |v: __m256| {
        let mut a = [0.0f32; LANES];
        // SAFETY: as above.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) };
        a
    };
    let (mut t0, mut t1) = (load(start.0), load(start.1));
    let mut lanes = active;
    let mut live = active;
    let mut at = 0u32;
    let mut sp = 0;
    'walk: loop {
        let mut node = kd.nodes[at as usize];
        while !node.is_leaf() {
            let a = node.axis();
            let plane = _mm256_set1_ps(node.split());
            let t_split = _mm256_mul_ps(_mm256_sub_ps(plane, p.origin[a]), p.inv[a]);
            let (below, above) = (at + 1, node.above());
            let near = if octant >> a & 1 == 1 { above } else { below };
            let far = below ^ above ^ near;
            // Near unless the plane was crossed before the interval; far unless it comes
            // after it; both on NaN (the ray lies in the plane).
            let near_lanes = bits(_mm256_cmp_ps::<_CMP_NLT_UQ>(t_split, t0)) & lanes;
            let far_lanes = bits(_mm256_cmp_ps::<_CMP_NGT_UQ>(t_split, t1)) & lanes;
            if near_lanes == 0 {
                at = far;
            } else if far_lanes == 0 {
                at = near;
            } else {
                let both = packet8::lanes_mask(near_lanes & far_lanes);
                stack[sp] = Entry {
                    t0: store(_mm256_blendv_ps(t0, _mm256_max_ps(t_split, t0), both)),
                    t1: store(t1),
                    node: far,
                    lanes: far_lanes,
                };
                sp += 1;
                t1 = _mm256_blendv_ps(t1, _mm256_min_ps(t_split, t1), both);
                lanes = near_lanes;
                at = near;
            }
            node = kd.nodes[at as usize];
        }
        let (first, count) = (node.first() as usize, node.count() as usize);
        let four = raybench_geom::tri4::LANES;
        for tri4 in &kd.tri4s[first / four..(first + count).div_ceil(four)] {
            best.test_tri4(tri4, p, lanes);
        }
        if ANY_HIT {
            live &= !(best.hit_lanes() & lanes);
            if live == 0 {
                break 'walk;
            }
        }
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            let e = &stack[sp];
            let enter = load(&e.t0);
            // Lanes whose interval starts beyond their closest hit are done with it.
            let keep = bits(_mm256_cmp_ps::<_CMP_NGT_UQ>(enter, best.t)) & e.lanes & live;
            if keep != 0 {
                (at, lanes, t0) = (e.node, keep, enter);
                t1 = _mm256_min_ps(load(&e.t1), best.t);
                break;
            }
        }
    }
    active & !live
}

#[cfg(test)]
mod tests {
    use crate::{KdParams, KdTree};
    use raybench_accel::Accel;
    use raybench_geom::PacketWalk;
    use raybench_geom::TriangleMesh;
    use raybench_geom::packet8::Avx2Packets;
    use raybench_testkit::{
        camera_ray_sets, edge_cases, occlusion_packets_against_single_rays,
        packets_against_single_rays, scenes, seeded_cases, shadow_ray_sets, valid_rays,
    };
    use std::sync::Arc;

    /// `kd-packets` walking eight lanes whatever the CPU's widest walk, so a CPU with
    /// AVX-512F tests this walk too; `None` (said) without AVX2.
    fn eight_lanes(mesh: &Arc<TriangleMesh>) -> Option<KdTree> {
        let Some(k) = Avx2Packets::detect() else {
            eprintln!("no AVX2 on this CPU: the eight-lane packet walk never runs here");
            return None;
        };
        let mut kd = KdTree::build(mesh.clone(), &KdParams::packets()).expect("builds");
        kd.validate(mesh).expect("valid");
        kd.coherent = Some(PacketWalk::Avx2(k));
        Some(kd)
    }

    /// Every ray's closest hit and occlusion answer as the single-ray walk's (closest hits bit
    /// for bit but for exact ties), on the seeded and edge cases, and on camera rays and the
    /// shadow rays from their hits over scenes of every kind; the counts are asserted so the
    /// test cannot pass on nothing.
    #[test]
    fn eight_lanes_answer_as_single_rays() {
        for case in seeded_cases().into_iter().chain(edge_cases()) {
            let Some(kd) = eight_lanes(&case.mesh) else {
                return;
            };
            let rays = valid_rays(&case);
            packets_against_single_rays(&kd, &case.mesh, &rays, &case.name);
            occlusion_packets_against_single_rays(&kd, &rays, &case.name);
        }
        let (mut hits, mut occluded, mut shadow_rays) = (0usize, 0usize, 0usize);
        for spec in [
            "teapot-in-stadium",
            "city",
            "soup:triangles=20000",
            "hair:triangles=20000",
            "plane:quads=64",
        ] {
            let scene = scenes::generate(spec, 3).expect("generates");
            let Some(kd) = eight_lanes(&scene.mesh) else {
                return;
            };
            for rays in camera_ray_sets(&scene, 10_000) {
                hits += packets_against_single_rays(&kd, &scene.mesh, &rays, spec).0;
            }
            for rays in shadow_ray_sets(&scene, &kd, 6_000) {
                occluded += occlusion_packets_against_single_rays(&kd, &rays, spec);
                shadow_rays += rays.len();
            }
        }
        eprintln!("eight lanes: {hits} identical hits, {occluded} of {shadow_rays} occluded");
        assert!(hits > 50_000, "only {hits} hits");
        assert!(occluded > 3_000, "only {occluded} occluded");
        assert!(
            shadow_rays - occluded > 3_000,
            "only {} unoccluded",
            shadow_rays - occluded
        );
    }
}
