//! The wide tree's invariant check.

use super::BvhWide;
use crate::node::{ChildRef, MAX_DEPTH};
use raybench_geom::{Aabb, MollerTriangle, NO_PRIM, Tri4, TriangleMesh};

impl<const W: usize> BvhWide<W> {
    /// Every child box inside its parent's; leaves tiling the `Tri4`s in depth-first order,
    /// their triangles in the first lanes and the rest empty; every lane equal to its mesh
    /// triangle; every mesh triangle exactly once; depth within the stack bound. With spatial
    /// splits a triangle may be in several leaves (never twice in one) whose boxes each hold
    /// part of it: they must overlap its box and together cover it
    /// (`check_references`).
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let n = mesh.len();
        check_lanes(
            &self.tri4s,
            mesh,
            self.params.binary.spatial_splits.is_some(),
        )?;
        if n == 0 {
            return Ok(());
        }
        let (mut covered, mut interior) = (0, 0);
        let mut pieces = self.params.binary.spatial_splits.map(|_| Vec::new());
        self.check_subtree(
            mesh,
            self.root,
            &self.root_bounds,
            0,
            (&mut covered, &mut interior),
            &mut pieces,
        )?;
        if let Some(pieces) = pieces {
            crate::cover::check_references(mesh, pieces)?;
        }
        check_reached(covered, self.tri4s.len(), interior, self.nodes.len())
    }

    fn check_subtree(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        bounds: &Aabb,
        depth: usize,
        (covered, interior): (&mut usize, &mut usize),
        pieces: &mut Option<Vec<(u32, Aabb)>>,
    ) -> Result<(), String> {
        if depth >= MAX_DEPTH {
            return Err(format!("depth {depth} exceeds {MAX_DEPTH}"));
        }
        if r.is_leaf() {
            return self.check_leaf(mesh, r, bounds, covered, pieces);
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
            let counts = (&mut *covered, &mut *interior);
            self.check_subtree(mesh, node.child[i], &child, depth + 1, counts, pieces)?;
        }
        Ok(())
    }

    /// A leaf: at the next `Tri4` in depth-first order, `count` used lanes followed by unused
    /// ones, every triangle inside the leaf's box (with `pieces`, noted with the leaf's box
    /// instead, none twice in the leaf).
    fn check_leaf(
        &self,
        mesh: &TriangleMesh,
        r: ChildRef,
        bounds: &Aabb,
        covered: &mut usize,
        pieces: &mut Option<Vec<(u32, Aabb)>>,
    ) -> Result<(), String> {
        if r.index as usize != *covered {
            return Err(format!("leaf at Tri4 {}, expected {covered}", r.index));
        }
        let tri4s = (r.count as usize).div_ceil(4);
        let first = r.index as usize;
        let leaf = self
            .tri4s
            .get(first..first + tri4s)
            .ok_or("leaf runs past the Tri4s")?;
        for (k, &id) in leaf.iter().flat_map(|t| &t.ids).enumerate() {
            if (k < r.count as usize) != (id != NO_PRIM) {
                return Err(format!("leaf at Tri4 {} has lane {k} misused", r.index));
            }
            if id == NO_PRIM {
                continue;
            }
            if let Some(pieces) = pieces.as_mut() {
                if leaf.iter().flat_map(|t| &t.ids).take(k).any(|&o| o == id) {
                    return Err(format!(
                        "triangle {id} twice in the leaf at Tri4 {}",
                        r.index
                    ));
                }
                pieces.push((id, *bounds));
            } else if !bounds.contains_box(&mesh.triangle(id as usize).bounds()) {
                return Err(format!("leaf box does not contain triangle {id}"));
            }
        }
        *covered += tri4s;
        Ok(())
    }
}

/// The walk from the root reached every `Tri4` (through leaves) and every node, whatever the
/// node format.
pub(super) fn check_reached(
    covered: usize,
    tri4s: usize,
    interior: usize,
    nodes: usize,
) -> Result<(), String> {
    if covered != tri4s || interior != nodes {
        return Err(format!(
            "leaves hold {covered} of {tri4s} Tri4s; {interior} of {nodes} nodes reachable"
        ));
    }
    Ok(())
}

/// Every used lane is its mesh triangle, every mesh triangle is in exactly one lane (in one or
/// more with `spatial_splits`), and unused lanes are the all-zero triangle.
pub(super) fn check_lanes(
    tri4s: &[Tri4],
    mesh: &TriangleMesh,
    spatial_splits: bool,
) -> Result<(), String> {
    let mut seen = vec![false; mesh.len()];
    for (slot, id) in tri4s.iter().flat_map(|t| t.ids).enumerate() {
        let lane = tri4s[slot / 4].lane(slot % 4);
        if id == NO_PRIM {
            if lane != Tri4::default().lane(0) {
                return Err(format!("unused lane {slot} holds a triangle"));
            }
            continue;
        }
        let s = seen
            .get_mut(id as usize)
            .ok_or(format!("prim id {id} out of range"))?;
        if std::mem::replace(s, true) && !spatial_splits {
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

#[cfg(test)]
mod tests {
    use crate::{Bvh8, WideParams};
    use raybench_accel::Accel;

    /// The wide validator, on the collapsed tree: a leaf box cut in half leaves its triangles
    /// uncovered.
    #[test]
    fn the_wide_validator_catches_a_shrunk_leaf() {
        let mesh = raybench_testkit::generated("hair:triangles=2000", 4);
        let mut bvh = Bvh8::build(mesh.clone(), &WideParams::sbvh()).expect("builds");
        bvh.validate(&mesh).expect("a sound tree passes");
        let (n, slot) = (0..bvh.nodes.len())
            .flat_map(|n| (0..8).map(move |s| (n, s)))
            .find(|&(n, s)| s < bvh.nodes[n].children() && bvh.nodes[n].child[s].is_leaf())
            .expect("a leaf");
        for axis in 0..3 {
            let p = &mut bvh.nodes[n].planes[axis];
            p[1][slot] = (p[0][slot] + p[1][slot]) * 0.5;
        }
        let err = bvh.validate(&mesh).unwrap_err();
        assert!(err.contains("cover") || err.contains("misses"), "{err}");
    }
}
