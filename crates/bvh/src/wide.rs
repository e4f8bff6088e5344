//! An 8-wide BVH collapsed from the binary SAH tree, traversed with one SIMD box test per node
//! (the first step of issue 8; see the README for where it stands against Embree).
//!
//! Collapse (as in Wald et al. 2008, "Getting rid of packets", and Embree's BVH8 builders):
//! each wide node starts from a binary node's two children and repeatedly opens the child with
//! the largest surface area — the one a ray is most likely to enter — until it has 8 children
//! or only leaves remain. Leaves are the binary tree's leaves, unchanged. The wide tree has a
//! third of the binary tree's depth, so a ray walks fewer, wider nodes: fewer dependent memory
//! fetches, each testing up to 8 boxes in two 4-lane SSE passes per axis.
//!
//! Traversal is ordered: the children a ray enters are sorted by entry distance, the farther
//! ones pushed with that distance and skipped when popped beyond the closest hit.
//!
//! Leaves are SIMD packets ([`Tri4`]): the binary builder prices a leaf by the packets of four
//! it fills (`leaf_block = 4`), and one SSE Möller–Trumbore test answers for four triangles.
//! The node test runs in one 8-lane AVX2 pass per axis when the CPU has AVX2 (detected at build
//! time, [`crate::avx2`]) and in two 4-lane SSE passes otherwise; both are the scalar slab test
//! lane for lane and pass the same conformance tests.

use crate::BvhParams;
use crate::build;
use crate::node::{ChildRef, MAX_DEPTH, Node};
use crate::simd::F4;
use crate::tri4::{NO_PRIM, Ray4, Tri4};
use raybench_accel::{
    Accel, BuildError, BuildStats, CounterSink, Counters, Hit, Memory, NoCount, PreparedRays,
    SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST,
};
use raybench_geom::{Aabb, MollerTriangle, Ray, TriHit, TriangleMesh, Vec3};
use serde::Serialize;
use std::cell::RefCell;
use std::sync::Arc;

/// Children per wide node.
pub const WIDTH: usize = 8;

/// Stack entries a walk can need: a node pushes at most `WIDTH - 1`, one per level, and the
/// binary builder caps the depth at [`MAX_DEPTH`] (collapsing only shortens it).
const STACK: usize = (WIDTH - 1) * MAX_DEPTH + 1;

/// One wide node: 256 bytes, four cache lines. Child boxes per axis as `[min or max][half]`
/// of 4 lanes; unused slots hold an empty box (`min = +inf`, `max = -inf`) that no ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node8 {
    /// `[axis][0 = min, 1 = max][half][lane]`, child `4 * half + lane`.
    pub planes: [[[[f32; 4]; 2]; 2]; 3],
    pub child: [ChildRef; WIDTH],
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);

impl Node8 {
    fn empty() -> Node8 {
        let mut planes = [[[[0.0; 4]; 2]; 2]; 3];
        for axis in &mut planes {
            axis[0] = [[f32::INFINITY; 4]; 2];
            axis[1] = [[f32::NEG_INFINITY; 4]; 2];
        }
        Node8 {
            planes,
            child: [ChildRef::default(); WIDTH],
        }
    }

    pub fn child_bounds(&self, i: usize) -> Aabb {
        let at = |axis: usize, side: usize| self.planes[axis][side][i / 4][i % 4];
        Aabb::new(
            Vec3::new(at(0, 0), at(1, 0), at(2, 0)),
            Vec3::new(at(0, 1), at(1, 1), at(2, 1)),
        )
    }

    fn set_child(&mut self, i: usize, b: &Aabb, r: ChildRef) {
        for axis in 0..3 {
            self.planes[axis][0][i / 4][i % 4] = b.min[axis];
            self.planes[axis][1][i / 4][i % 4] = b.max[axis];
        }
        self.child[i] = r;
    }

    /// Slots in use: children are packed from slot 0.
    pub fn children(&self) -> usize {
        (0..WIDTH)
            .take_while(|&i| self.planes[0][0][i / 4][i % 4] <= self.planes[0][1][i / 4][i % 4])
            .count()
    }
}

/// Which instructions test a wide node.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NodeSimd {
    /// AVX2 when the CPU has it (run-time detection), SSE otherwise.
    #[default]
    Auto,
    /// Two 4-lane SSE passes per axis (the x86-64 baseline; portable code elsewhere).
    Sse,
}

