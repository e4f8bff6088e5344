//! The invariants of a built BVH, checked by tests after every build.

use crate::{Bvh, MAX_DEPTH};
use raybench_geom::TriangleMesh;

/// Every child box inside its parent's, every leaf box containing its triangles, leaf ranges
/// tiling the triangle array exactly once, `prim_ids` a permutation of the mesh's triangles,
/// the reordered triangles matching the mesh, and the depth within the traversal stack.
pub(crate) fn validate(bvh: &Bvh, mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.len();
    if bvh.prim_ids.len() != n || bvh.triangles.len() != n {
        return Err(format!(
            "{} ids / {} triangles for a mesh of {n}",
            bvh.prim_ids.len(),
            bvh.triangles.len()
        ));
    }
    let mut seen = vec![false; n];
    for &id in &bvh.prim_ids {
        let slot = seen
            .get_mut(id as usize)
            .ok_or(format!("prim id {id} out of range"))?;
        if std::mem::replace(slot, true) {
            return Err(format!("prim id {id} appears twice"));
        }
    }
    for (i, &id) in bvh.prim_ids.iter().enumerate() {
        if bvh.triangles[i] != raybench_geom::MollerTriangle::new(&mesh.triangle(id as usize)) {
            return Err(format!("triangle slot {i} is not mesh triangle {id}"));
        }
    }
    if bvh.nodes.is_empty() {
        return if n == 0 {
            Ok(())
        } else {
            Err("no nodes for a non-empty mesh".into())
        };
    }
    let mut covered = 0usize;
    walk(bvh, mesh, 0, 0, &mut covered)?;
    if covered != n {
        return Err(format!("leaves hold {covered} triangles, the mesh has {n}"));
    }
    Ok(())
}

/// Depth-first from `node`: checks the subtree and returns the index after it.
fn walk(
    bvh: &Bvh,
    mesh: &TriangleMesh,
    node: usize,
    depth: usize,
    covered: &mut usize,
) -> Result<usize, String> {
    if depth >= MAX_DEPTH {
        return Err(format!(
            "node {node} at depth {depth} exceeds the stack size {MAX_DEPTH}"
        ));
    }
    let n = bvh
        .nodes
        .get(node)
        .ok_or(format!("node index {node} out of range"))?;
    let bounds = n.bounds();
    if n.is_leaf() {
        let first = n.index as usize;
        if first != *covered {
            return Err(format!(
                "leaf {node} starts at {first}, expected {covered} (depth-first order)"
            ));
        }
        for i in first..first + n.count as usize {
            let id = *bvh
                .prim_ids
                .get(i)
                .ok_or(format!("leaf {node} runs past the triangles"))?;
            if !bounds.contains_box(&mesh.triangle(id as usize).bounds()) {
                return Err(format!("leaf {node} does not contain triangle {id}"));
            }
        }
        *covered += n.count as usize;
        return Ok(node + 1);
    }
    let first_child = node + 1;
    let after_first = walk(bvh, mesh, first_child, depth + 1, covered)?;
    if n.index as usize != after_first {
        return Err(format!(
            "node {node}'s second child is {} but its first subtree ends at {after_first}",
            n.index
        ));
    }
    for child in [first_child, after_first] {
        if !bounds.contains_box(&bvh.nodes[child].bounds()) {
            return Err(format!("child {child} is not inside its parent {node}"));
        }
    }
    walk(bvh, mesh, after_first, depth + 1, covered)
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams};
    use raybench_accel::Accel;
    use std::sync::Arc;

    fn built() -> (Bvh, Arc<raybench_geom::TriangleMesh>) {
        let mesh = raybench_scenes::generate("soup:triangles=500", 3)
            .unwrap()
            .mesh;
        (
            Bvh::build(mesh.clone(), &BvhParams::binned()).unwrap(),
            mesh,
        )
    }

    #[test]
    fn a_sound_tree_passes() {
        let (bvh, mesh) = built();
        assert_eq!(bvh.validate(&mesh), Ok(()));
    }

    #[test]
    fn a_child_outside_its_parent_is_caught() {
        let (mut bvh, mesh) = built();
        bvh.nodes[1].bounds[1][0] += 10.0;
        assert!(
            bvh.validate(&mesh)
                .unwrap_err()
                .contains("not inside its parent")
        );
    }

    #[test]
    fn a_duplicated_triangle_is_caught() {
        let (mut bvh, mesh) = built();
        bvh.prim_ids[1] = bvh.prim_ids[0];
        assert!(bvh.validate(&mesh).unwrap_err().contains("appears twice"));
    }

    #[test]
    fn a_leaf_box_missing_its_triangle_is_caught() {
        let (mut bvh, mesh) = built();
        let leaf = bvh.nodes.iter().position(|n| n.is_leaf()).unwrap();
        bvh.nodes[leaf].bounds[0] = bvh.nodes[leaf].bounds[1];
        let err = bvh.validate(&mesh).unwrap_err();
        assert!(
            err.contains("does not contain") || err.contains("not inside"),
            "{err}"
        );
    }

    #[test]
    fn a_wrong_second_child_is_caught() {
        let (mut bvh, mesh) = built();
        bvh.nodes[0].index += 1;
        assert!(bvh.validate(&mesh).is_err());
    }
}
