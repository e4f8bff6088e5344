//! Wide BVHs — 8 children per node ([`Bvh8`]) or 4 ([`Bvh4`]) — collapsed from the binary SAH
//! tree, traversed with one SIMD box test per node (issue 8; see the README for where they
//! stand against Embree).
//!
//! Collapse (as in Wald et al. 2008, "Getting rid of packets", and Embree's BVH4/BVH8
//! builders): each wide node starts from a binary node's two children and repeatedly opens the
//! child with the largest surface area — the one a ray is most likely to enter — until it has
//! `W` children or only leaves remain; slots still empty then are filled by splitting the
//! largest leaves of more than one packet in two (`fill_slots`, as Embree's builder splits
//! every child until the node is full: over the 17 default scenes shadow rays +2.3–2.8 %,
//! primary −0.1 to +1.0 %, random +0.4–0.9 % in three sweeps, and the SAH cost with the
//! shared constants 10–35 % lower, this VM, 2026-11-21). The
//! wide tree has about a third (8 wide) or half (4 wide) of the binary tree's depth, so a ray
//! walks fewer, wider nodes: fewer dependent memory fetches. The trade-off between the widths:
//! a 4-wide node is two cache lines and one 4-lane SSE test per axis, an 8-wide node four
//! lines and one 8-lane AVX2 test, and fewer of them on a ray's path.
//!
//! Traversal is ordered: the children a ray enters are sorted by entry distance, the farther
//! ones pushed with that distance and skipped when popped beyond the closest hit. Every child
//! entered is prefetched before the ordering, so the fetch of the subtrees pushed for later
//! overlaps the walk below the nearest (bunny random rays 0.97× → 1.11× embree-medium, this VM,
//! 2026-11-21; prefetching only the pushed ones gained less).
//!
//! Leaves are SIMD packets ([`Tri4`]): the binary builder prices a leaf by the packets of four
//! it fills (`leaf_block = 4`), and one SSE Möller–Trumbore test answers for four triangles;
//! with AVX2 a leaf's packets are tested two at a time, eight lanes a pass
//! ([`crate::avx2`]), with the same answers.
//! An 8-wide node is tested in one 8-lane AVX2 pass per axis when the CPU has AVX2 (detected
//! at build time, [`crate::avx2`]) and in two 4-lane SSE passes otherwise; both are the scalar
//! slab test lane for lane and pass the same conformance tests.

use crate::BvhParams;
use crate::build::{self, Box3, PrimRef};
use crate::node::{ChildRef, MAX_DEPTH, Node};
use crate::simd::{F4, prefetch};
use raybench_accel::{
    Accel, BuildError, BuildStats, CounterSink, Hit, Memory, NoCount, PreparedRays,
    SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST, Walk,
};
use raybench_geom::{Aabb, MollerTriangle, Ray, RayError, TriHit, TriangleMesh, Vec3};
use raybench_geom::{NO_PRIM, Tri4};
use serde::Serialize;
use std::cell::RefCell;
use std::sync::Arc;

/// The widest node built (and the size of every traversal stack).
pub const MAX_WIDTH: usize = 8;

/// Stack entries a walk can need: a node pushes at most `MAX_WIDTH - 1`, one per level, and
/// the binary builder caps the depth at [`MAX_DEPTH`] (collapsing only shortens it).
pub(crate) const STACK: usize = (MAX_WIDTH - 1) * MAX_DEPTH + 1;

/// One wide node of `W` children (4 or 8): child boxes per axis as `[min or max][slot]`, so
/// one SIMD load fetches a plane of four or eight children; unused slots hold an empty box
/// (`min = +inf`, `max = -inf`) that no ray enters. 8 wide: 256 bytes, four cache lines;
/// 4 wide: 128 bytes, two.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode<const W: usize> {
    /// `[axis][0 = min, 1 = max][slot]`.
    pub planes: [[[f32; W]; 2]; 3],
    pub child: [ChildRef; W],
}

pub type Node8 = WideNode<8>;
pub type Node4 = WideNode<4>;

const _: () = assert!(std::mem::size_of::<Node8>() == 256);
const _: () = assert!(std::mem::size_of::<Node4>() == 128);

impl<const W: usize> WideNode<W> {
    fn empty() -> WideNode<W> {
        WideNode {
            planes: [[[f32::INFINITY; W], [f32::NEG_INFINITY; W]]; 3],
            child: [ChildRef::default(); W],
        }
    }

    pub fn child_bounds(&self, i: usize) -> Aabb {
        let at = |axis: usize, side: usize| self.planes[axis][side][i];
        Aabb::new(
            Vec3::new(at(0, 0), at(1, 0), at(2, 0)),
            Vec3::new(at(0, 1), at(1, 1), at(2, 1)),
        )
    }

    fn set_child(&mut self, i: usize, b: &Aabb, r: ChildRef) {
        for axis in 0..3 {
            self.planes[axis][0][i] = b.min[axis];
            self.planes[axis][1][i] = b.max[axis];
        }
        self.child[i] = r;
    }

    /// Slots in use: children are packed from slot 0.
    pub fn children(&self) -> usize {
        (0..W)
            .take_while(|&i| self.planes[0][0][i] <= self.planes[0][1][i])
            .count()
    }
}

/// The four lanes `4 * q ..` of a plane row, for one SSE load.
#[inline(always)]
pub(crate) fn quad<const W: usize>(row: &[f32; W], q: usize) -> &[f32; 4] {
    &row.as_chunks::<4>().0[q]
}

