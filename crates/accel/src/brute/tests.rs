use super::*;
use crate::Counters;
use raybench_geom::Vec3;

fn two_layers() -> Arc<TriangleMesh> {
    // Two identical triangles at z = 0 (a tie) and one at z = -1.
    let t = |z: f32| {
        Triangle::new(
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(0.0, 1.0, z),
        )
    };
    Arc::new(
        TriangleMesh::from_triangles(&[t(-1.0), t(0.0), t(0.0)])
            .unwrap()
            .0,
    )
}

#[test]
fn closest_hit_and_lowest_prim_on_ties() {
    let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
    let r = Ray::infinite(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let h = bf.intersect(&r).unwrap();
    assert_eq!((h.t, h.prim), (1.0, 1));
    let mut c = Counters::default();
    assert_eq!(bf.intersect_counted(&r, &mut c), Some(h));
    assert_eq!(c.prim_tests, 3);
    assert!(bf.occluded(&r));
    let mut c = Counters::default();
    assert!(bf.occluded_counted(&r, &mut c));
    assert_eq!(c.prim_tests, 1, "any hit stops at the first hit");
}

#[test]
fn empty_mesh_misses() {
    let (mesh, _) = TriangleMesh::new(vec![], vec![]).unwrap();
    let bf = BruteForce::build(Arc::new(mesh), &Default::default()).unwrap();
    let r = Ray::infinite(Vec3::ZERO, Vec3::X);
    assert_eq!(bf.intersect(&r), None);
    assert!(!bf.occluded(&r));
}

#[test]
fn closest_point_is_nearest_with_lowest_prim_on_ties() {
    let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
    let p = Vec3::new(0.2, 0.2, 1.0);
    let h = bf.closest_point(p, f32::INFINITY).unwrap();
    assert_eq!((h.prim, h.distance), (1, 1.0));
    // Face region: the barycentric weights are rounded, the point is not exactly (0.2, 0.2).
    assert!(
        h.point.distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6,
        "{}",
        h.point
    );
    let mut c = Counters::default();
    assert_eq!(bf.closest_point_counted(p, f32::INFINITY, &mut c), Some(h));
    assert_eq!(c.prim_tests, 3, "one distance test per triangle");
    // Below both layers: the z = -1 triangle (prim 0) is nearer.
    let below = bf.closest_point(Vec3::new(0.2, 0.2, -1.5), f32::INFINITY);
    assert_eq!(below.map(|h| (h.prim, h.distance)), Some((0, 0.5)));
}

#[test]
fn closest_point_radius_is_inclusive() {
    let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
    let p = Vec3::new(0.2, 0.2, 1.0);
    assert_eq!(bf.closest_point(p, 1.0).map(|h| h.prim), Some(1));
    assert_eq!(bf.closest_point(p, 0.999), None);
    let on_surface = Vec3::new(0.0, 0.0, 0.0);
    assert_eq!(bf.closest_point(on_surface, 0.0).map(|h| h.prim), Some(1));
}

#[test]
fn closest_point_rejects_bad_queries_without_panicking() {
    let bf = BruteForce::build(two_layers(), &Default::default()).unwrap();
    let mut c = Counters::default();
    for (p, r) in [
        (Vec3::new(f32::NAN, 0.0, 0.0), f32::INFINITY),
        (Vec3::new(0.0, f32::INFINITY, 0.0), f32::INFINITY),
        (Vec3::new(0.0, 0.0, 1e19), f32::INFINITY),
        (Vec3::ZERO, -1.0),
        (Vec3::ZERO, f32::NAN),
    ] {
        assert_eq!(bf.closest_point(p, r), None, "{p} {r}");
        assert_eq!(bf.closest_point_counted(p, r, &mut c), None, "{p} {r}");
    }
    assert_eq!(c.prim_tests, 0, "rejected before any test");
}

#[test]
fn closest_point_on_zero_area_triangle_and_empty_mesh() {
    let a = Vec3::new(1.0, 2.0, 3.0);
    let point = Triangle::new(a, a, a);
    let segment = Triangle::new(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::X);
    let mesh = TriangleMesh::from_triangles(&[point, segment]).unwrap().0;
    let bf = BruteForce::build(Arc::new(mesh), &Default::default()).unwrap();
    let h = bf
        .closest_point(Vec3::new(1.0, 2.0, 4.0), f32::INFINITY)
        .unwrap();
    assert_eq!((h.prim, h.point, h.distance), (0, a, 1.0));
    let h = bf
        .closest_point(Vec3::new(1.5, -2.0, 0.0), f32::INFINITY)
        .unwrap();
    assert_eq!(
        (h.prim, h.point, h.distance),
        (1, Vec3::new(1.5, 0.0, 0.0), 2.0)
    );

    let (empty, _) = TriangleMesh::new(vec![], vec![]).unwrap();
    let bf = BruteForce::build(Arc::new(empty), &Default::default()).unwrap();
    assert_eq!(bf.closest_point(Vec3::ZERO, f32::INFINITY), None);
}

/// `n` triangles of about unit size, their corners around points `spread` apart (`v` draws a
/// point of the unit cube).
fn soup(v: &mut impl FnMut() -> Vec3, n: usize, spread: f32) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let c = v() * spread;
            Triangle::new(c + v() - Vec3::splat(0.5), c + v(), c - v())
        })
        .collect()
}

