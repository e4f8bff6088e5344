//! k-d tree closest-point cases on top of the shared point suite: points lying exactly in split
//! planes, the zero-area side tree, and what the counters must show (pruning, the mailbox, the
//! radius).

use raybench_accel::{Accel, Counters};
use raybench_geom::{Aabb, Triangle, TriangleMesh, Vec3};
use raybench_kdtree::{KdParams, KdTree};
use raybench_testkit::generated;
use raybench_testkit::points::{
    check_points, counted_work as work, points_in_box, points_near_surface,
};
use std::sync::Arc;

const SEED: u64 = 0x5eed_7d01;

fn soup(n: usize) -> Arc<TriangleMesh> {
    generated(&format!("soup:triangles={n}"), SEED)
}

fn near_points(mesh: &TriangleMesh, n: usize) -> Vec<Vec3> {
    points_near_surface(mesh, n, 0.01 * mesh.bounds().diagonal(), SEED)
}

/// Points with one coordinate exactly on a split plane of the tree: the point is in both
/// closed cells, and either may be entered first.
#[test]
fn points_in_split_planes() {
    for spec in ["coplanar:triangles=3000", "city:triangles=3000"] {
        let mesh = generated(spec, SEED);
        for params in [KdParams::sah(), KdParams::median()] {
            let kd = KdTree::build(mesh.clone(), &params).unwrap();
            kd.validate(&mesh).unwrap();
            let splits: Vec<(usize, f32)> = kd
                .nodes()
                .iter()
                .filter(|n| !n.is_leaf())
                .map(|n| (n.axis(), n.split()))
                .collect();
            let mut points = points_in_box(&kd.bounds().enlarged(0.05), 1500, SEED);
            for (i, p) in points.iter_mut().enumerate() {
                let (axis, split) = splits[i % splits.len()];
                p[axis] = split;
            }
            let counts = check_points(&kd, &mesh, &points, f32::INFINITY)
                .unwrap_or_else(|e| panic!("{spec}: {e}"));
            assert_eq!(counts.answered(), 1500, "{spec}: {counts:?}");
            let small = 0.01 * mesh.bounds().diagonal();
            let counts =
                check_points(&kd, &mesh, &points, small).unwrap_or_else(|e| panic!("{spec}: {e}"));
            assert!(counts.answered() > 10, "{spec}: {counts:?}");
        }
    }
}

/// Near the surface, the search opens a few leaves and tests a few triangles, not the tree.
#[test]
fn pruning_keeps_near_surface_queries_local() {
    let mesh = soup(3000);
    let kd = KdTree::build(mesh.clone(), &KdParams::sah()).unwrap();
    let points = near_points(&mesh, 1000);
    let c = work(&kd, &points, f32::INFINITY);
    let per = |x: u64| x as f64 / points.len() as f64;
    let leaves = kd.build_stats().leaves as f64;
    eprintln!(
        "per query: {} tests, {} leaves of {leaves}",
        per(c.prim_tests),
        per(c.leaves)
    );
    // Measured 4.7 tests and 1.5 leaves (of 3854) per query; a walk that stopped pruning
    // would test hundreds.
    assert!(per(c.prim_tests) < 15.0, "of 3000 triangles: {c:?}");
    assert!(per(c.leaves) < 10.0, "of {leaves} leaves: {c:?}");
}

/// The mailbox only turns repeated tests into skips: the same walk (nodes, leaves, answers),
/// and every skip is a test the walk without it performs.
#[test]
fn the_mailbox_changes_the_work_not_the_walk() {
    let mesh = soup(3000);
    let with = KdTree::build(mesh.clone(), &KdParams::sah()).unwrap();
    let without = KdTree::build(
        mesh.clone(),
        &KdParams {
            mailbox: false,
            ..KdParams::sah()
        },
    )
    .unwrap();
    let mut points = near_points(&mesh, 500);
    points.extend(points_in_box(&mesh.bounds().enlarged(0.2), 500, SEED));
    for &p in &points {
        let (mut a, mut b) = (Counters::default(), Counters::default());
        let hit = with.closest_point_counted(p, f32::INFINITY, &mut a);
        assert_eq!(hit, without.closest_point_counted(p, f32::INFINITY, &mut b));
        assert_eq!((a.nodes, a.leaves), (b.nodes, b.leaves), "{p}");
        assert_eq!(a.prim_tests + a.mailbox_skips, b.prim_tests, "{p}");
        assert_eq!(b.mailbox_skips, 0);
    }
    assert!(work(&with, &points, f32::INFINITY).mailbox_skips > 100);
}

