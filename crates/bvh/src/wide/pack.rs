//! Leaf triangles into `Tri4`s: numbering them in tree order, then filling them.

use super::node::WideNode;
use crate::build::PrimRef;
use crate::node::ChildRef;
use crate::simd::prefetch;
use raybench_geom::{MollerTriangle, Tri4, TriangleMesh};

/// `Tri4`s ahead of the one being filled whose vertices are prefetched, their indices twice as
/// far ahead: up to 8 and 16 triangles, as the spatial search prefetches references (not tuned
/// here).
const AHEAD: usize = 2;

/// The fewest `Tri4`s a fill task takes on small trees (large ones take 1,024 a task; see
/// `grain.rs`).
const MIN_FILL_TASK: usize = 64;

/// One `Tri4`'s triangles: the builder's records `refs[start..start + len]`, `len` 1 to 4.
#[derive(Clone, Copy)]
pub(super) struct Tri4Source {
    start: u32,
    len: u32,
}

impl Tri4Source {
    /// Its triangles' records in `refs`.
    fn records(self, refs: &[PrimRef]) -> &[PrimRef] {
        &refs[self.start as usize..(self.start + self.len) as usize]
    }
}

/// The `Tri4`s in tree order (see [`number_tri4s`]), built on rayon: gathering each
/// triangle's vertices from the mesh is the part of the collapse that touches memory at
/// random, and `Tri4`s are independent. The length is known, so the indexed `collect` writes
/// each `Tri4` straight into its place, with no per-task lists and final copy (measured: see
/// docs/experiments.md, "`Tri4`s built by an indexed parallel `collect`"). Each task fills
/// consecutive `Tri4`s, so the indices and vertices of the triangles a few `Tri4`s on are
/// prefetched while one is filled (measured: see docs/experiments.md, "the `Tri4` fill
/// prefetching"). The result does not depend on the thread count.
pub(super) fn fill_tri4s(
    mesh: &TriangleMesh,
    refs: &[PrimRef],
    sources: &[Tri4Source],
) -> Vec<Tri4> {
    use rayon::prelude::*;
    let (indices, positions) = (mesh.indices(), mesh.positions());
    // The records of the `Tri4` `by` after the `k`-th (none past the last).
    let ahead = |k: usize, by: usize| sources.get(k + by).map_or(&[][..], |a| a.records(refs));
    (0..sources.len())
        .into_par_iter()
        .with_min_len(crate::grain::grain(sources.len(), MIN_FILL_TASK, 1024))
        .map(|k| {
            for p in ahead(k, 2 * AHEAD) {
                prefetch(indices.as_ptr().wrapping_add(p.id() as usize));
            }
            for p in ahead(k, AHEAD) {
                for v in indices[p.id() as usize] {
                    prefetch(positions.as_ptr().wrapping_add(v as usize));
                }
            }
            let mut tri4 = Tri4::default();
            for (lane, p) in sources[k].records(refs).iter().enumerate() {
                let i = p.id();
                tri4.set_lane(lane, i, &MollerTriangle::new(&mesh.triangle(i as usize)));
            }
            tri4
        })
        .collect()
}

/// Turns every leaf reference of the collapsed tree from a triangle range into its `Tri4`s
/// (`{ index: first Tri4, count: triangles }`), numbered in depth-first order, which is the
/// order of the triangles; returns where each `Tri4`'s triangles are, in that order.
pub(super) fn number_tri4s<const W: usize>(
    nodes: &mut [WideNode<W>],
    r: &mut ChildRef,
) -> Vec<Tri4Source> {
    fn visit<const W: usize>(
        nodes: &mut [WideNode<W>],
        r: &mut ChildRef,
        sources: &mut Vec<Tri4Source>,
    ) {
        if r.is_leaf() {
            let first = r.index;
            r.index = sources.len() as u32;
            for k in (0..r.count).step_by(4) {
                sources.push(Tri4Source {
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
