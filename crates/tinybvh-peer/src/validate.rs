//! Invariants of the node arrays tinybvh-rs exposes, checked after a build: the binary Wald BVH
//! every entry starts from and, for BVH8_CPU, the 8-wide MBVH it is converted from (the
//! BVH8_CPU blocks themselves are not exposed by the crate).

use tinybvh_rs::{bvh, mbvh};

/// tinybvh's traversal stacks hold 256 entries (`BVH::Intersect`, `BVH8_CPU::Intersect`); a
/// root-to-leaf path shorter than that cannot overflow them.
const STACK_ENTRIES: usize = 256;

fn inside(min: [f32; 3], max: [f32; 3], pmin: [f32; 3], pmax: [f32; 3]) -> bool {
    (0..3).all(|a| min[a] >= pmin[a] && max[a] <= pmax[a])
}

/// The Wald BVH over `positions`: every node reached once from the root, children inside their
/// parent, depth below the traversal stack, every leaf's triangle references in range. With
/// `exact_partition` (binned builds, no spatial splits) every triangle is referenced exactly once
/// and lies inside its leaf's box; an SBVH's references are checked as far as tinybvh-rs
/// exposes them (see below).
pub(crate) fn wald(
    data: &bvh::BVHData,
    positions: &[[f32; 4]],
    exact_partition: bool,
) -> Result<Vec<u32>, String> {
    let nodes = data.nodes();
    let indices = data.indices();
    let tris = positions.len() / 3;
    let mut refs = vec![0u32; tris];
    let mut seen = vec![false; nodes.len()];
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        let node = nodes
            .get(i)
            .ok_or(format!("node {i} out of {}", nodes.len()))?;
        if std::mem::replace(&mut seen[i], true) {
            return Err(format!("node {i} reached twice"));
        }
        if depth >= STACK_ENTRIES {
            return Err(format!("node {i} at depth {depth}"));
        }
        if node.is_leaf() {
            let (first, count) = (node.left_first as usize, node.tri_count as usize);
            // tinybvh-rs exposes `triCount` references, but an SBVH stores `idxCount` (more,
            // with spatial splits): references past the slice cannot be read, only a binned
            // build's must all be in it.
            let end = if exact_partition {
                first + count
            } else {
                (first + count)
                    .min(indices.len())
                    .max(first.min(indices.len()))
            };
            let range = indices
                .get(first.min(end)..end)
                .ok_or(format!("leaf {i}: references {first}+{count} out of range"))?;
            for &p in range {
                let p = p as usize;
                *refs.get_mut(p).ok_or(format!("leaf {i}: triangle {p}"))? += 1;
                if exact_partition {
                    for v in &positions[3 * p..3 * p + 3] {
                        let v = [v[0], v[1], v[2]];
                        if !inside(v, v, node.min, node.max) {
                            return Err(format!("leaf {i}: triangle {p} sticks out of its box"));
                        }
                    }
                }
            }
            continue;
        }
        for c in [node.left_first as usize, node.left_first as usize + 1] {
            let child = nodes.get(c).ok_or(format!("node {i}: child {c} missing"))?;
            if c < 2 || !inside(child.min, child.max, node.min, node.max) {
                return Err(format!("node {i}: child {c} not a box inside its parent"));
            }
            stack.push((c, depth + 1));
        }
    }
    // Every triangle exactly once (binned); for an SBVH the unexposed references may hold the
    // only copy of a triangle, so only duplicates-free is not required and nothing is checked.
    if let Some(p) = refs.iter().position(|&r| exact_partition && r != 1) {
        return Err(format!("triangle {p} referenced {} times", refs[p]));
    }
    Ok(refs)
}

/// The MBVH8 a BVH8_CPU is converted from: every node reached once, at most eight children each
/// inside its parent, leaves of at most four triangles (BVH8_CPU's leaf holds four), whose
/// ranges of the Wald BVH's references cover each reference exactly once.
#[cfg_attr(not(target_feature = "avx2"), allow(dead_code))]
pub(crate) fn mbvh8(data: &mbvh::BVHData, wald_refs: usize) -> Result<(), String> {
    let nodes = data.nodes();
    let mut covered = vec![false; wald_refs];
    let mut seen = vec![false; nodes.len()];
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        let node = nodes
            .get(i)
            .ok_or(format!("node {i} out of {}", nodes.len()))?;
        if std::mem::replace(&mut seen[i], true) || depth >= STACK_ENTRIES {
            return Err(format!("node {i} reached twice or at depth {depth}"));
        }
        if node.is_leaf() {
            if node.tri_count > 4 {
                return Err(format!("leaf {i} holds {} triangles", node.tri_count));
            }
            let first = node.first_tri as usize;
            for r in first..first + node.tri_count as usize {
                let slot = covered
                    .get_mut(r)
                    .ok_or(format!("leaf {i}: reference {r}"))?;
                if std::mem::replace(slot, true) {
                    return Err(format!("reference {r} in two leaves"));
                }
            }
            continue;
        }
        // Empty child slots hold 0 and may sit anywhere among the eight; a mesh whose binary
        // BVH is one leaf gets a root with that single child.
        let children = node.child.iter().filter(|&&c| c != 0);
        if children.clone().count() != node.child_count as usize || node.child_count < 1 {
            return Err(format!("node {i}: children {:?}", node.child));
        }
        for &c in children {
            let child = nodes
                .get(c as usize)
                .ok_or(format!("node {i}: child {c}"))?;
            if !inside(child.aabb_min, child.aabb_max, node.aabb_min, node.aabb_max) {
                return Err(format!("node {i}: child {c} outside its parent"));
            }
            stack.push((c as usize, depth + 1));
        }
    }
    match covered.iter().position(|&c| !c) {
        Some(r) => Err(format!("reference {r} in no leaf")),
        None => Ok(()),
    }
}