/// A finite radius prunes from the start; a point farther than the radius from the whole tree
/// costs no node at all.
#[test]
fn the_radius_prunes_from_the_start() {
    let mesh = soup(3000);
    let kd = KdTree::build(mesh.clone(), &KdParams::sah()).unwrap();
    let points = points_in_box(&mesh.bounds().enlarged(0.2), 1000, SEED);
    let all = work(&kd, &points, f32::INFINITY);
    let near = work(&kd, &points, 0.01);
    assert!(near.prim_tests < all.prim_tests / 2, "{near:?} vs {all:?}");
    assert!(near.nodes < all.nodes, "{near:?} vs {all:?}");
    let far = mesh.bounds().max + Vec3::splat(10.0);
    let mut c = Counters::default();
    assert_eq!(kd.closest_point_counted(far, 1.0, &mut c), None);
    assert_eq!(c, Counters::default());
    let hit = kd
        .closest_point_counted(far, f32::INFINITY, &mut c)
        .unwrap();
    assert!(hit.distance > 17.0 && c.leaves >= 1, "{hit:?} {c:?}");
}

/// A soup with segment and point triangles (no ray ever hits them) placed where they are the
/// nearest feature: found through the side tree, which rays never walk.
#[test]
fn zero_area_triangles_are_found_through_the_side_tree() {
    let mut tris: Vec<Triangle> = soup(500).triangles().collect();
    let hittable = tris.len() as u32;
    let mut rng = raybench_geom::SplitMix64::new(SEED);
    let mut f = move || rng.unit();
    let mut probes = Vec::new();
    for i in 0..300 {
        // Outside the soup's unit box, so nothing else is nearer.
        let a = Vec3::new(f(), f(), f()) * 3.0 + Vec3::new(2.0, 0.0, 0.0);
        let b = a + Vec3::new(f(), f(), f()) * 0.1;
        // A repeated vertex makes the normal exactly zero (a computed midpoint would not).
        tris.push(if i % 2 == 0 {
            Triangle::new(a, b, b)
        } else {
            Triangle::new(a, a, a)
        });
        probes.push((hittable + i, a));
    }
    let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
    let kd = KdTree::build(mesh.clone(), &KdParams::sah()).unwrap();
    kd.validate(&mesh).unwrap();
    let stats = kd.build_stats();
    assert_eq!(stats.extra["excluded_degenerate"], 300.0);
    assert!(stats.extra["zero_area_tree_refs"] >= 300.0, "{stats:?}");
    for (prim, at) in probes {
        // Exactly on the zero-area triangle's first vertex: distance 0 (another zero-area
        // triangle may share the spot only by chance, with a higher id).
        let hit = kd.closest_point(at, 0.0).unwrap();
        assert_eq!((hit.distance, hit.point), (0.0, at));
        assert!(hit.prim <= prim, "{hit:?} for {prim}");
    }
    let mut points = near_points(&mesh, 1000);
    points.extend(points_in_box(&mesh.bounds(), 1000, SEED));
    let counts = check_points(&kd, &mesh, &points, f32::INFINITY).unwrap();
    assert!(counts.exact > 1500, "{counts:?}");
    // A mesh of zero-area triangles only: no tree for rays, every point answered.
    let only: Vec<Triangle> = tris[hittable as usize..].to_vec();
    let mesh = Arc::new(TriangleMesh::from_triangles(&only).unwrap().0);
    let kd = KdTree::build(mesh.clone(), &KdParams::median()).unwrap();
    kd.validate(&mesh).unwrap();
    assert!(kd.nodes().is_empty());
    let points = points_in_box(&Aabb::new(Vec3::ZERO, Vec3::splat(6.0)), 500, SEED);
    let counts = check_points(&kd, &mesh, &points, f32::INFINITY).unwrap();
    assert_eq!(counts.exact, 500, "{counts:?}");
}
