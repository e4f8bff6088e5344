//! The leaves' final layout: each leaf's references padded to a multiple of four, and the
//! triangles they name copied, four to a [`Tri4`], in the same order, so the walk goes from a
//! leaf node straight to its triangles (one fetch, no index array in between) and tests them
//! four at a time. A leaf starting at reference `f` (a multiple of four) owns the Tri4s from
//! `f / 4`; padding references are [`PAD`] and their lanes are unused (the all-zero triangle,
//! which no ray hits, and [`raybench_geom::NO_PRIM`]).
//!
//! References are then renumbered to slots in the order leaves first reference the triangles
//! (`prim_ids[slot]` is the mesh index), which closest-point queries and `validate` read.
//! Trade-off: a triangle referenced by several leaves is copied into each, so the Tri4s take
//! about 48 bytes a reference (padding included) where one copy per triangle took 48 bytes a
//! triangle.

use crate::node::Node;
use raybench_geom::tri4::LANES;
use raybench_geom::{MollerTriangle, Tri4, Triangle};
use rayon::prelude::*;

/// A padding reference.
pub const PAD: u32 = u32::MAX;

/// What [`pack`] returns.
pub(crate) struct Packed {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub prim_ids: Vec<u32>,
    pub tri4s: Vec<Tri4>,
}

/// Pads and copies the leaves of `nodes`, whose `refs` are mesh indices into `tris`.
pub(crate) fn pack(mut nodes: Vec<Node>, refs: &[u32], tris: &[Triangle]) -> Packed {
    let mut padded = Vec::with_capacity(refs.len() + refs.len() / 2);
    for node in nodes.iter_mut().filter(|n| n.is_leaf()) {
        let (first, count) = (node.first() as usize, node.count() as usize);
        *node = Node::leaf(padded.len() as u32, count as u32);
        padded.extend_from_slice(&refs[first..first + count]);
        padded.resize(padded.len().next_multiple_of(LANES), PAD);
    }
    let tri4s = padded
        .par_chunks_exact(LANES)
        .map(|four| {
            let mut t = Tri4::default();
            for (lane, &id) in four.iter().enumerate().filter(|(_, id)| **id != PAD) {
                t.set_lane(lane, id, &MollerTriangle::new(&tris[id as usize]));
            }
            t
        })
        .collect();
    // Slots in the order leaves first reference the triangles.
    let mut slot_of = vec![u32::MAX; tris.len()];
    let mut prim_ids = Vec::new();
    for r in padded.iter_mut().filter(|r| **r != PAD) {
        let slot = &mut slot_of[*r as usize];
        if *slot == u32::MAX {
            *slot = prim_ids.len() as u32;
            prim_ids.push(*r);
        }
        *r = *slot;
    }
    Packed {
        nodes,
        refs: padded,
        prim_ids,
        tri4s,
    }
}