/// Knobs of the wide BVH: the binary tree it is collapsed from, and the node test.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bvh8Params {
    pub binary: BvhParams,
    pub width: u32,
    pub node_simd: NodeSimd,
}

impl Default for Bvh8Params {
    fn default() -> Self {
        Bvh8Params {
            // A packet test costs about one wide node test, as Embree's BVH8 builder prices
            // them (intersection cost 1 per block of 4, traversal cost 1): 0.25 per triangle
            // slot. Leaves of up to 16 (four packets) let the SAH stop early where triangles
            // overlap. Against cost 1 and 8: 2–7 % faster primary, random and shadow rays on
            // the bunny and conference and 10 % faster builds (this VM, 2026-11-21, best of 15
            // passes interleaved with embree-medium, under load, so ±5 %).
            binary: BvhParams {
                leaf_block: 4,
                intersection_cost: 0.25,
                max_leaf_size: 16,
                ..BvhParams::binned()
            },
            width: WIDTH as u32,
            node_simd: NodeSimd::Auto,
        }
    }
}

/// A wide BVH. A leaf reference is `{ index: first packet, count: triangles }`; its triangles
/// fill `count.div_ceil(4)` consecutive packets, lane by lane.
#[derive(Debug)]
pub struct Bvh8 {
    params: Bvh8Params,
    nodes: Vec<Node8>,
    root: ChildRef,
    root_bounds: Aabb,
    /// Leaf triangles, four to a packet, each lane with its mesh index ([`NO_PRIM`] unused).
    packets: Vec<Tri4>,
    /// The mesh as built, for closest-point queries (exact vertices).
    mesh: Arc<TriangleMesh>,
    #[cfg(target_arch = "x86_64")]
    avx2: Option<crate::avx2::Avx2Nodes>,
}

/// Appends the packets of one binary leaf (mesh triangles `ids`) and returns its wide reference.
fn pack_leaf(mesh: &TriangleMesh, ids: &[u32], packets: &mut Vec<Tri4>) -> ChildRef {
    let index = packets.len() as u32;
    for chunk in ids.chunks(4) {
        let mut packet = Tri4::default();
        for (lane, &i) in chunk.iter().enumerate() {
            packet.set_lane(lane, i, &MollerTriangle::new(&mesh.triangle(i as usize)));
        }
        packets.push(packet);
    }
    ChildRef {
        index,
        count: ids.len() as u32,
    }
}

/// Collapses the binary subtree `r` into wide nodes appended to `out` depth-first; `leaf`
/// turns each binary leaf into its wide reference, in depth-first order.
fn collapse(
    binary: &[Node],
    r: ChildRef,
    out: &mut Vec<Node8>,
    leaf: &mut impl FnMut(ChildRef) -> ChildRef,
) -> ChildRef {
    if r.is_leaf() {
        return leaf(r);
    }
    let n = &binary[r.index as usize];
    let mut kids: Vec<(ChildRef, Aabb)> = vec![
        (n.child[0], n.child_bounds(0)),
        (n.child[1], n.child_bounds(1)),
    ];
    while kids.len() < WIDTH {
        // Open the interior child with the largest area (first such on ties: deterministic).
        let Some(i) = (0..kids.len())
            .filter(|&i| !kids[i].0.is_leaf())
            .max_by(|&a, &b| {
                kids[a]
                    .1
                    .surface_area()
                    .total_cmp(&kids[b].1.surface_area())
                    .then(b.cmp(&a))
            })
        else {
            break;
        };
        let m = &binary[kids[i].0.index as usize];
        kids[i] = (m.child[0], m.child_bounds(0));
        kids.insert(i + 1, (m.child[1], m.child_bounds(1)));
    }
    let at = out.len();
    out.push(Node8::empty());
    for (slot, (child, bounds)) in kids.iter().enumerate() {
        let r = collapse(binary, *child, out, leaf);
        out[at].set_child(slot, bounds, r);
    }
    ChildRef {
        index: at as u32,
        count: 0,
    }
}

impl Bvh8 {
    pub fn nodes(&self) -> &[Node8] {
        &self.nodes
    }

