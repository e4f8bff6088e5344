//! The invariants of a built k-d tree, checked by tests after every build.
//!
//! Structure: nodes reached exactly once in depth-first order (the child below the plane right
//! after its parent), depth within the build's limit and the traversal stack, leaves tiling the
//! reference array in order, every split plane finite and strictly inside its node's cell, the
//! root cell containing every triangle, and the stored triangles matching the mesh.
//!
//! References: every triangle is referenced by every leaf its clipped bounds reach and by no
//! other. "Reach" is recomputed here from the geometry alone, walking each triangle down the
//! tree with the builders' own functions ([`crate::clip::side`], [`crate::clip::halves`],
//! [`crate::clip::straddler_bounds`]), so a reference set differing by one triangle in one leaf
//! is caught. The tolerance story, explicitly:
//! * A triangle that only *touches* a split plane from one side is required on that side only
//!   (its only points on the other side lie in the plane, inside the closed cell on its own
//!   side), and allowed on the other side only if it reaches it in its own right.
//! * A triangle lying *in* a split plane may be on either side (the SAH builder picks the
//!   cheaper side per split, which the flat node does not record): it is allowed on both and
//!   required on at least one.
//! * Clipping is conservative: bounds are rounded outwards to f32, and a straddler that
//!   clipping finds empty in a child (only possible within rounding of the plane) keeps its
//!   bounds cut to that child. A reference this adds is allowed, because the walk uses the same
//!   function.
//! * Triangles whose precomputed normal is zero (never hit) must not be referenced at all;
//!   they must all be in the zero-area side tree (closest-point queries only), which is
//!   checked the same way with the selection reversed.

use crate::KdTree;
use crate::build::Selection;
use crate::build::pack::PAD;
use crate::clip::{Side, halves, side, straddler_bounds};
use crate::node::{LEAF, MAX_DEPTH, Node};
use raybench_geom::tri4::{LANES, NO_PRIM};
use raybench_geom::{Aabb, MollerTriangle, Tri4, Triangle, TriangleMesh};

pub(crate) fn validate(kd: &KdTree, mesh: &TriangleMesh) -> Result<(), String> {
    validate_tree(kd, mesh)?;
    let zero_area = mesh.triangles().any(|t| Selection::ZeroArea.holds(&t));
    match &kd.zero_area {
        Some(side) if side.selection == Selection::ZeroArea && side.zero_area.is_none() => {
            validate_tree(side, mesh).map_err(|e| format!("zero-area side tree: {e}"))
        }
        Some(_) => Err("malformed zero-area side tree".into()),
        None if zero_area => Err("zero-area triangles but no side tree".into()),
        None => Ok(()),
    }
}

