//! Leaf triangles into `Tri4`s: numbering them in tree order, then filling them.

use super::node::WideNode;
use crate::build::PrimRef;
use crate::node::ChildRef;
use raybench_geom::{MollerTriangle, Tri4, TriangleMesh};

/// One packet's triangles: the builder's records `refs[start..start + len]`, `len` 1 to 4.
#[derive(Clone, Copy)]
pub(super) struct PacketSource {
    start: u32,
    len: u32,
}

/// The packets in tree order (see [`number_packets`]), built on rayon: gathering each
/// triangle's vertices from the mesh is the part of the collapse that touches memory at
/// random, and packets are independent. The length is known, so the indexed `collect` writes
/// each packet straight into its place (a `flat_map` over leaves collected through per-task
/// lists and a final copy: about 7 % of the 8-wide build's samples on the sphere, perf with 2
/// threads, this VM, 2026-11-22). The result does not depend on the thread count.
pub(super) fn pack_leaves(
    mesh: &TriangleMesh,
    refs: &[PrimRef],
    sources: &[PacketSource],
) -> Vec<Tri4> {
    use rayon::prelude::*;
    sources
        .par_iter()
        .with_min_len(1024)
        .map(|s| {
            let mut packet = Tri4::default();
            for (lane, p) in refs[s.start as usize..(s.start + s.len) as usize]
                .iter()
                .enumerate()
            {
                let i = p.id();
                packet.set_lane(lane, i, &MollerTriangle::new(&mesh.triangle(i as usize)));
            }
            packet
        })
        .collect()
}

/// Turns every leaf reference of the collapsed tree from a triangle range into its packets
/// (`{ index: first packet, count: triangles }`), numbered in depth-first order, which is the
/// order of the triangles; returns where each packet's triangles are, in that order.
pub(super) fn number_packets<const W: usize>(
    nodes: &mut [WideNode<W>],
    r: &mut ChildRef,
) -> Vec<PacketSource> {
    fn visit<const W: usize>(
        nodes: &mut [WideNode<W>],
        r: &mut ChildRef,
        sources: &mut Vec<PacketSource>,
    ) {
        if r.is_leaf() {
            let first = r.index;
            r.index = sources.len() as u32;
            for k in (0..r.count).step_by(4) {
                sources.push(PacketSource {
                    start: first + k,
                    len: (r.count - k).min(4),
                });
            }
            return;
        }
        let i = r.index as usize;
        for slot in 0..nodes[i].children() {
            let mut c = nodes[i].child[slot];
            visit(nodes, &mut c, sources);
            nodes[i].child[slot] = c;
        }
    }
    let mut sources = Vec::new();
    visit(nodes, r, &mut sources);
    sources
}
