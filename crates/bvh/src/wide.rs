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

use crate::BvhParams;
use crate::build;
use crate::node::{ChildRef, MAX_DEPTH, Node};
use crate::simd::F4;
use crate::traverse::intersect_leaf;
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

/// Knobs of the wide BVH: the binary tree it is collapsed from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bvh8Params {
    pub binary: BvhParams,
    pub width: u32,
}

impl Default for Bvh8Params {
    fn default() -> Self {
        Bvh8Params {
            binary: BvhParams::binned(),
            width: WIDTH as u32,
        }
    }
}

#[derive(Debug)]
pub struct Bvh8 {
    params: Bvh8Params,
    nodes: Vec<Node8>,
    root: ChildRef,
    root_bounds: Aabb,
    triangles: Vec<MollerTriangle>,
    prim_ids: Vec<u32>,
}

/// Collapses the binary subtree `r` into wide nodes appended to `out` depth-first.
fn collapse(binary: &[Node], r: ChildRef, out: &mut Vec<Node8>) -> ChildRef {
    if r.is_leaf() {
        return r;
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
        let r = collapse(binary, *child, out);
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

    pub fn params(&self) -> &Bvh8Params {
        &self.params
    }

    /// Every child box inside its parent's, leaves tiling the triangle array in depth-first
    /// order, every mesh triangle exactly once, depth within the stack bound.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let n = mesh.len();
        if self.prim_ids.len() != n || self.triangles.len() != n {
            return Err(format!("{} ids for a mesh of {n}", self.prim_ids.len()));
        }
        let mut seen = vec![false; n];
        for (slot, &id) in self.prim_ids.iter().enumerate() {
            let s = seen
                .get_mut(id as usize)
                .ok_or(format!("prim id {id} out of range"))?;
            if std::mem::replace(s, true) {
                return Err(format!("prim id {id} appears twice"));
            }
            if self.triangles[slot] != MollerTriangle::new(&mesh.triangle(id as usize)) {
                return Err(format!("triangle slot {slot} is not mesh triangle {id}"));
            }
        }
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
        if covered != n || interior != self.nodes.len() {
            return Err(format!(
                "leaves hold {covered} of {n} triangles; {interior} of {} nodes reachable",
                self.nodes.len()
            ));
        }
        Ok(())
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
            if r.index as usize != *covered {
                return Err(format!("leaf at {}, expected {covered}", r.index));
            }
            for i in r.index as usize..(r.index + r.count) as usize {
                let id = *self.prim_ids.get(i).ok_or("leaf runs past the triangles")?;
                if !bounds.contains_box(&mesh.triangle(id as usize).bounds()) {
                    return Err(format!("leaf box does not contain triangle {id}"));
                }
            }
            *covered += r.count as usize;
            return Ok(());
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

/// The ray as the wide node test needs it: origin and inverse direction splatted, and per axis
/// which stored side (min or max) holds the near planes.
struct WideRay {
    origin: [F4; 3],
    inv: [F4; 3],
    near: [usize; 3],
}

impl WideRay {
    fn new(ray: &Ray) -> WideRay {
        let inv = ray.inv_dir().to_array();
        WideRay {
            origin: ray.origin().to_array().map(F4::splat),
            inv: inv.map(F4::splat),
            // -0 counts as negative: its inverse is -inf (bug class B3).
            near: inv.map(|x| x.is_sign_negative() as usize),
        }
    }

    /// Entry distances of all 8 children and a mask of those entered within `[t_min, t_max]`.
    /// The same arithmetic as the scalar slab test lane for lane; a NaN (`0 * inf`, origin in a
    /// face plane) is ignored because `max_keep`/`min_keep` keep the accumulator (B1).
    #[inline(always)]
    fn test(&self, n: &Node8, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut entry = [0.0; WIDTH];
        for half in 0..2 {
            let mut t0 = F4::splat(t_min);
            let mut t1 = F4::splat(t_max);
            for a in 0..3 {
                let near = F4::load(&n.planes[a][self.near[a]][half]);
                let far = F4::load(&n.planes[a][1 - self.near[a]][half]);
                t0 = near.sub(self.origin[a]).mul(self.inv[a]).max_keep(t0);
                t1 = far.sub(self.origin[a]).mul(self.inv[a]).min_keep(t1);
            }
            mask |= t0.le_mask(t1) << (4 * half);
            entry[4 * half..4 * half + 4].copy_from_slice(&t0.to_array());
        }
        (mask, entry)
    }
}

type Entry = (ChildRef, f32);

thread_local! {
    /// The single-ray paths' traversal stack, allocated once per thread.
    static STACK_TLS: RefCell<Vec<Entry>> = RefCell::new(Vec::with_capacity(STACK));
}

impl Bvh8 {
    /// The one traversal loop: closest or any hit, counted or not. `stack` is only scratch
    /// space (cleared here), so batch callers reuse one allocation for all their rays.
    fn trace<const ANY_HIT: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        stack: &mut Vec<Entry>,
        c: &mut C,
    ) -> Option<Hit> {
        if self.triangles.is_empty() {
            return None;
        }
        let t_min = ray.t_min();
        let mut best_t = ray.t_max();
        self.root_bounds.intersect(ray)?;
        let wide = WideRay::new(ray);
        let mut best: Option<(usize, TriHit)> = None;
        stack.clear();
        let mut next = Some(self.root);
        'walk: loop {
            while let Some(r) = next.take() {
                if r.is_leaf() {
                    if intersect_leaf::<ANY_HIT, C>(
                        &self.triangles,
                        r,
                        ray,
                        &mut best_t,
                        &mut best,
                        c,
                    ) {
                        break 'walk;
                    }
                    break;
                }
                c.node();
                let n = &self.nodes[r.index as usize];
                let (mut mask, entry) = wide.test(n, t_min, best_t);
                if mask == 0 {
                    break;
                }
                // Entered children sorted nearest first (insertion sort: usually 1–3 of them).
                let mut hits = [(ChildRef::default(), 0f32); WIDTH];
                let mut count = 0;
                while mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let mut j = count;
                    while j > 0 && hits[j - 1].1 > entry[i] {
                        hits[j] = hits[j - 1];
                        j -= 1;
                    }
                    hits[j] = (n.child[i], entry[i]);
                    count += 1;
                }
                stack.extend(hits[1..count].iter().rev());
                next = Some(hits[0].0);
            }
            loop {
                let Some((r, t_entry)) = stack.pop() else {
                    break 'walk;
                };
                if t_entry <= best_t {
                    next = Some(r);
                    break;
                }
            }
        }
        best.map(|(i, h)| Hit {
            t: h.t,
            prim: self.prim_ids[i],
            u: h.u,
            v: h.v,
        })
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
        let root = if flat.prim_ids.is_empty() {
            ChildRef::default()
        } else {
            collapse(&flat.nodes, flat.root, &mut nodes)
        };
        let triangles = flat
            .prim_ids
            .iter()
            .map(|&i| MollerTriangle::new(&mesh.triangle(i as usize)))
            .collect();
        Ok(Bvh8 {
            params: params.clone(),
            nodes,
            root,
            root_bounds: flat.root_bounds,
            triangles,
            prim_ids: flat.prim_ids,
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

    fn intersect_prepared(
        &self,
        rays: &[Ray],
        _: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        let mut stack = Vec::with_capacity(STACK);
        for (o, ray) in out.iter_mut().zip(&rays[first..]) {
            *o = self.trace::<false, _>(ray, &mut stack, &mut NoCount);
        }
    }

    fn occluded_prepared(&self, rays: &[Ray], _: &PreparedRays, first: usize, out: &mut [bool]) {
        let mut stack = Vec::with_capacity(STACK);
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
            indices: std::mem::size_of_val(self.prim_ids.as_slice()) as u64,
            primitives: std::mem::size_of_val(self.triangles.as_slice()) as u64,
        }
    }
}

impl Bvh8 {
    /// Shape and SAH cost of the wide tree (a wide node costs one traversal step: one SIMD
    /// node test), with the constants shared by every structure.
    fn measure(&self) -> BuildStats {
        let mut s = BuildStats::default();
        if self.triangles.is_empty() {
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
        s.nodes += s.leaves;
        s.sah_cost = (root_area > 0.0).then_some(sah);
        s
    }
}