/// Which instructions test a wide node and its leaves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NodeSimd {
    /// AVX2 when the CPU has it (run-time detection), SSE otherwise; the batch loops with
    /// AVX-512VL's 32 registers when the CPU has AVX-512F and VL too.
    #[default]
    Auto,
    /// AVX2 when the CPU has it, never AVX-512 (the kernels as they were before `Auto` used
    /// AVX-512's registers, for comparison).
    Avx2,
    /// 4-lane SSE: one pass per axis and four children, one packet of four triangles a pass
    /// (the x86-64 baseline; portable code elsewhere).
    Sse,
}

/// Knobs of a wide BVH: the binary tree it is collapsed from, the node width and the node
/// test.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WideParams {
    pub binary: BvhParams,
    /// Children per node: 8 ([`Bvh8`]) or 4 ([`Bvh4`]); a tree is built only with its own.
    pub width: u32,
    /// The kernels: with AVX2, 8-wide nodes take one 8-lane pass per axis (4-wide ones keep
    /// one 4-lane pass) and leaves are tested two packets a pass.
    pub node_simd: NodeSimd,
    /// Split leaves of more than one packet into the slots a node would leave empty (see
    /// [`collapse`]); off, the wide tree has exactly the binary tree's leaves.
    pub fill_slots: bool,
    /// Batches prepared as coherent (`Accel::prepare_coherent_rays`: the primary rays) are
    /// traced for closest hit sixteen rays at a time, one per AVX-512 lane ([`crate::packet`]),
    /// when the CPU has AVX-512F; every other batch, and every batch without AVX-512, ray by
    /// ray. The registry's `bvh8-packets`.
    pub coherent_packets: bool,
}

impl WideParams {
    /// The defaults for nodes of `width` children.
    pub fn for_width(width: u32) -> WideParams {
        WideParams {
            width,
            ..WideParams::default()
        }
    }
}

impl Default for WideParams {
    fn default() -> Self {
        WideParams {
            // 0.15 per triangle slot: a packet of four costs 0.6 of a wide node test. Embree's
            // BVH8 builder prices a packet like one node test (0.25 here), which was 2–7 %
            // faster than 1 and 8; since the AVX2 leaf test takes two packets a pass, larger
            // leaves pay. Over the 17 scenes of the default suite, against 0.25 (geometric
            // means of best-of-6 passes interleaved in one process, this VM, 2026-11-21):
            // 0.15 primary +3.2 %, random +3.4 %, shadow +2.4 %; 0.125 +2.2–2.9 / +2.6–2.9 /
            // +1.0–1.4 % (two sweeps); 0.1 and 0.18 less; a leaf cap of 12 nothing. Below 0.15
            // the SAH cost with the shared constants (which price every triangle alike)
            // exceeds bvh-binned's on the bunny and the dragon (0.125: 33.4 against 31.3;
            // 0.15: 30.5).
            //
            // Leaves of at most 8 triangles (two packets, one AVX2 leaf pass): with 16, the
            // SAH could stop early where triangles overlap, and on soup and hair the tree's
            // SAH cost with the shared constants came out above bvh-binned's (553.0 against
            // 454.1, 9,658.5 against 9,032.7), which issue 8 rules out. With 8 the 8-wide tree
            // is below bvh-binned on all 17 default scenes (soup 401.9, hair 8,688.9; the
            // bunny 22.5 → 18.7). The price, over the 17 scenes against 16 (best of 6 passes
            // interleaved with embree-medium, this VM, 2026-11-22): primary −1.4 % single-ray
            // and −0.4 % in packets, random −3.0 %, shadow −2.5 %.
            //
            // 64 bins, not bvh-binned's 32: over the 17 default scenes, best of 10 passes
            // interleaved in one process (this VM, 2026-11-21), primary +2.1 % and +1.6 %,
            // random +0.9 % and -0.8 %, shadow +1.8 % and -0.4 % in two sweeps; the steady
            // part is the teapot in the stadium's close-up, +14-17 % on primary rays (its
            // 219,956 centroids spread over the stadium leave the teapot in one bin of 32 for
            // more levels). 128 and 256 bins gained no more.
            //
            // One bin per 4 triangles in a node (bvh-binned keeps one per triangle): the sweep
            // over the boundaries costs per bin, the binning per triangle, and below 256
            // triangles the bins were most of a small node's work. Over the 17 default scenes
            // against one per triangle (best of 6 passes interleaved with embree-medium, two
            // sweeps with the roles swapped, this VM, 2026-11-22): primary −0.4 %, random
            // −0.5 %, shadow −1.0 %, about the noise; one per 8 lost 1.5–2.1 %. The build ran
            // 24 % fewer instructions on the bunny (callgrind; one per 8: 28 %). The SAH cost
            // with the shared constants fell on 13 of the 16 meshes, stayed on the plane and
            // rose on Sibenik (32.14 → 32.24) and hair (8,688.9 → 8,835.1), both still below
            // bvh-binned (47.15, 9,032.7).
            binary: BvhParams {
                bins: 64,
                triangles_per_bin: 4,
                leaf_block: 4,
                intersection_cost: 0.15,
                max_leaf_size: 8,
                ..BvhParams::binned()
            },
            width: MAX_WIDTH as u32,
            node_simd: NodeSimd::Auto,
            fill_slots: true,
            coherent_packets: false,
        }
    }
}

