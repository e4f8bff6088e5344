//! The invariants of a built octree, checked by tests after every build.

use crate::Octree;
use crate::build::{enlarged, root_box};
use crate::node::{MAX_DEPTH_LIMIT, child_box, mid};
use raybench_geom::tribox::TriBox;
use raybench_geom::{MollerTriangle, TriangleMesh, Vec3};

/// The root box is the cube around the mesh; every interior node splits at the centre of its
/// box and has at least one child; every node is reached exactly once, within MAX_DEPTH; leaf
/// ranges tile the reference array in depth-first order and are strictly ascending; every
/// reference overlaps its leaf (full 13-axis test on the enlarged leaf box); and every
/// triangle is in every leaf it overlaps and never overlaps a missing (empty) octant — found by
/// descending from the root with the same test.
pub(crate) fn validate(tree: &Octree, mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.len();
    if tree.triangles.len() != n {
        return Err(format!(
            "{} triangle copies for a mesh of {n}",
            tree.triangles.len()
        ));
    }
    for (i, t) in tree.triangles.iter().enumerate() {
        if *t != MollerTriangle::new(&mesh.triangle(i)) {
            return Err(format!("triangle copy {i} is not mesh triangle {i}"));
        }
    }
    let limit_ok = match tree.params.max_depth {
        Some(d) => tree.depth_limit == d,
        None => tree.depth_limit <= MAX_DEPTH_LIMIT,
    };
    if !limit_ok {
        return Err(format!(
            "depth limit {} for MAX_DEPTH {:?} (at most {MAX_DEPTH_LIMIT})",
            tree.depth_limit, tree.params.max_depth
        ));
    }
    let expected_root = root_box(&mesh.bounds());
    if tree.root_box != expected_root {
        return Err(format!(
            "root box {:?} is not the cube around the mesh {:?}",
            tree.root_box, expected_root
        ));
    }
    if tree.nodes.is_empty() {
        return if n == 0 && tree.refs.is_empty() {
            Ok(())
        } else {
            Err("no nodes for a non-empty mesh".into())
        };
    }
    let mut walk = Walk {
        tree,
        mesh,
        reached: vec![false; tree.nodes.len()],
        covered: 0,
    };
    walk.node(0, tree.root_box.min, tree.root_box.max, 0)?;
    if let Some(i) = walk.reached.iter().position(|r| !r) {
        return Err(format!("node {i} is not reachable from the root"));
    }
    if walk.covered != tree.refs.len() {
        return Err(format!(
            "leaves hold {} references, the array has {}",
            walk.covered,
            tree.refs.len()
        ));
    }
    // Completeness: descend with each triangle.
    for prim in 0..n as u32 {
        let tb = TriBox::new(&mesh.triangle(prim as usize));
        let (lo, hi) = enlarged(tree.root_box.min, tree.root_box.max);
        if !tb.overlaps(lo, hi) {
            let (blo, bhi) = tb.bounds();
            if blo.cmple(bhi).all() {
                return Err(format!("triangle {prim} lies outside the root box"));
            }
            continue; // NaN: overlaps nothing (never in a mesh)
        }
        descend(tree, &tb, prim, 0, tree.root_box.min, tree.root_box.max)?;
    }
    Ok(())
}

struct Walk<'a> {
    tree: &'a Octree,
    mesh: &'a TriangleMesh,
    reached: Vec<bool>,
    covered: usize,
}

impl Walk<'_> {
    fn node(&mut self, at: usize, lo: Vec3, hi: Vec3, depth: u32) -> Result<(), String> {
        let tree = self.tree;
        if depth > tree.depth_limit {
            return Err(format!(
                "node {at} at depth {depth} beyond MAX_DEPTH {}",
                tree.depth_limit
            ));
        }
        let reached = self
            .reached
            .get_mut(at)
            .ok_or(format!("node index {at} out of range"))?;
        if std::mem::replace(reached, true) {
            return Err(format!("node {at} reached twice"));
        }
        let node = tree.nodes[at];
        if node.is_leaf() {
            let range = node.refs();
            if range.start != self.covered {
                return Err(format!(
                    "leaf {at} starts at reference {}, expected {} (depth-first order)",
                    range.start, self.covered
                ));
            }
            let list = tree
                .refs
                .get(range.clone())
                .ok_or(format!("leaf {at} runs past the references"))?;
            if list.is_empty() {
                return Err(format!("leaf {at} is empty (empty octants are not stored)"));
            }
            if let Some(w) = list.windows(2).find(|w| w[0] >= w[1]) {
                return Err(format!(
                    "leaf {at}: references not strictly ascending ({} then {})",
                    w[0], w[1]
                ));
            }
            let (elo, ehi) = enlarged(lo, hi);
            for &prim in list {
                if prim as usize >= self.mesh.len() {
                    return Err(format!("leaf {at}: triangle id {prim} out of range"));
                }
                if !TriBox::new(&self.mesh.triangle(prim as usize)).overlaps(elo, ehi) {
                    return Err(format!(
                        "triangle {prim} is in leaf {at}, which it does not overlap"
                    ));
                }
            }
            self.covered = range.end;
            return Ok(());
        }
        let m = mid(lo, hi);
        if node.mid != m.to_array() {
            return Err(format!(
                "node {at} splits at {:?}, not its centre {m:?}",
                node.mid
            ));
        }
        if node.mask() == 0 {
            return Err(format!("interior node {at} has no children"));
        }
        for o in 0..8 {
            if let Some(child) = node.child(o) {
                let (clo, chi) = child_box(lo, hi, m, o);
                self.node(child as usize, clo, chi, depth + 1)?;
            }
        }
        Ok(())
    }
}