/// The scan in blocks (the branch-free candidate test first) answers and counts as a plain
/// loop over every triangle with the deciding test, for both triangle tests: closest hit
/// (ties to the lower index, layered and repeated triangles), any hit, and `prim_tests` up
/// to the first hit, on a soup whose last block is partial (its last pack too).
#[test]
fn the_blocked_scan_answers_and_counts_as_one_triangle_at_a_time() {
    let mut rng = raybench_geom::SplitMix64::new(0x2545_f491_4f6c_dd1d);
    let mut next = move || rng.unit();
    let mut v = || Vec3::new(next(), next(), next());
    let mut tris = soup(&mut v, 1_000, 4.0);
    // A repeated triangle in a later block: equal t, the earlier index must win.
    tris.push(tris[7]);
    tris.extend_from_within(40..45);
    let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
    let rays: Vec<Ray> = (0..2_000)
        .map(|i| {
            let o = v() * 6.0 - Vec3::ONE;
            let d = if i % 2 == 0 {
                v() - Vec3::splat(0.5)
            } else {
                mesh.triangle(i % 1_000).v0 - o
            };
            let t_max = if i % 5 == 0 { 2.0 } else { f32::INFINITY };
            Ray::new(o, d, 0.0, t_max)
        })
        .collect();
    for triangle_test in [TriangleTest::MollerTrumbore, TriangleTest::Watertight] {
        let bf = BruteForce::build(mesh.clone(), &BruteForceParams { triangle_test }).unwrap();
        let decide = |prim: usize, r: &Ray| {
            let t = mesh.triangle(prim);
            match triangle_test {
                TriangleTest::MollerTrumbore => MollerTriangle::new(&t).intersect(r),
                TriangleTest::Watertight => t.intersect_watertight(r),
            }
        };
        let (mut hit, mut missed) = (0, 0);
        for (i, &ray) in rays.iter().enumerate() {
            // The plain loop: every triangle in order, the window shrinking at each hit.
            let (mut best, mut r, mut first_hit) = (None::<Hit>, ray, None);
            for prim in 0..mesh.len() {
                if let Some(h) = decide(prim, &r) {
                    first_hit.get_or_insert(prim as u64 + 1);
                    if !best.is_some_and(|b| h.t >= b.t) {
                        best = Some(Hit::from_tri_hit(prim as u32, h));
                        r = r.with_t_max(h.t);
                    }
                }
            }
            let at = format!("{triangle_test:?} ray {i}");
            let mut c = Counters::default();
            assert_eq!(bf.intersect_counted(&ray, &mut c), best, "{at}");
            assert_eq!(c.prim_tests, mesh.len() as u64, "{at}");
            let mut c = Counters::default();
            assert_eq!(bf.occluded_counted(&ray, &mut c), best.is_some(), "{at}");
            assert_eq!(c.prim_tests, first_hit.unwrap_or(mesh.len() as u64), "{at}");
            if best.is_some() {
                hit += 1
            } else {
                missed += 1
            }
        }
        assert!(hit > 500 && missed > 500, "{hit} hits, {missed} misses");
    }
}