/// A wide BVH of `W`-child nodes. A leaf reference is `{ index: first packet, count:
/// triangles }`; its triangles fill `count.div_ceil(4)` consecutive packets, lane by lane.
#[derive(Debug)]
pub struct BvhWide<const W: usize> {
    params: WideParams,
    nodes: Vec<WideNode<W>>,
    root: ChildRef,
    root_bounds: Aabb,
    /// Leaf triangles, four to a packet, each lane with its mesh index ([`NO_PRIM`] unused).
    packets: Vec<Tri4>,
    /// The mesh as built, for closest-point queries (exact vertices).
    mesh: Arc<TriangleMesh>,
    #[cfg(target_arch = "x86_64")]
    avx2: Option<crate::avx2::Avx2Nodes>,
    /// The packet walk for coherent batches, when asked for and the CPU has AVX-512F.
    #[cfg(target_arch = "x86_64")]
    coherent: Option<crate::packet::Avx512Packets>,
}

/// 8 children per node, tested in one AVX2 pass per axis: the structure that races Embree.
pub type Bvh8 = BvhWide<8>;
/// 4 children per node, tested in one SSE pass per axis: half the node bytes, twice the depth.
pub type Bvh4 = BvhWide<4>;

/// One packet's triangles: the builder's records `refs[start..start + len]`, `len` 1 to 4.
#[derive(Clone, Copy)]
struct PacketSource {
    start: u32,
    len: u32,
}

/// The packets in tree order (see [`number_packets`]), built on rayon: gathering each
/// triangle's vertices from the mesh is the part of the collapse that touches memory at
/// random, and packets are independent. The length is known, so the indexed `collect` writes
/// each packet straight into its place (a `flat_map` over leaves collected through per-task
/// lists and a final copy: about 7 % of the 8-wide build's samples on the sphere, perf with 2
/// threads, this VM, 2026-11-22). The result does not depend on the thread count.
fn pack_leaves(mesh: &TriangleMesh, refs: &[PrimRef], sources: &[PacketSource]) -> Vec<Tri4> {
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

/// What every collapse task reads: the binary tree, the number of triangles under each of its
/// interior nodes (a subtree's triangles are one range of the builder's records), and whether
/// empty slots are filled.
struct Binary<'a> {
    nodes: &'a [Node],
    sizes: Vec<u32>,
    fill_slots: bool,
}

/// Leaves of more triangles than this (one packet) may be split to fill a node's empty slots.
const SPLIT_LEAVES_ABOVE: u32 = 4;

/// Subtrees of at least this many triangles collapse their children's subtrees on rayon.
const PARALLEL_COLLAPSE: usize = 4096;

impl Binary<'_> {
    fn new(nodes: &[Node], fill_slots: bool) -> Binary<'_> {
        let mut sizes = vec![0u32; nodes.len()];
        // Children follow their parent in the depth-first array: fill in sizes bottom-up.
        for i in (0..nodes.len()).rev() {
            sizes[i] = nodes[i]
                .child
                .iter()
                .map(|c| {
                    if c.is_leaf() {
                        c.count
                    } else {
                        sizes[c.index as usize]
                    }
                })
                .sum();
        }
        Binary {
            nodes,
            sizes,
            fill_slots,
        }
    }

    fn size(&self, r: ChildRef) -> usize {
        if r.is_leaf() {
            r.count as usize
        } else {
            self.sizes[r.index as usize] as usize
        }
    }

    /// The children of the wide node made from binary node `r`, whose triangles are `refs`
    /// (the first of them record `start`): starting from its two children, the interior child
    /// with the largest area is opened (first on ties: deterministic) until there are `W` or
    /// only leaves remain; slots still empty are filled by splitting the largest leaves of more
    /// than one packet. Children stay in the order of their triangles.
    fn open<const W: usize>(
        &self,
        refs: &mut [PrimRef],
        start: u32,
        r: ChildRef,
    ) -> ([(ChildRef, Aabb); W], usize) {
        let n = &self.nodes[r.index as usize];
        // A fixed array, not a Vec: one wide node per call, no allocation.
        let mut kids = [(ChildRef::default(), Aabb::EMPTY); W];
        kids[0] = (n.child[0], n.child_bounds(0));
        kids[1] = (n.child[1], n.child_bounds(1));
        let mut len = 2;
        let largest = |kids: &[(ChildRef, Aabb)], openable: &dyn Fn(ChildRef) -> bool| {
            (0..kids.len())
                .filter(|&i| openable(kids[i].0))
                .max_by(|&a, &b| {
                    kids[a]
                        .1
                        .surface_area()
                        .total_cmp(&kids[b].1.surface_area())
                        .then(b.cmp(&a))
                })
        };
        while len < W {
            let two = if let Some(i) = largest(&kids[..len], &|c| !c.is_leaf()) {
                let m = &self.nodes[kids[i].0.index as usize];
                let halves = [
                    (m.child[0], m.child_bounds(0)),
                    (m.child[1], m.child_bounds(1)),
                ];
                (i, halves)
            } else if let Some(i) = largest(&kids[..len], &|c| {
                self.fill_slots && c.is_leaf() && c.count > SPLIT_LEAVES_ABOVE
            }) {
                let leaf = kids[i].0;
                let at = (leaf.index - start) as usize;
                let range = &mut refs[at..at + leaf.count as usize];
                (i, split_leaf(range, leaf.index))
            } else {
                break;
            };
            let (i, [a, b]) = two;
            kids.copy_within(i + 1..len, i + 2);
            kids[i] = a;
            kids[i + 1] = b;
            len += 1;
        }
        (kids, len)
    }
}

