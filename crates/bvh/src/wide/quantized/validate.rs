//! The quantized tree's invariant check. Decoded boxes are not nested (each node's grid spans
//! its own float bounds, so a grandchild's decoded box may poke out of its parent's), so the
//! check is the one a walk relies on: every decoded child box holds every triangle below it,
//! and so does every box of the float root node the ray walk tests in the root's place.

use super::BvhQuantized;
use super::node::{Plane, QNode, QWIDTH, step};
use crate::node::{ChildRef, MAX_DEPTH};
use crate::wide::validate::{check_lanes, check_reached};
use raybench_geom::{Aabb, NO_PRIM, TriangleMesh};

impl<P: Plane> BvhQuantized<P> {
    /// Every decoded child box holds the bounds of the triangles below it; every node's
    /// frame sound (finite origins that flush-to-zero leaves alone, steps a normal power of
    /// two, `min <= max` bytes in used slots, zero bytes in unused ones, 2 to 8 children);
    /// nodes in depth-first order; leaves tiling the `Tri4`s in depth-first order with their
    /// triangles in the first lanes; every lane its mesh triangle; every mesh triangle
    /// exactly once; depth within the stack bound.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        check_lanes(
            &self.tri4s,
            mesh,
            self.params.binary.spatial_splits.is_some(),
        )?;
        if mesh.is_empty() {
            return Ok(());
        }
        let (mut covered, mut interior) = (0, 0);
        let bounds = self.check_subtree(mesh, self.root, 0, &mut covered, &mut interior)?;
        if !self.root_bounds.contains_box(&bounds) {
            return Err("the root bounds do not hold the triangles".into());
        }
        check_reached(covered, self.tri4s.len(), interior, self.nodes.len())
    }

    /// Checks the subtree at `r` and returns the bounds of its triangles.
    fn check_subtree(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        depth: usize,
        covered: &mut usize,
        interior: &mut usize,
    ) -> Result<Aabb, String> {
        if depth >= MAX_DEPTH {
            return Err(format!("depth {depth} exceeds {MAX_DEPTH}"));
        }
        if r.is_leaf() {
            return self.check_leaf(mesh, r, covered);
        }
        if r.index as usize != *interior {
            return Err(format!("node {} out of depth-first order", r.index));
        }
        *interior += 1;
        let node = self
            .nodes
            .get(r.index as usize)
            .ok_or("node index out of range")?;
        check_frame(node).map_err(|e| format!("node {}: {e}", r.index))?;
        let mut bounds = Aabb::default();
        // The walk tests the root's children on the float root node instead: the same
        // children, in the same slots, whose boxes must hold their triangles too.
        let is_root = r == self.root;
        if is_root
            && (self.root_node.child != node.child || self.root_node.children() != node.children())
        {
            return Err("the float root node's children are not the quantized root's".into());
        }
        for i in 0..node.children() {
            let below = self.check_subtree(mesh, node.child[i], depth + 1, covered, interior)?;
            if !node.child_bounds(i).contains_box(&below) {
                return Err(format!(
                    "decoded box of child {i} of node {} does not hold its triangles",
                    r.index
                ));
            }
            if is_root && !self.root_node.child_bounds(i).contains_box(&below) {
                return Err(format!(
                    "float box of child {i} of the root does not hold its triangles"
                ));
            }
            bounds = bounds.union(&below);
        }
        Ok(bounds)
    }

    /// A leaf: at the next `Tri4` in depth-first order, `count` used lanes followed by unused
    /// ones; returns its triangles' bounds.
    fn check_leaf(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        covered: &mut usize,
    ) -> Result<Aabb, String> {
        if r.index as usize != *covered {
            return Err(format!("leaf at Tri4 {}, expected {covered}", r.index));
        }
        let tri4s = (r.count as usize).div_ceil(4);
        let first = r.index as usize;
        let leaf = self
            .tri4s
            .get(first..first + tri4s)
            .ok_or("leaf runs past the Tri4s")?;
        let mut bounds = Aabb::default();
        for (k, &id) in leaf.iter().flat_map(|t| &t.ids).enumerate() {
            if (k < r.count as usize) != (id != NO_PRIM) {
                return Err(format!("leaf at Tri4 {} has lane {k} misused", r.index));
            }
            if id != NO_PRIM {
                bounds = bounds.union(&mesh.triangle(id as usize).bounds());
            }
        }
        *covered += tri4s;
        Ok(bounds)
    }
}

/// A node's grid and bytes, independent of what lies below it.
fn check_frame<P: Plane>(n: &QNode<P>) -> Result<(), String> {
    let used = n.children();
    if !(2..=QWIDTH).contains(&used) {
        return Err(format!("{used} children"));
    }
    for axis in 0..3 {
        let o = n.origin[axis];
        if !(o == 0.0 || o.is_normal()) {
            return Err(format!("origin {o} on axis {axis} is not zero or normal"));
        }
        let s = step(n.exp[axis]);
        if !s.is_normal() || !(255.0 * s).is_finite() {
            return Err(format!("exponent {} on axis {axis}", n.exp[axis]));
        }
        for i in 0..QWIDTH {
            let (lo, hi) = (n.q[axis][0][i].get(), n.q[axis][1][i].get());
            if i >= used && (lo, hi) != (0, 0) {
                return Err(format!("planes in unused slot {i}"));
            }
            if lo > hi {
                return Err(format!("slot {i} has min plane {lo} above max {hi}"));
            }
        }
        for side in 0..2 {
            for i in 0..used {
                let plane = super::node::decode(o, s, n.q[axis][side][i].get());
                if !(plane == 0.0 || plane.is_normal()) {
                    return Err(format!("slot {i} decodes to {plane}, not zero or normal"));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::BvhQuantized;
    use super::super::node::Plane;
    use crate::wide::{NodeFormat, WideParams};

    /// The validator catches a decoded box that no longer holds its triangles, and inverted
    /// bytes.
    #[test]
    fn the_validator_rejects_a_shrunken_box() {
        rejects::<u8>(NodeFormat::Quantized);
        rejects::<u16>(NodeFormat::Quantized16);
    }

    fn rejects<P: Plane>(node_format: NodeFormat) {
        let mesh = raybench_testkit::generated("teapot:triangles=2000", 1);
        let params = WideParams {
            node_format,
            ..WideParams::for_width(8)
        };
        let mut q = BvhQuantized::<P>::build_quantized(mesh.clone(), &params).expect("builds");
        q.validate(&mesh).expect("valid as built");
        let slot = (0..q.nodes[0].children())
            .find(|&i| q.nodes[0].q[0][1][i].get() > q.nodes[0].q[0][0][i].get())
            .expect("a child with some extent in x");
        q.nodes[0].q[0][1][slot] = P::new(q.nodes[0].q[0][1][slot].get() - 1);
        let e = q.validate(&mesh).expect_err("a shrunken box");
        assert!(e.contains("does not hold"), "{e}");
        q.nodes[0].q[0][1][slot] = P::new(0);
        q.nodes[0].q[0][0][slot] = P::new(P::TOP);
        let e = q.validate(&mesh).expect_err("inverted bytes");
        assert!(e.contains("above max"), "{e}");
    }
}