/// The triangle overlaps node `at` (box `[lo, hi]`): it must be in the leaf, or in every
/// present child it overlaps, and overlap no missing one.
fn descend(
    tree: &Octree,
    tb: &TriBox,
    prim: u32,
    at: u32,
    lo: Vec3,
    hi: Vec3,
) -> Result<(), String> {
    let node = tree.nodes[at as usize];
    if node.is_leaf() {
        return if tree.refs[node.refs()].binary_search(&prim).is_ok() {
            Ok(())
        } else {
            Err(format!(
                "triangle {prim} overlaps leaf {at} but is not in it"
            ))
        };
    }
    let m = Vec3::from_array(node.mid);
    for o in 0..8 {
        let (clo, chi) = child_box(lo, hi, m, o);
        let (elo, ehi) = enlarged(clo, chi);
        if !tb.overlaps(elo, ehi) {
            continue;
        }
        match node.child(o) {
            Some(child) => descend(tree, tb, prim, child, clo, chi)?,
            None => {
                return Err(format!(
                    "triangle {prim} overlaps octant {o} of node {at}, which is missing"
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{Octree, OctreeParams};
    use raybench_accel::Accel;
    use std::sync::Arc;

    fn built() -> (Octree, Arc<raybench_geom::TriangleMesh>) {
        let mesh = raybench_testkit::generated("soup:triangles=500", 3);
        (
            Octree::build(mesh.clone(), &OctreeParams::default()).unwrap(),
            mesh,
        )
    }

    fn leaf_with(tree: &Octree, k: usize) -> usize {
        (0..tree.nodes.len())
            .find(|&i| tree.nodes[i].is_leaf() && tree.nodes[i].refs().len() >= k)
            .expect("a leaf")
    }

    #[test]
    fn a_sound_tree_passes() {
        let (tree, mesh) = built();
        assert!(tree.nodes.len() > 20, "a real tree: {}", tree.nodes.len());
        assert_eq!(tree.validate(&mesh), Ok(()));
    }

    #[test]
    fn a_reference_replaced_by_another_triangle_is_caught() {
        let (mut tree, mesh) = built();
        let leaf = leaf_with(&tree, 1);
        let at = tree.nodes[leaf].refs().start;
        // A triangle far away in id (and so, in a soup, in space).
        let other = (tree.refs[at] + 250) % 500;
        tree.refs[at] = other;
        let err = tree.validate(&mesh).unwrap_err();
        assert!(
            err.contains("does not overlap")
                || err.contains("not strictly ascending")
                || err.contains("but is not in it"),
            "{err}"
        );
    }

    #[test]
    fn a_duplicate_is_caught() {
        let (mut tree, mesh) = built();
        let leaf = leaf_with(&tree, 2);
        let at = tree.nodes[leaf].refs().start;
        tree.refs[at + 1] = tree.refs[at];
        assert!(
            tree.validate(&mesh)
                .unwrap_err()
                .contains("not strictly ascending")
        );
    }

    #[test]
    fn a_missing_child_is_caught() {
        let (mut tree, mesh) = built();
        let mask = tree.nodes[0].mask();
        let last = 31 - mask.leading_zeros(); // the highest present octant
        tree.nodes[0].set_mask((mask & !(1 << last)) as u8);
        let err = tree.validate(&mesh).unwrap_err();
        assert!(
            err.contains("missing") || err.contains("not reachable"),
            "{err}"
        );
    }

    #[test]
    fn a_moved_split_point_is_caught() {
        let (mut tree, mesh) = built();
        tree.nodes[0].mid[1] += 0.01;
        assert!(tree.validate(&mesh).unwrap_err().contains("centre"));
    }

    #[test]
    fn a_wrong_triangle_copy_or_root_is_caught() {
        let (mut tree, mesh) = built();
        tree.triangles[3].e1.y += 1.0;
        assert!(tree.validate(&mesh).unwrap_err().contains("copy 3"));
        let (mut tree, mesh) = built();
        tree.root_box.max.x += 1.0;
        assert!(tree.validate(&mesh).unwrap_err().contains("root box"));
    }
}