/// Splits a leaf's triangles `refs` (the first of them record `first`) in two, forced (as
/// Embree's wide builder splits every child of more than one block until the node is full):
/// sorted by centroid on the axis where the centroids spread most, cut where `area × packets`
/// summed over both halves is least (first on ties). One axis, not three: three sorts made the
/// collapse about a third slower on the bunny for the same speed. Ties in the sort go by mesh
/// index (deterministic).
fn split_leaf(refs: &mut [PrimRef], first: u32) -> [(ChildRef, Aabb); 2] {
    let spread = refs
        .iter()
        .fold(Box3::EMPTY, |b, p| b.grow(p.centroid2()))
        .extent();
    let axis = spread.max_position();
    refs.sort_unstable_by(|a, b| {
        a.centroid2_on(axis)
            .total_cmp(&b.centroid2_on(axis))
            .then(a.id().cmp(&b.id()))
    });
    let packets = |k: usize| k.div_ceil(4) as f64;
    let n = refs.len();
    // The boxes of the right-hand halves `refs[k..]`, on the stack for the usual leaf sizes.
    let (mut small, mut large) = ([Box3::EMPTY; 32], Vec::new());
    let right: &mut [Box3] = if n <= small.len() {
        &mut small[..n]
    } else {
        large.resize(n, Box3::EMPTY);
        &mut large
    };
    let mut acc = Box3::EMPTY;
    for k in (1..n).rev() {
        acc = acc.union(&refs[k].bounds());
        right[k] = acc;
    }
    let (mut best, mut cut, mut left) = (f64::INFINITY, 1, Box3::EMPTY);
    let mut acc = Box3::EMPTY;
    for k in 1..n {
        acc = acc.union(&refs[k - 1].bounds());
        let cost = acc.half_area() * packets(k) + right[k].half_area() * packets(n - k);
        if cost < best {
            (best, cut, left) = (cost, k, acc);
        }
    }
    let leaf = |index: usize, count: usize, b: Box3| {
        let r = ChildRef {
            index: first + index as u32,
            count: count as u32,
        };
        (r, b.to_aabb())
    };
    [leaf(0, cut, left), leaf(cut, n - cut, right[cut])]
}

/// Collapses the binary subtree `r`, whose triangles are `refs` (the first of them record
/// `start`), into wide nodes appended to `out` depth-first. Leaves stay triangle ranges
/// (`{ index: first record, count }`) until [`number_packets`]. A subtree of
/// [`PARALLEL_COLLAPSE`] triangles or more collapses its children on rayon, each into a
/// vector of its own, appended in slot order afterwards: the same nodes in the same order as
/// one thread makes them.
fn collapse<const W: usize>(
    b: &Binary,
    refs: &mut [PrimRef],
    start: u32,
    r: ChildRef,
    out: &mut Vec<WideNode<W>>,
) -> ChildRef {
    if r.is_leaf() {
        return r;
    }
    let parallel = refs.len() >= PARALLEL_COLLAPSE;
    let (kids, len) = b.open::<W>(refs, start, r);
    let at = out.len();
    out.push(WideNode::empty());
    // The children's triangles are consecutive ranges of `refs`, in slot order.
    let mut jobs = Vec::with_capacity(len);
    let (mut rest, mut first) = (refs, start);
    for &(child, _) in &kids[..len] {
        let size = b.size(child);
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size);
        debug_assert!(!child.is_leaf() || child.index == first);
        jobs.push((child, mine, first));
        rest = tail;
        first += size as u32;
    }
    if parallel {
        use rayon::prelude::*;
        let parts: Vec<(ChildRef, Vec<WideNode<W>>)> = jobs
            .into_par_iter()
            .map(|(child, mine, first)| {
                let mut local = Vec::new();
                let r = collapse(b, mine, first, child, &mut local);
                (r, local)
            })
            .collect();
        for (slot, (r, local)) in parts.into_iter().enumerate() {
            let r = append_part(out, r, local);
            out[at].set_child(slot, &kids[slot].1, r);
        }
    } else {
        for (slot, (child, mine, first)) in jobs.into_iter().enumerate() {
            let r = collapse(b, mine, first, child, out);
            out[at].set_child(slot, &kids[slot].1, r);
        }
    }
    ChildRef {
        index: at as u32,
        count: 0,
    }
}

/// Appends a subtree collapsed into a vector of its own (interior references local to it) to
/// `out`, and returns the reference to its root there.
fn append_part<const W: usize>(
    out: &mut Vec<WideNode<W>>,
    r: ChildRef,
    local: Vec<WideNode<W>>,
) -> ChildRef {
    if r.is_leaf() {
        return r;
    }
    let base = out.len() as u32;
    out.extend(local.into_iter().map(|mut node| {
        let used = node.children();
        for c in node.child[..used].iter_mut().filter(|c| !c.is_leaf()) {
            c.index += base;
        }
        node
    }));
    ChildRef {
        index: base + r.index,
        count: 0,
    }
}