    /// The parts the closest-point walk reads (`point.rs`).
    pub(crate) fn point_view(&self) -> crate::point::WideView<'_> {
        crate::point::WideView {
            root: self.root,
            root_bounds: &self.root_bounds,
            nodes: &self.nodes,
            packets: &self.packets,
            mesh: &self.mesh,
        }
    }

    pub fn params(&self) -> &Bvh8Params {
        &self.params
    }

    /// The mesh index of every packet lane in order (`4 * packet + lane`), [`NO_PRIM`] for
    /// unused lanes.
    fn lane_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.packets.iter().flat_map(|p| p.ids)
    }

    /// Whether nodes are tested with the AVX2 kernel (else SSE).
    pub fn uses_avx2(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return self.avx2.is_some();
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
        for i in 0..WIDTH {
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

impl Bvh8 {
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
pub(crate) trait NodeKernel: Copy {
    type Ray;
    fn ray(self, ray: &Ray) -> Self::Ray;
    fn test(self, ray: &Self::Ray, n: &Node8, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);
}

/// The baseline kernel: two 4-lane passes per axis (SSE on x86-64, portable elsewhere).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SseNodes;

/// The ray as [`SseNodes`] needs it: origin and inverse direction splatted, and per axis which
/// stored side (min or max) holds the near planes.
pub(crate) struct WideRay {
    origin: [F4; 3],
    inv: [F4; 3],
    near: [bool; 3],
}

impl NodeKernel for SseNodes {
    type Ray = WideRay;

    #[inline(always)]
    fn ray(self, ray: &Ray) -> WideRay {
        let inv = ray.inv_dir().to_array();
        WideRay {
            origin: ray.origin().to_array().map(F4::splat),
            inv: inv.map(F4::splat),
            // -0 counts as negative: its inverse is -inf (bug class B3).
            near: inv.map(|x| x.is_sign_negative()),
        }
    }

    #[inline(always)]
    fn test(self, r: &WideRay, n: &Node8, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut entry = [0.0; WIDTH];
        for half in 0..2 {
            let mut t0 = F4::splat(t_min);
            let mut t1 = F4::splat(t_max);
            for a in 0..3 {
                let near = F4::load(&n.planes[a][r.near[a] as usize][half]);
                let far = F4::load(&n.planes[a][!r.near[a] as usize][half]);
                t0 = near.sub(r.origin[a]).mul(r.inv[a]).max_keep(t0);
                t1 = far.sub(r.origin[a]).mul(r.inv[a]).min_keep(t1);
            }
            mask |= t0.le_mask(t1) << (4 * half);
            entry[4 * half..4 * half + 4].copy_from_slice(&t0.to_array());
        }
        (mask, entry)
    }
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
/// lowest slot of `mask` and pushes the others to pop in slot order.
#[inline(always)]
fn first_in_slot_order(
    n: &Node8,
    mask: u32,
    entry: &[f32; WIDTH],
    stack: &mut Stack,
    sp: &mut usize,
) -> ChildRef {
    let first = mask.trailing_zeros() as usize;
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        let i = 31 - rest.leading_zeros() as usize;
        rest &= !(1 << i);
        stack[*sp] = (n.child[i], entry[i]);
        *sp += 1;
    }
    n.child[first]
}

/// Of the children of `n` in `mask` (entry distances `entry`), returns the nearest and pushes
/// the others so that they pop nearest first (equal distances: lower slot first). One and two
/// children — most nodes — take a short path; more are inserted into the stack in place.
#[inline(always)]
fn nearest_first(
    n: &Node8,
    mut mask: u32,
    entry: &[f32; WIDTH],
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

/// Tests the packets of leaf `r` below `*best_t`, keeping the closest hit (as a lane index
/// `4 * packet + lane`); true when an any-hit query may stop.
#[inline(always)]
fn intersect_packets<const ANY_HIT: bool, C: CounterSink>(
    packets: &[Tri4],
    r: ChildRef,
    ray: &Ray4,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
    c: &mut C,
) -> bool {
    c.leaf();
    c.prim_tests(r.count as u64);
    let first = r.index as usize;
    let used = (r.count as usize).div_ceil(4);
    for (k, packet) in packets[first..first + used].iter().enumerate() {
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

impl Bvh8 {
    /// The one traversal loop — closest or any hit, counted or not — for a given node
    /// kernel. `stack` is scratch space, so batch callers reuse one allocation for all their
    /// rays. There is no separate test of the root box: the root node's test covers it.
    #[inline(always)]
    pub(crate) fn walk_ray<const ANY_HIT: bool, C: CounterSink, K: NodeKernel>(
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
        let ray4 = Ray4::new(ray);
        let mut best: Option<(usize, TriHit)> = None;
        let mut sp = 0;
        let mut r = self.root;
        'walk: loop {
            if r.is_leaf() {
                if intersect_packets::<ANY_HIT, C>(
                    &self.packets,
                    r,
                    &ray4,
                    &mut best_t,
                    &mut best,
                    c,
                ) {
                    break 'walk;
                }
            } else {
                c.node();
                let n = &self.nodes[r.index as usize];
                let (mask, entry) = kernel.test(&wide, n, t_min, best_t);
                if mask != 0 {
                    r = if ANY_HIT {
                        first_in_slot_order(n, mask, &entry, stack, &mut sp)
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
                if t_entry <= best_t {
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

    /// [`Bvh8::walk_ray`] with the kernel chosen at build time.
    fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        stack: &mut Stack,
        c: &mut C,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.avx2 {
            return crate::avx2::walk_ray::<ANY_HIT, C>(self, k, ray, stack, c);
        }
        self.walk_ray::<ANY_HIT, C, SseNodes>(SseNodes, ray, stack, c)
    }

    fn trace_single<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        STACK_TLS.with(|s| self.trace::<ANY_HIT, C>(ray, &mut s.borrow_mut(), c))
    }
}

impl Accel for Bvh8 {
    type Params = Bvh8Params;

    fn build(mesh: Arc<TriangleMesh>, params: &Bvh8Params) -> Result<Bvh8, BuildError> {
        if params.width as usize != WIDTH {
            return Err(BuildError::Unsupported(format!(
                "width {} (only {WIDTH})",
                params.width
            )));
        }
        let flat = build::build(&mesh, &params.binary)?;
        let mut nodes = Vec::with_capacity(flat.nodes.len() / 3 + 1);
        let mut packets = Vec::with_capacity(flat.prim_ids.len() / 2 + 1);
        let root = if flat.prim_ids.is_empty() {
            ChildRef::default()
        } else {
            collapse(&flat.nodes, flat.root, &mut nodes, &mut |r| {
                let ids = &flat.prim_ids[r.index as usize..(r.index + r.count) as usize];
                pack_leaf(&mesh, ids, &mut packets)
            })
        };
        Ok(Bvh8 {
            params: params.clone(),
            nodes,
            root,
            root_bounds: flat.root_bounds,
            packets,
            mesh,
            #[cfg(target_arch = "x86_64")]
            avx2: match params.node_simd {
                NodeSimd::Auto => crate::avx2::Avx2Nodes::detect(),
                NodeSimd::Sse => None,
            },
        })
    }

    fn name(&self) -> &str {
        "bvh8-binned"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.trace_single::<false, _>(ray, &mut NoCount)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.trace_single::<true, _>(ray, &mut NoCount).is_some()
    }

    fn intersect_counted(&self, ray: &Ray, c: &mut Counters) -> Option<Hit> {
        self.trace_single::<false, _>(ray, c)
    }

    fn occluded_counted(&self, ray: &Ray, c: &mut Counters) -> bool {
        self.trace_single::<true, _>(ray, c).is_some()
    }

    fn closest_point(&self, p: Vec3, max_radius: f32) -> Option<raybench_accel::PointHit> {
        crate::point::closest_point_wide(&self.point_view(), p, max_radius, &mut NoCount)
    }

    fn closest_point_counted(
        &self,
        p: Vec3,
        max_radius: f32,
        c: &mut Counters,
    ) -> Option<raybench_accel::PointHit> {
        crate::point::closest_point_wide(&self.point_view(), p, max_radius, c)
    }

    fn intersect_prepared(
        &self,
        rays: &[Ray],
        _: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        let mut stack = new_stack();
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.trace::<false, _>(ray, &mut stack, &mut NoCount);
        }
    }

    fn occluded_prepared(&self, rays: &[Ray], _: &PreparedRays, first: usize, out: &mut [bool]) {
        let mut stack = new_stack();
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
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

impl Bvh8 {
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
            .insert("avx2_node_test".into(), self.uses_avx2() as u8 as f64);
        s.nodes += s.leaves;
        s.sah_cost = (root_area > 0.0).then_some(sah);
        s
    }
}
