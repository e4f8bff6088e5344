//! The spatial builder's references, and the validators on trees with duplicated references.

use crate::build::{Flat, build};
use crate::node::ChildRef;
use crate::{Bvh, Bvh8, BvhParams, WideParams};
use raybench_accel::Accel;
use raybench_geom::{Aabb, TriangleMesh};
use std::sync::Arc;

fn mesh(spec: &str) -> Arc<TriangleMesh> {
    raybench_testkit::generated(spec, 4)
}

/// Every leaf's records with the leaf's box, from the flat tree the builder returns.
fn leaves(flat: &Flat) -> Vec<(Aabb, std::ops::Range<usize>)> {
    fn visit(f: &Flat, r: ChildRef, b: Aabb, out: &mut Vec<(Aabb, std::ops::Range<usize>)>) {
        if r.is_leaf() {
            out.push((b, r.index as usize..(r.index + r.count) as usize));
            return;
        }
        let node = &f.nodes[r.index as usize];
        for i in 0..2 {
            visit(f, node.child[i], node.child_bounds(i), out);
        }
    }
    let mut out = Vec::new();
    visit(flat, flat.root, flat.root_bounds, &mut out);
    out
}

/// Each reference's own (clipped) box lies inside its leaf's box and its triangle's box, and a
/// triangle's reference boxes together cover it: the property the leaf-box check of the
/// validators rests on, here on the references themselves.
#[test]
fn reference_boxes_lie_in_their_leaf_and_triangle_and_cover_it() {
    for spec in ["hair:triangles=3000", "soup:triangles=3000", "one-centroid"] {
        let mesh = mesh(spec);
        let flat = build(&mesh, &WideParams::sbvh().binary).expect("builds");
        assert!(
            flat.refs.len() > mesh.len(),
            "{spec}: some references are split"
        );
        let mut pieces = Vec::new();
        for (leaf, range) in leaves(&flat) {
            for r in &flat.refs[range] {
                let b = r.bounds().to_aabb();
                let tri = mesh.triangle(r.id() as usize).bounds();
                assert!(leaf.contains_box(&b), "{spec}: reference outside its leaf");
                assert!(
                    tri.contains_box(&b),
                    "{spec}: reference outside its triangle"
                );
                pieces.push((r.id(), b));
            }
        }
        crate::cover::check_references(&mesh, pieces).unwrap_or_else(|e| panic!("{spec}: {e}"));
    }
}

/// Triangles sharing one centroid defeat every object split; spatial splits separate them
/// and lower the SAH cost below the binned tree's forced halves.
#[test]
fn one_centroid_is_split_by_planes() {
    let mesh = mesh("one-centroid");
    let sbvh = Bvh8::build(mesh.clone(), &WideParams::sbvh()).expect("builds");
    sbvh.validate(&mesh).expect("validates");
    let binned = Bvh8::build(mesh.clone(), &WideParams::default()).expect("builds");
    let (s, b) = (sbvh.build_stats(), binned.build_stats());
    assert!(s.extra["spatial_splits"] > 0.0, "{s:?}");
    assert!(s.sah_cost < b.sah_cost, "{s:?} {b:?}");
}

/// A binary tree with a split triangle and the index of a leaf holding one of its pieces.
fn split_tree() -> (Bvh, Arc<TriangleMesh>, usize, usize) {
    let mesh = mesh("hair:triangles=2000");
    let bvh = Bvh::build(mesh.clone(), &BvhParams::sbvh()).expect("builds");
    bvh.validate(&mesh).expect("a sound tree passes");
    let ids = bvh.prim_ids();
    let twice = (0..ids.len())
        .find(|&i| ids.iter().filter(|&&o| o == ids[i]).count() > 1)
        .expect("a duplicated triangle");
    let (node, side) = (0..bvh.nodes.len())
        .flat_map(|n| [(n, 0), (n, 1)])
        .find(|&(n, s)| {
            let c = bvh.nodes[n].child[s];
            c.is_leaf() && (c.index as usize..(c.index + c.count) as usize).contains(&twice)
        })
        .expect("the leaf holding it");
    (bvh, mesh, node, side)
}

#[test]
fn a_leaf_box_shrunk_off_a_split_triangle_is_caught() {
    let (mut bvh, mesh, node, side) = split_tree();
    let b = bvh.nodes[node].child_bounds(side);
    let mid = (b.min + b.max) * 0.5;
    bvh.nodes[node].set_child_bounds(side, &Aabb::new(b.min, mid));
    let err = bvh.validate(&mesh).unwrap_err();
    assert!(err.contains("cover") || err.contains("misses"), "{err}");
}

#[test]
fn a_triangle_twice_in_one_leaf_is_caught() {
    let (mut bvh, mesh, _, _) = split_tree();
    let leaf = (0..bvh.nodes.len())
        .flat_map(|n| bvh.nodes[n].child)
        .find(|c| c.count >= 2)
        .expect("a leaf of two or more");
    let (a, b) = (leaf.index as usize, leaf.index as usize + 1);
    bvh.prim_ids[b] = bvh.prim_ids[a];
    bvh.triangles[b] = bvh.triangles[a];
    let err = bvh.validate(&mesh).unwrap_err();
    assert!(err.contains("twice in the leaf"), "{err}");
}