/// Turns every leaf reference of the collapsed tree from a triangle range into its packets
/// (`{ index: first packet, count: triangles }`), numbered in depth-first order, which is the
/// order of the triangles; returns where each packet's triangles are, in that order.
fn number_packets<const W: usize>(
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

impl<const W: usize> BvhWide<W> {
    pub fn nodes(&self) -> &[WideNode<W>] {
        &self.nodes
    }

    /// The root: a node, or a leaf when the tree is a single leaf.
    pub(crate) fn root(&self) -> ChildRef {
        self.root
    }

    /// The leaves' triangle packets, in depth-first order.
    pub fn packets(&self) -> &[Tri4] {
        &self.packets
    }

    /// The parts the closest-point walk reads (`point.rs`).
    pub(crate) fn point_view(&self) -> crate::point::WideView<'_, W> {
        crate::point::WideView {
            root: self.root,
            root_bounds: &self.root_bounds,
            nodes: &self.nodes,
            packets: &self.packets,
            mesh: &self.mesh,
        }
    }

    pub fn params(&self) -> &WideParams {
        &self.params
    }

    /// The mesh index of every packet lane in order (`4 * packet + lane`), [`NO_PRIM`] for
    /// unused lanes.
    fn lane_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.packets.iter().flat_map(|p| p.ids)
    }

    /// Whether the AVX2 kernels test nodes and leaves (else SSE).
    pub fn uses_avx2(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.avx2.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// Whether coherent batches are traced in packets (`coherent_packets` asked for it and the
    /// CPU has AVX-512F).
    pub fn packet_walk(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.coherent.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// Whether the batch loops run with AVX-512VL's 32 vector registers (same arithmetic).
    pub fn avx512_registers(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.avx2.is_some_and(|k| k.wide_registers());
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// Every child box inside its parent's; leaves tiling the packets in depth-first order,
    /// their triangles in the first lanes and the rest empty; every lane equal to its mesh
    /// triangle; every mesh triangle exactly once; depth within the stack bound.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let n = mesh.len();
        self.check_lanes(mesh)?;
        if n == 0 {
            return Ok(());
        }
        let (mut covered, mut interior) = (0, 0);
        self.walk(
            mesh,
            self.root,
            &self.root_bounds,
            0,
            &mut covered,
            &mut interior,
        )?;
        if covered != self.packets.len() || interior != self.nodes.len() {
            return Err(format!(
                "leaves hold {covered} of {} packets; {interior} of {} nodes reachable",
                self.packets.len(),
                self.nodes.len()
            ));
        }
        Ok(())
    }

    /// Every used lane is its mesh triangle, every mesh triangle is in exactly one lane, and
    /// unused lanes are the all-zero triangle.
    fn check_lanes(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let mut seen = vec![false; mesh.len()];
        for (slot, id) in self.lane_ids().enumerate() {
            let lane = self.packets[slot / 4].lane(slot % 4);
            if id == NO_PRIM {
                if lane != Tri4::default().lane(0) {
                    return Err(format!("unused lane {slot} holds a triangle"));
                }
                continue;
            }
            let s = seen
                .get_mut(id as usize)
                .ok_or(format!("prim id {id} out of range"))?;
            if std::mem::replace(s, true) {
                return Err(format!("prim id {id} appears twice"));
            }
            if lane != MollerTriangle::new(&mesh.triangle(id as usize)) {
                return Err(format!("lane {slot} is not mesh triangle {id}"));
            }
        }
        match seen.iter().position(|&s| !s) {
            Some(missing) => Err(format!("mesh triangle {missing} is in no leaf")),
            None => Ok(()),
        }
    }

    fn walk(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        bounds: &Aabb,
        depth: usize,
        covered: &mut usize,
        interior: &mut usize,
    ) -> Result<(), String> {
        if depth >= MAX_DEPTH {
            return Err(format!("depth {depth} exceeds {MAX_DEPTH}"));
        }
        if r.is_leaf() {
            return self.walk_leaf(mesh, r, bounds, covered);
        }
        if r.index as usize != *interior {
            return Err(format!("node {} out of depth-first order", r.index));
        }
        *interior += 1;
        let node = self
            .nodes
            .get(r.index as usize)
            .ok_or("node index out of range")?;
        let used = node.children();
        if used < 2 {
            return Err(format!("node {} has {used} children", r.index));
        }
        for i in 0..W {
            let child = node.child_bounds(i);
            if i >= used {
                if !child.is_empty() {
                    return Err(format!("node {} has a box in unused slot {i}", r.index));
                }
                continue;
            }
            if !bounds.contains_box(&child) {
                return Err(format!(
                    "child {i} of node {} is not inside its parent",
                    r.index
                ));
            }
            self.walk(mesh, node.child[i], &child, depth + 1, covered, interior)?;
        }
        Ok(())
    }
}

impl<const W: usize> BvhWide<W> {
    /// A leaf: at the next packet in depth-first order, `count` used lanes followed by unused
    /// ones, every triangle inside the leaf's box.
    fn walk_leaf(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        bounds: &Aabb,
        covered: &mut usize,
    ) -> Result<(), String> {
        if r.index as usize != *covered {
            return Err(format!("leaf at packet {}, expected {covered}", r.index));
        }
        let packets = (r.count as usize).div_ceil(4);
        let first = r.index as usize;
        let leaf = self
            .packets
            .get(first..first + packets)
            .ok_or("leaf runs past the packets")?;
        for (k, &id) in leaf.iter().flat_map(|p| &p.ids).enumerate() {
            if (k < r.count as usize) != (id != NO_PRIM) {
                return Err(format!("leaf at packet {} has lane {k} misused", r.index));
            }
            if id != NO_PRIM && !bounds.contains_box(&mesh.triangle(id as usize).bounds()) {
                return Err(format!("leaf box does not contain triangle {id}"));
            }
        }
        *covered += packets;
        Ok(())
    }
}

/// One wide-node slab test: entry distances of all 8 children and the mask of those entered
/// within `[t_min, t_max]`. Implementations compute the scalar slab test's arithmetic lane for
/// lane, so every kernel answers alike; a NaN (`0 * inf`, a ray in a box's face plane) is
/// ignored because the `max`/`min` keep the accumulator (bug class B1).
pub(crate) trait NodeKernel<const W: usize>: Copy {
    type Ray;
    fn ray(self, ray: &Ray) -> Self::Ray;
    fn test(self, ray: &Self::Ray, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]);
    /// The packets of one leaf (the first is packet `first` of the tree) against the ray below
    /// `*best_t`, exactly as [`intersect_packets`] does it; true when an any-hit query may stop.
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &Self::Ray,
        packets: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool;
}

