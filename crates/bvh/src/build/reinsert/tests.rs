//! The optimizer's arithmetic against the tree it edits: a move's priced gain is the area it
//! removes, the branch and bound finds the best destination an exhaustive scan finds, and the
//! conversion to and from the flat form loses nothing.

use super::search::{Marks, best_move, exact_gain};
use super::tree::{Kind, Tree};
use super::{interior_area, optimize};
use crate::build::{Flat, build};
use crate::{BvhParams, Reinsertion};

fn flat(spec: &str, seed: u64, p: &BvhParams) -> Flat {
    build(&raybench_testkit::generated(spec, seed), p).expect("builds")
}

/// A fixed pseudo-random sequence (xorshift), so the pairs tried are the same on every run.
fn pairs(n: usize, count: usize, mut s: u64) -> Vec<(u32, u32)> {
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % n as u64) as u32
    };
    (0..count).map(|_| (next(), next())).collect()
}

const NO_DEPTH_LIMIT: u32 = u32::MAX;

#[test]
fn a_priced_move_saves_exactly_its_gain() {
    let f = flat("soup:triangles=2000", 4, &BvhParams::median());
    let mut t = Tree::from_flat(&f);
    let mut marks = Marks::new(t.len());
    let (mut applied, mut refused) = (0, 0);
    for (x, c) in pairs(t.len(), 3000, 0x9e37_79b9_7f4a_7c15) {
        let Some(g) = exact_gain(&t, x, c, NO_DEPTH_LIMIT, &mut marks) else {
            refused += 1;
            continue;
        };
        let before = interior_area(&t);
        t.move_next_to(x, c);
        let after = interior_area(&t);
        assert!(
            (before - after - g).abs() <= 1e-9 * before,
            "moving {x} next to {c}: priced {g}, saved {}",
            before - after
        );
        applied += 1;
    }
    assert!(
        applied > 1000 && refused > 0,
        "{applied} applied, {refused} refused"
    );
}

#[test]
fn illegal_destinations_are_refused() {
    let f = flat("soup:triangles=500", 2, &BvhParams::binned());
    let t = Tree::from_flat(&f);
    let mut marks = Marks::new(t.len());
    // The deepest leaf, its ancestors and the root.
    let leaf = (0..t.len() as u32).max_by_key(|&n| {
        let mut d = 0;
        let mut a = n;
        while a != t.root {
            a = t.parent[a as usize];
            d += 1;
        }
        d
    });
    let leaf = leaf.expect("nodes");
    let mut up = t.parent[leaf as usize];
    while up != super::tree::NONE {
        assert_eq!(exact_gain(&t, leaf, up, NO_DEPTH_LIMIT, &mut marks), None);
        // Nor into its own subtree.
        assert_eq!(exact_gain(&t, up, leaf, NO_DEPTH_LIMIT, &mut marks), None);
        up = t.parent[up as usize];
    }
    assert_eq!(
        exact_gain(&t, t.root, leaf, NO_DEPTH_LIMIT, &mut marks),
        None
    );
    assert_eq!(exact_gain(&t, leaf, leaf, NO_DEPTH_LIMIT, &mut marks), None);
    // Too deep: any destination puts the leaf at depth 1 or more.
    let other = t.sibling(t.parent[leaf as usize]);
    assert_eq!(exact_gain(&t, leaf, other, 0, &mut marks), None);
    assert!(exact_gain(&t, leaf, other, NO_DEPTH_LIMIT, &mut marks).is_some());
}

/// On a tree small enough to try every destination, the branch and bound finds the best one.
#[test]
fn the_search_finds_the_best_destination() {
    let f = flat("soup:triangles=300", 9, &BvhParams::median());
    let t = Tree::from_flat(&f);
    let mut marks = Marks::new(t.len());
    let mut stack = Vec::new();
    let mut found = 0;
    for x in (0..t.len() as u32).filter(|&x| x != t.root) {
        let best = (0..t.len() as u32)
            .filter_map(|c| exact_gain(&t, x, c, NO_DEPTH_LIMIT, &mut marks))
            .fold(0.0f64, f64::max);
        match best_move(&t, x, &mut stack) {
            Some(m) => {
                found += 1;
                let exact = exact_gain(&t, x, m.to, NO_DEPTH_LIMIT, &mut marks).expect("legal");
                assert!(
                    (m.gain - exact).abs() <= 1e-9 * best,
                    "{m:?} priced {exact}"
                );
                assert!(m.gain >= best * (1.0 - 1e-9), "{m:?}, exhaustive {best}");
            }
            None => assert!(best <= 1e-9 * interior_area(&t), "missed a gain of {best}"),
        }
    }
    assert!(found > 20, "only {found} nodes could move");
}

#[test]
fn the_flat_round_trip_is_exact() {
    let f = flat("teapot:triangles=3000", 1, &BvhParams::binned());
    let t = Tree::from_flat(&f);
    assert!(matches!(t.kind[0], Kind::Interior(_)));
    let back = t.into_flat(&f.refs);
    assert!(back.nodes == f.nodes);
    assert_eq!(back.root, f.root);
    assert_eq!(back.root_bounds, f.root_bounds);
    assert_eq!(back.prim_ids(), f.prim_ids());
}

/// Every reference survives, duplicates included: a flat tree whose refs repeat a mesh index
/// (as spatial splits make) comes back with the same multiset of ids, each leaf's records
/// together.
#[test]
fn duplicated_references_are_carried_as_they_are() {
    let p = BvhParams {
        reinsertion: Some(Reinsertion {
            batch_fraction: 0.5,
            ..Reinsertion::default()
        }),
        ..BvhParams::median()
    };
    let mut f = flat("soup:triangles=1000", 5, &p);
    let copy = f.refs[0];
    for r in f.refs.iter_mut().step_by(7) {
        *r = copy;
    }
    let mut before = f.prim_ids();
    let (out, stats) = optimize(f, &p);
    let stats = stats.expect("asked for");
    assert!(
        stats.moves > 0 && stats.sah_after < stats.sah_before,
        "{stats:?}"
    );
    let mut after = out.prim_ids();
    before.sort_unstable();
    after.sort_unstable();
    assert_eq!(before, after);
}