/// `intersect_all` answers every ray as `intersect` does, for both triangle tests, on a
/// mesh of three tiles (the last partial) with triangles repeated across a tile boundary
/// (ties, the earlier index winning) and windows ending short of some hits.
#[test]
fn every_ray_at_once_answers_as_ray_by_ray() {
    let mut rng = raybench_geom::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
    let mut next = move || rng.unit();
    let mut v = || Vec3::new(next(), next(), next());
    let mut tris = soup(&mut v, 2 * TILE + 900, 8.0);
    tris.extend_from_within(TILE - 20..TILE + 20);
    let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
    let rays: Vec<Ray> = (0..600)
        .map(|i| {
            let o = v() * 10.0 - Vec3::ONE;
            let d = if i % 2 == 0 {
                v() - Vec3::splat(0.5)
            } else {
                mesh.triangle(TILE - 20 + i % 40).centroid() - o
            };
            Ray::new(o, d, 0.0, if i % 3 == 0 { 0.9 } else { f32::INFINITY })
        })
        .collect();
    for triangle_test in [TriangleTest::MollerTrumbore, TriangleTest::Watertight] {
        let bf = BruteForce::build(mesh.clone(), &BruteForceParams { triangle_test }).unwrap();
        let one_by_one: Vec<_> = rays.iter().map(|r| bf.intersect(r)).collect();
        assert_eq!(bf.intersect_all(&rays), one_by_one, "{triangle_test:?}");
        let hits: Vec<u32> = one_by_one.iter().flatten().map(|h| h.prim).collect();
        assert!(hits.len() > 200, "{triangle_test:?}: {} hits", hits.len());
        // Rays aimed at the repeated triangles hit the first copy, before the boundary.
        assert!(
            hits.iter()
                .any(|&p| (TILE as u32 - 20..TILE as u32).contains(&p))
        );
        assert!(hits.iter().all(|&p| p < 2 * TILE as u32 + 900));
    }
}

/// The closest-point scan with its box skip answers as testing every triangle does, at
/// three scales (unit, tiny and far from the origin), for points near the triangles and
/// far from them, at an infinite radius and a small one, with repeated triangles (ties).
#[test]
fn the_closest_point_scan_answers_as_testing_every_triangle() {
    let mut rng = raybench_geom::SplitMix64::new(0x853c_49e6_748f_ea9b);
    let mut next = move || rng.unit();
    let mut found_some = false;
    for (scale, offset) in [(1.0, 0.0), (1e-15, 0.0), (1.0, 1e6)] {
        let mut v = || Vec3::new(next(), next(), next());
        let at = |x: Vec3| x * scale + Vec3::splat(offset);
        let mut tris: Vec<Triangle> = (0..600)
            .map(|_| {
                let c = v() * 8.0;
                Triangle::new(at(c), at(c + v()), at(c - v()))
            })
            .collect();
        tris.extend_from_within(10..20);
        let mesh = Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0);
        let bf = BruteForce::build(mesh.clone(), &Default::default()).unwrap();
        for i in 0..400 {
            let p = if i % 2 == 0 {
                mesh.triangle(i % tris.len()).v1 + (v() - Vec3::splat(0.5)) * scale * 0.01
            } else {
                at(v() * 12.0 - Vec3::splat(2.0))
            };
            for radius in [f32::INFINITY, 0.5 * scale] {
                let mut every = Nearest::within(p, radius).unwrap();
                let mut distances = 0;
                for (prim, tri) in mesh.triangles().enumerate() {
                    every.test_triangle(p, prim as u32, &tri);
                    distances += 1;
                }
                let mut c = Counters::default();
                let got = bf.closest_point_counted(p, radius, &mut c);
                assert_eq!(got, every.into_hit(), "scale {scale}, point {i}, {radius}");
                assert_eq!(c.prim_tests, distances);
                found_some |= got.is_some();
            }
        }
    }
    assert!(found_some);
}

#[test]
fn usable_as_trait_object() {
    let dynamic = crate::build_dyn::<BruteForce>(two_layers(), &Default::default()).unwrap();
    assert_eq!(dynamic.name(), "bruteforce");
}