/// The baseline kernel: one 4-lane pass per axis and four children (SSE on x86-64, portable
/// elsewhere).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SseNodes;

/// The ray as [`SseNodes`] needs it: the ray itself (for the leaves' [`Tri4`] tests), its
/// origin and inverse direction splatted, and per axis which stored side (min or max) holds
/// the near planes.
pub(crate) struct WideRay {
    ray: Ray,
    origin: [F4; 3],
    inv: [F4; 3],
    near: [bool; 3],
}

impl<const W: usize> NodeKernel<W> for SseNodes {
    type Ray = WideRay;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> WideRay {
        let inv = ray.inv_dir().to_array();
        WideRay {
            inv: inv.map(F4::splat),
            // -0 counts as negative: its inverse is -inf (bug class B3).
            near: inv.map(|x| x.is_sign_negative()),
            origin: ray.origin().to_array().map(F4::splat),
            ray: *ray,
        }
    }

    #[inline(always)]
    fn leaf<const ANY_HIT: bool>(
        self,
        ray: &WideRay,
        packets: &[Tri4],
        first: usize,
        best_t: &mut f32,
        best: &mut Option<(usize, TriHit)>,
    ) -> bool {
        intersect_packets::<ANY_HIT>(packets, first, &ray.ray, best_t, best)
    }

    #[inline(always)]
    fn test(self, r: &WideRay, n: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        slab_quads(&r.origin, &r.inv, r.near, n, t_min, t_max)
    }
}

/// The slab test of a node's children four lanes a pass, for a ray splatted as `origin` and
/// `inv` whose near planes lie on the sides `near` (the SSE kernel, and the AVX2 kernel's
/// 4-wide nodes).
#[inline(always)]
pub(crate) fn slab_quads<const W: usize>(
    origin: &[F4; 3],
    inv: &[F4; 3],
    near: [bool; 3],
    n: &WideNode<W>,
    t_min: f32,
    t_max: f32,
) -> (u32, [f32; W]) {
    let mut mask = 0;
    let mut entry = [0.0; W];
    for q in 0..W / 4 {
        let mut t0 = F4::splat(t_min);
        let mut t1 = F4::splat(t_max);
        for a in 0..3 {
            let near_planes = F4::load(quad(&n.planes[a][near[a] as usize], q));
            let far_planes = F4::load(quad(&n.planes[a][!near[a] as usize], q));
            t0 = near_planes.sub(origin[a]).mul(inv[a]).max_keep(t0);
            t1 = far_planes.sub(origin[a]).mul(inv[a]).min_keep(t1);
        }
        mask |= t0.le_mask(t1) << (4 * q);
        entry[4 * q..4 * q + 4].copy_from_slice(&t0.to_array());
    }
    (mask, entry)
}

type Entry = (ChildRef, f32);

/// A traversal stack: subtrees still to visit with their entry distances.
pub(crate) type Stack = [Entry; STACK];

pub(crate) fn new_stack() -> Box<Stack> {
    Box::new([(ChildRef::default(), 0.0); STACK])
}

thread_local! {
    /// The single-ray paths' traversal stack, allocated once per thread.
    static STACK_TLS: RefCell<Box<Stack>> = RefCell::new(new_stack());
}

/// Any hit will do, so no sorting (as Embree's occlusion traversal): returns the child in the
/// lowest slot of `mask` and pushes the others to pop in slot order. Their entry distances are
/// not kept: an any-hit walk ends at its first hit, so `t_max` never shrinks and no pushed
/// subtree is ever skipped (the pop does not look at them either).
#[inline(always)]
fn first_in_slot_order<const W: usize>(
    n: &WideNode<W>,
    mask: u32,
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    let first = mask.trailing_zeros() as usize;
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        let i = 31 - rest.leading_zeros() as usize;
        rest &= !(1 << i);
        stack[*sp] = (n.child[i], 0.0);
        *sp += 1;
    }
    n.child[first]
}

