//! The invariants of a built BVH, checked by tests after every build.

use crate::{Bvh, ChildRef, MAX_DEPTH};
use raybench_geom::TriangleMesh;

/// Every child box inside its parent's, every leaf box containing its triangles, leaf ranges
/// tiling the triangle array exactly once, `prim_ids` a permutation of the mesh's triangles,
/// the reordered triangles matching the mesh, and the depth within the traversal stack.
///
/// With spatial splits a triangle may be in several leaves (never twice in one), and each of
/// those leaves' boxes may hold only part of it: then every triangle must be in some leaf, and
/// the boxes of the leaves holding it must overlap its box and together cover it
/// ([`cover::check_references`](crate::cover::check_references)).
pub(crate) fn validate(bvh: &Bvh, mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.len();
    let spatial = bvh.params.spatial_splits.is_some();
    let refs = bvh.prim_ids.len();
    if (!spatial && refs != n) || refs < n || bvh.triangles.len() != refs {
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
        if std::mem::replace(slot, true) && !spatial {
            return Err(format!("prim id {id} appears twice"));
        }
    }
    for (i, &id) in bvh.prim_ids.iter().enumerate() {
        if bvh.triangles[i] != raybench_geom::MollerTriangle::new(&mesh.triangle(id as usize)) {
            return Err(format!("triangle slot {i} is not mesh triangle {id}"));
        }
    }
    if n == 0 {
        return if bvh.nodes.is_empty() {
            Ok(())
        } else {
            Err("nodes for an empty mesh".into())
        };
    }
    let mut covered = 0usize;
    let mut interior = 0usize;
    let mut pieces = spatial.then(Vec::new);
    walk(
        bvh,
        mesh,
        bvh.root,
        &bvh.root_bounds,
        0,
        (&mut covered, &mut interior),
        &mut pieces,
    )?;
    if covered != refs {
        return Err(format!(
            "leaves hold {covered} triangles, the tree has {refs}"
        ));
    }
    if let Some(pieces) = pieces {
        crate::cover::check_references(mesh, pieces)?;
    }
    if interior != bvh.nodes.len() {
        return Err(format!("{interior} nodes reachable of {}", bvh.nodes.len()));
    }
    Ok(())
}

/// Depth-first from `r`, whose box is `bounds`: leaves contain their triangles and tile the
/// triangle array in order; children's boxes lie inside their parent's. With `pieces` (spatial
/// splits), a leaf's triangles are noted with its box instead, and none may repeat in it.
fn walk(
    bvh: &Bvh,
    mesh: &TriangleMesh,
    r: ChildRef,
    bounds: &raybench_geom::Aabb,
    depth: usize,
    (covered, interior): (&mut usize, &mut usize),
    pieces: &mut Option<Vec<(u32, raybench_geom::Aabb)>>,
) -> Result<(), String> {
    if depth >= MAX_DEPTH {
        return Err(format!("depth {depth} exceeds the stack size {MAX_DEPTH}"));
    }
    if r.is_leaf() {
        let first = r.index as usize;
        if first != *covered {
            return Err(format!(
                "leaf at {first}, expected {covered} (depth-first order)"
            ));
        }
        for i in first..first + r.count as usize {
            let id = *bvh
                .prim_ids
                .get(i)
                .ok_or(format!("leaf at {first} runs past the triangles"))?;
            if let Some(pieces) = pieces.as_mut() {
                if bvh.prim_ids[first..i].contains(&id) {
                    return Err(format!("triangle {id} twice in the leaf at {first}"));
                }
                pieces.push((id, *bounds));
            } else if !bounds.contains_box(&mesh.triangle(id as usize).bounds()) {
                return Err(format!("leaf box does not contain triangle {id}"));
            }
        }
        *covered += r.count as usize;
        return Ok(());
    }
    let at = r.index as usize;
    if at != *interior {
        return Err(format!(
            "node {at} reached out of depth-first order (expected {})",
            *interior
        ));
    }
    *interior += 1;
    let node = bvh
        .nodes
        .get(at)
        .ok_or(format!("node index {at} out of range"))?;
    for i in 0..2 {
        let child = node.child_bounds(i);
        if !bounds.contains_box(&child) {
            return Err(format!("child {i} of node {at} is not inside its parent"));
        }
        walk(
            bvh,
            mesh,
            node.child[i],
            &child,
            depth + 1,
            (&mut *covered, &mut *interior),
            pieces,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams};
    use raybench_accel::Accel;
    use std::sync::Arc;

    fn built() -> (Bvh, Arc<raybench_geom::TriangleMesh>) {
        let mesh = raybench_testkit::generated("soup:triangles=500", 3);
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
        let mut b = bvh.nodes[1].child_bounds(0);
        b.max.x += 10.0;
        bvh.nodes[1].set_child_bounds(0, &b);
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
        let (node, side) = (0..bvh.nodes.len())
            .flat_map(|n| [(n, 0), (n, 1)])
            .find(|&(n, i)| bvh.nodes[n].child[i].is_leaf())
            .unwrap();
        let b = bvh.nodes[node].child_bounds(side);
        bvh.nodes[node].set_child_bounds(side, &raybench_geom::Aabb::new(b.max, b.max));
        let err = bvh.validate(&mesh).unwrap_err();
        assert!(
            err.contains("does not contain") || err.contains("not inside"),
            "{err}"
        );
    }

    #[test]
    fn a_wrong_second_child_is_caught() {
        let (mut bvh, mesh) = built();
        bvh.nodes[0].child[1].index += 1;
        assert!(bvh.validate(&mesh).is_err());
    }
}