/// One tree: the main one (hittable triangles) or the side one (zero-area triangles).
fn validate_tree(kd: &KdTree, mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.len();
    // Stored triangles: a subset of the mesh without repeats, matching it, and holding every
    // triangle of the tree's selection (those a ray can hit, or the zero-area ones).
    let mut slot_of = vec![u32::MAX; n];
    for (i, &id) in kd.prim_ids.iter().enumerate() {
        let s = slot_of
            .get_mut(id as usize)
            .ok_or(format!("prim id {id} out of range"))?;
        if *s != u32::MAX {
            return Err(format!("prim id {id} appears twice"));
        }
        *s = i as u32;
    }
    if kd.tri4s.len() * LANES != kd.refs.len() {
        return Err(format!(
            "{} Tri4s for {} references",
            kd.tri4s.len(),
            kd.refs.len()
        ));
    }
    let selected: Vec<u32> = (0..n as u32)
        .filter(|&i| kd.selection.holds(&mesh.triangle(i as usize)))
        .collect();
    for &i in &selected {
        if slot_of[i as usize] == u32::MAX {
            return Err(format!("triangle {i} is selected but not in the tree"));
        }
    }
    if kd.prim_ids.len() != selected.len() {
        return Err(format!(
            "{} triangles stored, {} selected",
            kd.prim_ids.len(),
            selected.len()
        ));
    }
    if selected.is_empty() {
        return if kd.nodes.is_empty() && kd.refs.is_empty() {
            Ok(())
        } else {
            Err("nodes or references for a mesh with nothing selected".into())
        };
    }
    for &i in &selected {
        if !kd.bounds.contains_box(&mesh.triangle(i as usize).bounds()) {
            return Err(format!("root cell does not contain triangle {i}"));
        }
    }

    // Structure.
    let mut leaves = Vec::new(); // (node index, cell)
    let mut next_node = 0usize;
    let mut next_ref = 0usize;
    structure(
        kd,
        0,
        &kd.bounds,
        0,
        &mut next_node,
        &mut next_ref,
        &mut leaves,
    )?;
    if next_node != kd.nodes.len() {
        return Err(format!("{next_node} nodes reachable of {}", kd.nodes.len()));
    }
    if next_ref != kd.refs.len() {
        return Err(format!(
            "leaves hold {next_ref} of {} references",
            kd.refs.len()
        ));
    }

    // References: the actual (leaf, triangle slot) pairs, each leaf without repeats.
    let mut actual: Vec<(u32, u32)> = Vec::with_capacity(kd.refs.len());
    for &(at, _) in &leaves {
        let node = kd.nodes[at];
        let range = node.first() as usize..(node.first() + node.count()) as usize;
        let mut in_leaf: Vec<u32> = kd.refs[range].to_vec();
        in_leaf.sort_unstable();
        if in_leaf.windows(2).any(|w| w[0] == w[1]) {
            return Err(format!("leaf {at} references a triangle twice"));
        }
        if let Some(&bad) = in_leaf.iter().find(|&&r| r as usize >= kd.prim_ids.len()) {
            return Err(format!("leaf {at} references slot {bad} out of range"));
        }
        actual.extend(in_leaf.into_iter().map(|r| (at as u32, r)));
    }
    actual.sort_unstable();
    let mut allowed: Vec<(u32, u32)> = Vec::with_capacity(kd.refs.len());
    for &i in &selected {
        let tri = mesh.triangle(i as usize);
        let slot = slot_of[i as usize];
        let mut walk = Walk {
            kd,
            tri: &tri,
            slot,
            actual: &actual,
            allowed: &mut allowed,
        };
        walk.down(0, &kd.bounds, &tri.bounds(), true)
            .map_err(|e| format!("triangle {i}: {e}"))?;
    }
    allowed.sort_unstable();
    allowed.dedup();
    if let Some(extra) = actual.iter().find(|p| allowed.binary_search(p).is_err()) {
        return Err(format!(
            "leaf {} references triangle {} whose clipped bounds do not reach it",
            extra.0, kd.prim_ids[extra.1 as usize]
        ));
    }
    for &(at, _) in &leaves {
        leaf_copies(kd, mesh, at)?;
    }
    Ok(())
}

/// The leaf's Tri4 lanes: its `count` references as exact copies of their mesh triangles with
/// the mesh index as id, then padding references and unused lanes to a multiple of four.
fn leaf_copies(kd: &KdTree, mesh: &TriangleMesh, at: usize) -> Result<(), String> {
    let (first, count) = (kd.nodes[at].first() as usize, kd.nodes[at].count() as usize);
    for j in first..first + count.next_multiple_of(LANES) {
        let (four, lane) = (&kd.tri4s[j / LANES], j % LANES);
        let r = kd.refs[j];
        if j >= first + count {
            if r != PAD || four.ids[lane] != NO_PRIM || four.lane(lane) != Tri4::default().lane(0) {
                return Err(format!("leaf {at}: padding reference {j} is not empty"));
            }
            continue;
        }
        let Some(&id) = kd.prim_ids.get(r as usize) else {
            return Err(format!("leaf {at} references slot {r} out of range"));
        };
        if four.ids[lane] != id
            || four.lane(lane) != MollerTriangle::new(&mesh.triangle(id as usize))
        {
            return Err(format!(
                "leaf {at}: lane {lane} of Tri4 {} is not mesh triangle {id}",
                j / LANES
            ));
        }
    }
    Ok(())
}