/// Of the children of `n` in `mask` (entry distances `entry`), returns the nearest and pushes
/// the others so that they pop nearest first (equal distances: lower slot first). One and two
/// children — most nodes — take a short path; more are inserted into the stack in place.
#[inline(always)]
fn nearest_first<const W: usize>(
    n: &WideNode<W>,
    mut mask: u32,
    entry: &[f32; W],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    let a = mask.trailing_zeros() as usize;
    mask &= mask - 1;
    if mask == 0 {
        return n.child[a];
    }
    let b = mask.trailing_zeros() as usize;
    mask &= mask - 1;
    if mask == 0 {
        let (near, far) = if entry[b] < entry[a] { (b, a) } else { (a, b) };
        stack[*sp] = (n.child[far], entry[far]);
        *sp += 1;
        return n.child[near];
    }
    // Three or more: keep stack[base..] in decreasing distance, the nearest on top; a later
    // (higher) slot goes below earlier slots at the same distance.
    let base = *sp;
    let mut insert = |i: usize| {
        let e = (n.child[i], entry[i]);
        let mut j = *sp;
        while j > base && stack[j - 1].1 <= e.1 {
            stack[j] = stack[j - 1];
            j -= 1;
        }
        stack[j] = e;
        *sp += 1;
    };
    insert(a);
    insert(b);
    while mask != 0 {
        insert(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
    *sp -= 1;
    stack[*sp].0
}

/// Tests a leaf's packets (the first is packet `first` of the tree) one after the other below
/// `*best_t`, keeping the closest hit (as a lane index `4 * packet + lane`); true when an
/// any-hit query may stop. A later packet's lane replaces the best hit so far when its
/// window test `t <= best_t` passes, so on an exact tie the later packet wins.
#[inline(always)]
pub(crate) fn intersect_packets<const ANY_HIT: bool>(
    packets: &[Tri4],
    first: usize,
    ray: &Ray,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
) -> bool {
    for (k, packet) in packets.iter().enumerate() {
        if let Some((lane, h)) = packet.intersect(ray, *best_t) {
            *best_t = h.t;
            *best = Some((4 * (first + k) + lane, h));
            if ANY_HIT {
                return true;
            }
        }
    }
    false
}

impl<const W: usize> BvhWide<W> {
    /// The one traversal loop — closest or any hit, counted or not — for a given node
    /// kernel. `stack` is scratch space, so batch callers reuse one allocation for all their
    /// rays. There is no separate test of the root box: the root node's test covers it.
    #[inline(always)]
    pub(crate) fn walk_with<const ANY_HIT: bool, C: CounterSink, K: NodeKernel<W>>(
        &self,
        kernel: K,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        if self.packets.is_empty() {
            return None;
        }
        let t_min = ray.t_min();
        let mut best_t = ray.t_max();
        let wide = kernel.ray(ray);
        let mut best: Option<(usize, TriHit)> = None;
        let mut sp = 0;
        let mut r = self.root;
        'walk: loop {
            if r.is_leaf() {
                c.leaf();
                c.prim_tests(r.count as u64);
                let first = r.index as usize;
                let leaf = &self.packets[first..first + (r.count as usize).div_ceil(4)];
                if kernel.leaf::<ANY_HIT>(&wide, leaf, first, &mut best_t, &mut best) {
                    break 'walk;
                }
            } else {
                c.node();
                let n = &self.nodes[r.index as usize];
                let (mask, entry) = kernel.test(&wide, n, t_min, best_t);
                if mask != 0 {
                    self.prefetch_children(n, mask);
                    r = if ANY_HIT {
                        first_in_slot_order(n, mask, stack, &mut sp)
                    } else {
                        nearest_first(n, mask, &entry, stack, &mut sp)
                    };
                    continue 'walk;
                }
            }
            // Pop the nearest pushed subtree that may still hold a closer hit.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let (next, t_entry) = stack[sp];
                if ANY_HIT || t_entry <= best_t {
                    r = next;
                    continue 'walk;
                }
            }
        }
        best.map(|(lane, h)| Hit {
            t: h.t,
            prim: self.packets[lane / 4].ids[lane % 4],
            u: h.u,
            v: h.v,
        })
    }

    /// Starts fetching every child in `mask`: a node's four (8 wide) or two (4 wide) lines, or
    /// a leaf's first packet (three lines).
    #[inline(always)]
    fn prefetch_children(&self, n: &WideNode<W>, mut mask: u32) {
        while mask != 0 {
            let r = n.child[mask.trailing_zeros() as usize];
            mask &= mask - 1;
            if r.is_leaf() {
                prefetch(self.packets.as_ptr().wrapping_add(r.index as usize));
            } else {
                prefetch(self.nodes.as_ptr().wrapping_add(r.index as usize));
            }
        }
    }

    /// [`BvhWide::walk_with`] with the kernel chosen at build time.
    #[inline(always)]
    fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            return crate::avx2::walk_ray::<W, ANY_HIT, C>(self, k, ray, stack, c);
        }
        self.walk_with::<ANY_HIT, C, SseNodes>(SseNodes, ray, stack, c)
    }

    fn trace_single<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        STACK_TLS.with(|s| self.trace::<ANY_HIT, C>(ray, &mut s.borrow_mut(), c))
    }
}

impl<const W: usize> Accel for BvhWide<W> {
    type Params = WideParams;

    fn build(mesh: Arc<TriangleMesh>, params: &WideParams) -> Result<BvhWide<W>, BuildError> {
        if W > MAX_WIDTH || !W.is_multiple_of(4) {
            return Err(BuildError::Unsupported(format!(
                "a {W}-wide BVH (4 or 8 children: the SIMD node tests take four lanes at a time \
                 and the stacks hold {MAX_WIDTH})"
            )));
        }
        if params.width as usize != W {
            return Err(BuildError::Unsupported(format!(
                "width {} in a {W}-wide BVH",
                params.width
            )));
        }
        let mut flat = build::build(&mesh, &params.binary)?;
        let mut nodes = Vec::with_capacity(flat.nodes.len() / 3 + 1);
        // The collapse leaves the leaves as triangle ranges; their packets are numbered
        // afterwards and filled in parallel.
        let (root, leaves) = if flat.refs.is_empty() {
            (ChildRef::default(), Vec::new())
        } else {
            let binary = Binary::new(&flat.nodes, params.fill_slots);
            let mut root = collapse(&binary, &mut flat.refs, 0, flat.root, &mut nodes);
            let leaves = number_packets(&mut nodes, &mut root);
            (root, leaves)
        };
        let packets = pack_leaves(&mesh, &flat.refs, &leaves);
        Ok(BvhWide {
            params: params.clone(),
            nodes,
            root,
            root_bounds: flat.root_bounds,
            packets,
            mesh,
            #[cfg(target_arch = "x86_64")]
            avx2: match params.node_simd {
                NodeSimd::Auto => crate::avx2::Avx2Nodes::detect(true),
                NodeSimd::Avx2 => crate::avx2::Avx2Nodes::detect(false),
                NodeSimd::Sse => None,
            },
            #[cfg(target_arch = "x86_64")]
            coherent: params
                .coherent_packets
                .then(crate::packet::Avx512Packets::detect)
                .flatten(),
        })
    }