/// Depth-first from `at` (whose cell is `cell`): order, depth, split planes, leaf tiling.
fn structure(
    kd: &KdTree,
    at: usize,
    cell: &Aabb,
    depth: usize,
    next_node: &mut usize,
    next_ref: &mut usize,
    leaves: &mut Vec<(usize, Aabb)>,
) -> Result<(), String> {
    if depth > kd.depth_limit as usize || depth > MAX_DEPTH {
        return Err(format!(
            "depth {depth} exceeds the limit {} (stack {MAX_DEPTH})",
            kd.depth_limit
        ));
    }
    if at != *next_node {
        return Err(format!(
            "node {at} reached out of depth-first order (expected {next_node})"
        ));
    }
    let node: Node = *kd
        .nodes
        .get(at)
        .ok_or(format!("node index {at} out of range"))?;
    *next_node += 1;
    if node.flags & 3 == LEAF {
        if node.first() as usize != *next_ref {
            return Err(format!(
                "leaf {at} starts at reference {}, expected {next_ref}",
                node.first()
            ));
        }
        *next_ref += (node.count() as usize).next_multiple_of(LANES);
        if *next_ref > kd.refs.len() {
            return Err(format!("leaf {at} runs past the references"));
        }

        leaves.push((at, *cell));
        return Ok(());
    }
    let (axis, p) = (node.axis(), node.split());
    if !(p.is_finite() && cell.min[axis] < p && p < cell.max[axis]) {
        return Err(format!(
            "node {at}: split {p} on axis {axis} is not strictly inside its cell [{}, {}]",
            cell.min[axis], cell.max[axis]
        ));
    }
    let (below, above) = halves(cell, axis, p);
    structure(kd, at + 1, &below, depth + 1, next_node, next_ref, leaves)?;
    if node.above() as usize != *next_node {
        return Err(format!(
            "node {at}: child above at {}, expected {next_node}",
            node.above()
        ));
    }
    structure(
        kd,
        node.above() as usize,
        &above,
        depth + 1,
        next_node,
        next_ref,
        leaves,
    )
}

/// One triangle walked down the tree as the builders classify it.
struct Walk<'a> {
    kd: &'a KdTree,
    tri: &'a Triangle,
    slot: u32,
    actual: &'a [(u32, u32)],
    allowed: &'a mut Vec<(u32, u32)>,
}

impl Walk<'_> {
    /// Visits the subtree at `at` with the triangle's bounds `b` clipped to `cell`; returns
    /// whether some leaf of it references the triangle. `required`: every leaf reached must.
    fn down(&mut self, at: usize, cell: &Aabb, b: &Aabb, required: bool) -> Result<bool, String> {
        let node = self.kd.nodes[at];
        if node.is_leaf() {
            self.allowed.push((at as u32, self.slot));
            let present = self.actual.binary_search(&(at as u32, self.slot)).is_ok();
            if required && !present {
                return Err(format!(
                    "not referenced by leaf {at} (cell {cell:?}), which its clipped bounds \
                     {b:?} reach"
                ));
            }
            return Ok(present);
        }
        let (axis, p) = (node.axis(), node.split());
        let (cb, ca) = halves(cell, axis, p);
        let below = at + 1;
        let above = node.above() as usize;
        Ok(match side(b, axis, p) {
            Side::Below => self.down(below, &cb, b, required)?,
            Side::Above => self.down(above, &ca, b, required)?,
            Side::Both => {
                let x = self.down(below, &cb, &straddler_bounds(self.tri, &cb), required)?;
                let y = self.down(above, &ca, &straddler_bounds(self.tri, &ca), required)?;
                x || y
            }
            Side::InPlane => {
                let x = self.down(below, &cb, b, false)?;
                let y = self.down(above, &ca, b, false)?;
                if required && !(x || y) {
                    return Err(format!(
                        "lies in the split plane of node {at} but is on neither side"
                    ));
                }
                x || y
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::node::Node;
    use crate::{KdParams, KdTree};
    use raybench_accel::Accel;
    use std::sync::Arc;

    fn built(params: KdParams) -> (KdTree, Arc<raybench_geom::TriangleMesh>) {
        let mesh = raybench_testkit::generated("soup:triangles=500", 3);
        (KdTree::build(mesh.clone(), &params).unwrap(), mesh)
    }

    fn first_interior(kd: &KdTree) -> usize {
        kd.nodes.iter().position(|n| !n.is_leaf()).unwrap()
    }

    fn first_full_leaf(kd: &KdTree) -> usize {
        kd.nodes
            .iter()
            .position(|n| n.is_leaf() && n.count() > 1)
            .unwrap()
    }

    #[test]
    fn sound_trees_pass() {
        for p in [KdParams::sah(), KdParams::median()] {
            let (kd, mesh) = built(p);
            assert_eq!(kd.validate(&mesh), Ok(()));
        }
    }

    #[test]
    fn a_split_outside_its_cell_is_caught() {
        let (mut kd, mesh) = built(KdParams::sah());
        let i = first_interior(&kd);
        let n = kd.nodes[i];
        let bad = kd.bounds.max[n.axis()] + 1.0;
        kd.nodes[i] = Node::interior(n.axis(), bad, n.above());
        let err = kd.validate(&mesh).unwrap_err();
        assert!(err.contains("not strictly inside"), "{err}");
    }

    #[test]
    fn a_moved_split_is_caught_by_the_reference_sets() {
        let (mut kd, mesh) = built(KdParams::sah());
        let i = first_interior(&kd);
        let n = kd.nodes[i];
        let moved = n.split() * 0.999 + kd.bounds.center()[n.axis()] * 0.001;
        kd.nodes[i] = Node::interior(n.axis(), moved, n.above());
        let err = kd.validate(&mesh).unwrap_err();
        assert!(err.contains("reach"), "{err}");
    }

    #[test]
    fn a_missing_reference_is_caught() {
        let (mut kd, mesh) = built(KdParams::sah());
        let leaf = kd.nodes[first_full_leaf(&kd)];
        // Replace the leaf's first reference by its second: one missing, one repeated.
        let f = leaf.first() as usize;
        kd.refs[f] = kd.refs[f + 1];
        assert!(kd.validate(&mesh).unwrap_err().contains("twice"));
        // Replace it by a triangle from elsewhere: one missing, one not allowed.
        let (mut kd, mesh) = built(KdParams::sah());
        let leaf = kd.nodes[first_full_leaf(&kd)];
        let f = leaf.first() as usize;
        let elsewhere = (0..kd.prim_ids.len() as u32)
            .find(|r| !kd.refs[f..f + leaf.count() as usize].contains(r))
            .unwrap();
        kd.refs[f] = elsewhere;
        let err = kd.validate(&mesh).unwrap_err();
        assert!(
            err.contains("not referenced") || err.contains("do not reach"),
            "{err}"
        );
    }

    #[test]
    fn a_wrong_child_index_is_caught() {
        let (mut kd, mesh) = built(KdParams::median());
        let i = first_interior(&kd);
        let n = kd.nodes[i];
        kd.nodes[i] = Node::interior(n.axis(), n.split(), n.above() + 1);
        assert!(kd.validate(&mesh).is_err());
    }

    #[test]
    fn a_wrong_triangle_is_caught() {
        let (mut kd, mesh) = built(KdParams::sah());
        kd.tri4s.swap(0, 1);
        assert!(
            kd.validate(&mesh)
                .unwrap_err()
                .contains("is not mesh triangle")
        );
        // A padding lane that holds a triangle.
        let (mut kd, mesh) = built(KdParams::sah());
        let at = (0..kd.nodes.len())
            .find(|&i| kd.nodes[i].is_leaf() && kd.nodes[i].count() % 4 != 0)
            .expect("a leaf with padding");
        let (f, c) = (kd.nodes[at].first() as usize, kd.nodes[at].count() as usize);
        let j = f + c;
        let copy = kd.tri4s[f / 4].lane(0);
        kd.tri4s[j / 4].set_lane(j % 4, 0, &copy);
        assert!(kd.validate(&mesh).unwrap_err().contains("padding"));
    }

    #[test]
    fn a_leaf_past_the_depth_limit_is_caught() {
        let (mut kd, mesh) = built(KdParams::sah());
        kd.depth_limit = 1;
        assert!(
            kd.validate(&mesh)
                .unwrap_err()
                .contains("exceeds the limit")
        );
    }
}