    fn name(&self) -> &str {
        match (W, self.params.coherent_packets) {
            (4, false) => "bvh4-binned",
            (4, true) => "bvh4-packets",
            (_, false) => "bvh8-binned",
            (_, true) => "bvh8-packets",
        }
    }

    raybench_accel::walk_queries!();

    /// With the packet walk, the rays are laid out in packets of sixteen, structure of arrays
    /// (as Embree's stream takes `RTCRayHit`s, converted outside timing); without it, as they
    /// are.
    fn prepare_coherent_rays(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
        #[cfg(target_arch = "x86_64")]
        if self.coherent.is_some() {
            let packets = crate::packet::RayPackets::new(rays);
            return Ok(PreparedRays::Foreign(Box::new(packets)));
        }
        Ok(PreparedRays::Native)
    }

    fn intersect_prepared(
        &self,
        rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let (Some(k), PreparedRays::Foreign(any)) = (self.coherent, prepared)
            && let Some(packets) = any.downcast_ref::<crate::packet::RayPackets>()
            && let Some(packets) = packets.range(first, out.len())
        {
            return crate::packet::intersect_coherent(k, self, packets, out);
        }
        let mut stack = new_stack();
        let rays = &rays[first..];
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            return crate::avx2::intersect_all(self, k, rays, out, &mut stack);
        }
        for (o, ray) in out.iter_mut().zip(rays) {
            *o = self.trace::<false, _>(ray, &mut stack, &mut NoCount);
        }
    }

    fn occluded_prepared(&self, rays: &[Ray], _: &PreparedRays, first: usize, out: &mut [bool]) {
        let mut stack = new_stack();
        let rays = &rays[first..];
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            return crate::avx2::occluded_all(self, k, rays, out, &mut stack);
        }
        for (o, ray) in out.iter_mut().zip(rays) {
            *o = self
                .trace::<true, _>(ray, &mut stack, &mut NoCount)
                .is_some();
        }
    }

    fn build_stats(&self) -> BuildStats {
        self.measure()
    }

    fn memory(&self) -> Memory {
        Memory {
            nodes: std::mem::size_of_val(self.nodes.as_slice()) as u64,
            // Triangle ids live in the packets.
            indices: 0,
            primitives: std::mem::size_of_val(self.packets.as_slice()) as u64,
        }
    }
}

impl<const W: usize> BvhWide<W> {
    /// Shape and SAH cost of the wide tree (a wide node costs one traversal step: one SIMD
    /// node test), with the constants shared by every structure.
    fn measure(&self) -> BuildStats {
        let mut s = BuildStats::default();
        if self.packets.is_empty() {
            return s;
        }
        let root_area = self.root_bounds.surface_area();
        let mut sah = 0.0;
        let mut children = 0u64;
        let mut stack = vec![(self.root, self.root_bounds, 0u32)];
        while let Some((r, b, depth)) = stack.pop() {
            s.max_depth = s.max_depth.max(depth);
            let area = if root_area > 0.0 {
                b.surface_area() / root_area
            } else {
                0.0
            };
            if r.is_leaf() {
                s.leaves += 1;
                s.refs += r.count as u64;
                sah += area * SAH_INTERSECTION_COST * r.count as f64;
            } else {
                s.nodes += 1;
                sah += area * SAH_TRAVERSAL_COST;
                let n = &self.nodes[r.index as usize];
                children += n.children() as u64;
                for i in 0..n.children() {
                    stack.push((n.child[i], n.child_bounds(i), depth + 1));
                }
            }
        }
        s.extra.insert(
            "mean_children".into(),
            children as f64 / s.nodes.max(1) as f64,
        );
        s.extra.insert(
            "mean_leaf_size".into(),
            s.refs as f64 / s.leaves.max(1) as f64,
        );
        s.extra.insert(
            "packet_fill".into(),
            s.refs as f64 / (4 * self.packets.len()).max(1) as f64,
        );
        s.extra
            .insert("avx2_kernels".into(), self.uses_avx2() as u8 as f64);
        s.extra.insert(
            "avx512_registers".into(),
            self.avx512_registers() as u8 as f64,
        );
        s.nodes += s.leaves;
        s.sah_cost = (root_area > 0.0).then_some(sah);
        s
    }
}

impl<const W: usize> Walk for BvhWide<W> {
    fn walk_ray<const ANY_HIT: bool, C: CounterSink>(&self, ray: &Ray, c: &mut C) -> Option<Hit> {
        self.trace_single::<ANY_HIT, C>(ray, c)
    }

    fn walk_point<C: CounterSink>(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut C,
    ) -> Option<raybench_accel::PointHit> {
        crate::point::closest_point_wide(&self.point_view(), p, max_radius, c)
    }
}
