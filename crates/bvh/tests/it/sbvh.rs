//! Spatial splits (`bvh8-sbvh`, and the binary tree with the same knob): the shared suite, a
//! scene where spatial splits must pay off, the reference budget, and thread independence.

use crate::on_threads;
use raybench_accel::{Accel, BuildStats, Counters};
use raybench_bvh::{Bvh, Bvh8, BvhParams, BvhWide, PacketFloors, SpatialSplits, WideParams};
use raybench_testkit::{Case, check_case, conformance};
use std::sync::Arc;

/// The Split BVH's knobs without spatial splits: the binned tree it is measured against (the
/// binned wide trees bound large children's centroids by their boxes; the Split BVH does not).
fn binned_like_sbvh() -> WideParams {
    let mut p = WideParams::sbvh();
    p.binary.spatial_splits = None;
    p
}

fn sbvh(growth: f32) -> WideParams {
    let mut p = WideParams::sbvh();
    p.binary.spatial_splits = Some(SpatialSplits {
        max_reference_growth: growth,
        ..SpatialSplits::default()
    });
    p
}

/// The binary tree with spatial splits, one of its knobs changed by `edit`.
fn binary_sbvh(
    mesh: &Arc<raybench_geom::TriangleMesh>,
    edit: impl FnOnce(&mut SpatialSplits),
) -> Result<Bvh, raybench_accel::BuildError> {
    let mut p = BvhParams::sbvh();
    edit(p.spatial_splits.as_mut().expect("spatial splits"));
    Bvh::build(mesh.clone(), &p)
}

#[test]
fn binary_sbvh_conforms() {
    for params in [
        BvhParams::sbvh(),
        BvhParams {
            max_leaf_size: 1,
            ..BvhParams::sbvh()
        },
    ] {
        let counts = conformance::<Bvh>(&params, &|b, m| b.validate(m));
        assert_eq!(counts.mismatch, 0, "{params:?}");
        assert!(counts.exact > 10_000, "{counts:?}");
    }
}

#[test]
fn wide_sbvh_conforms() {
    for params in [WideParams::sbvh(), sbvh(2.0)] {
        let counts = conformance::<Bvh8>(&params, &|b, m| b.validate(m));
        assert_eq!(counts.mismatch, 0, "{params:?}");
        assert!(counts.exact > 10_000, "{counts:?}");
    }
}

/// The packet walk over `params`' tree, whose leaves share triangles, registered as `name`:
/// the shared suite (whose coherent-batch check holds it to brute force), and on every case's
/// rays the single-ray walk's answers but for ties. A triangle in two leaves a packet reaches is
/// tested twice with the same answer, so duplicates change nothing a lane sees.
fn packets_over_split_references_conform<const W: usize>(params: WideParams, name: &str)
where
    BvhWide<W>: Accel<Params = WideParams>,
{
    let counts = conformance::<BvhWide<W>>(&params, &|b, m| b.validate(m));
    assert_eq!(counts.mismatch, 0, "{params:?}");
    assert!(counts.exact > 10_000, "{counts:?}");
    for case in raybench_testkit::seeded_cases()
        .into_iter()
        .chain(raybench_testkit::edge_cases())
    {
        let bvh = BvhWide::<W>::build(case.mesh.clone(), &params).expect("builds");
        assert_eq!(bvh.name(), name);
        let rays = raybench_testkit::valid_rays(&case);
        raybench_testkit::packets_against_single_rays(&bvh, &case.mesh, &rays, &case.name);
    }
}

/// `bvh8-sbvh-packets`' walk, at two reference budgets.
#[test]
fn packet_walk_over_split_references_conforms() {
    for params in [WideParams::sbvh(), sbvh(2.0)] {
        let params = WideParams {
            coherent_packets: true,
            ..params
        };
        packets_over_split_references_conform::<8>(params, "bvh8-sbvh-packets");
    }
}

/// The same over 16-wide nodes with the registry's floors (`bvh16-sbvh-packets`): the packet
/// bounds rule children out eight slots a pass, two passes a node, and the windows sent ray by
/// ray take the 16-wide walk.
#[test]
fn sixteen_wide_packet_walk_over_split_references_conforms() {
    let params = WideParams {
        width: 16,
        coherent_packets: true,
        packet_floors: PacketFloors::MEASURED,
        ..WideParams::sbvh()
    };
    packets_over_split_references_conform::<16>(params, "bvh16-sbvh-packets");
}

#[test]
fn wide_sbvh_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Bvh8>(&WideParams::sbvh(), &|b, m| {
            b.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}

/// Hair (long thin fibres at every angle) and a scene of long diagonal slivers: seeded rays
/// against brute force, with validation.
#[test]
fn sbvh_conforms_on_fibres() {
    for (spec, seed) in [("hair:triangles=5000", 3), ("soup:triangles=2000", 11)] {
        let mesh = raybench_testkit::generated(spec, seed);
        let mut rays = raybench_testkit::random_rays_in(&mesh.bounds().enlarged(0.1), 4000, seed);
        rays.extend(raybench_testkit::centroid_rays(&mesh, 4000, seed ^ 1));
        let case = Case {
            name: spec.to_string(),
            seed,
            mesh,
            rays,
        };
        let counts = check_case::<Bvh8>(&case, &WideParams::sbvh(), &|b, m| b.validate(m))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(counts.mismatch, 0, "{spec}: {counts:?}");
        let counts = check_case::<Bvh>(&case, &BvhParams::sbvh(), &|b, m| b.validate(m))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(counts.mismatch, 0, "{spec}: {counts:?}");
    }
}

fn stats(mesh: &Arc<raybench_geom::TriangleMesh>, params: &WideParams) -> BuildStats {
    let bvh = Bvh8::build(mesh.clone(), params).expect("builds");
    bvh.validate(mesh).expect("validates");
    bvh.build_stats()
}

/// On hair, spatial splits are taken, they lower the SAH cost below the binned tree's, and the
/// references grow, but no further than the budget.
#[test]
fn spatial_splits_pay_on_hair_within_the_budget() {
    let mesh = raybench_testkit::generated("hair", 1);
    let n = mesh.len() as f64;
    let binned = stats(&mesh, &binned_like_sbvh());
    assert!(!binned.extra.contains_key("spatial_splits"));
    for growth in [0.1, 0.5] {
        let s = stats(&mesh, &sbvh(growth));
        let context = format!("growth {growth}: binned {binned:?}, sbvh {s:?}");
        assert!(s.extra["spatial_splits"] > 0.0, "{context}");
        assert!(s.sah_cost.unwrap() < binned.sah_cost.unwrap(), "{context}");
        let refs = s.refs as f64;
        assert!(refs > n && refs <= n * (1.0 + growth as f64), "{context}");
        assert_eq!(s.extra["reference_growth"], refs / n, "{context}");
    }
}

/// With no budget for duplicates the tree is the binned tree.
#[test]
fn no_budget_builds_the_binned_tree() {
    let mesh = raybench_testkit::generated("hair", 2);
    let a = Bvh8::build(mesh.clone(), &sbvh(0.0)).expect("builds");
    let b = Bvh8::build(mesh.clone(), &binned_like_sbvh()).expect("builds");
    assert!(a.nodes() == b.nodes() && a.tri4s() == b.tri4s());
    assert_eq!(a.build_stats().extra["spatial_splits"], 0.0);
}

/// The tree, its references and every ray's answer and counters are the same on one and two
/// threads (the budget is shared top-down, never first come, first served, and a reference's
/// cuts are counted along its own line of cuts: city's ground reaches the default limit).
#[test]
fn sbvh_is_the_same_with_one_and_two_threads() {
    for spec in [
        "hair",
        "soup:triangles=20000",
        "city:triangles=30000",
        "soup:triangles=3000",
    ] {
        let mesh = raybench_testkit::generated(spec, 5);
        let build = |threads| {
            on_threads(threads, || {
                Bvh8::build(mesh.clone(), &WideParams::sbvh()).expect("builds")
            })
        };
        let (one, two) = (build(1), build(2));
        assert!(
            one.nodes().len() > 100,
            "{spec}: big enough to build in parallel"
        );
        assert!(one.build_stats().extra["spatial_splits"] > 0.0, "{spec}");
        assert!(one.nodes() == two.nodes(), "{spec}: nodes differ");
        assert!(one.tri4s() == two.tri4s(), "{spec}: Tri4s differ");
        for ray in raybench_testkit::random_rays_in(&mesh.bounds(), 3000, 9) {
            let (mut ca, mut cb) = (Counters::default(), Counters::default());
            assert_eq!(
                one.intersect_counted(&ray, &mut ca),
                two.intersect_counted(&ray, &mut cb)
            );
            assert_eq!(ca, cb);
        }
    }
}

/// Knobs out of range are refused, and the memory estimate counts the reference budget.
#[test]
fn bad_bins_are_refused_and_the_budget_is_in_the_estimate() {
    use raybench_accel::BuildError;
    let mesh = raybench_testkit::generated("soup:triangles=2000", 1);
    for bins in [0, 1, 65] {
        assert!(matches!(
            binary_sbvh(&mesh, |s| s.spatial_bins = bins),
            Err(BuildError::Unsupported(_))
        ));
    }
    let needed = |growth: f32| {
        let mut p = BvhParams::sbvh();
        p.memory_limit_bytes = 1;
        p.spatial_splits.as_mut().unwrap().max_reference_growth = growth;
        match Bvh::build(mesh.clone(), &p) {
            Err(BuildError::TooLarge { needed_bytes, .. }) => needed_bytes,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(needed(1.0), 2 * needed(0.0));
}

/// The overlap share decides where a spatial split is searched for: the higher it is, the
/// fewer nodes search (a knob that changed nothing would fail here); every split taken was
/// searched for; and at each share the splits still pay on hair.
#[test]
fn the_overlap_share_limits_where_spatial_splits_are_searched() {
    let mesh = raybench_testkit::generated("hair:triangles=5000", 3);
    let binned = stats(&mesh, &binned_like_sbvh());
    let mut searched_before = f64::INFINITY;
    for share in [0.0, 0.3, 0.9] {
        let mut p = WideParams::sbvh();
        p.binary.spatial_splits.as_mut().unwrap().overlap_share = share;
        let s = stats(&mesh, &p);
        let (splits, searched) = (s.extra["spatial_splits"], s.extra["spatial_searches"]);
        let context = format!("share {share}: {s:?}");
        assert!(searched < searched_before, "{context}");
        assert!(splits > 0.0 && splits <= searched, "{context}");
        assert!(s.sah_cost.unwrap() < binned.sah_cost.unwrap(), "{context}");
        searched_before = searched;
    }
}

/// An overlap share outside 0 to 1 (or NaN) is refused before the build; both ends are taken.
#[test]
fn an_overlap_share_outside_0_to_1_is_refused() {
    use raybench_accel::BuildError;
    let mesh = raybench_testkit::generated("soup:triangles=2000", 1);
    let with = |share: f32| binary_sbvh(&mesh, |s| s.overlap_share = share);
    for share in [-0.1, 1.5, f32::NAN] {
        assert!(
            matches!(with(share), Err(BuildError::Unsupported(ref m)) if m.contains("overlap_share")),
            "{share}"
        );
    }
    for share in [0.0, 1.0] {
        with(share).expect("builds");
    }
}

/// No triangle ends in more than `2^max_cuts` references. City's two ground triangles span the
/// scene and are cut at node after node: without a limit (64) some triangle has more pieces
/// than a low limit allows, so a knob that changed nothing would fail here; at each limit the
/// tree still validates and answers every ray as brute force does.
#[test]
fn max_cuts_bounds_the_pieces_of_every_triangle() {
    let mesh = raybench_testkit::generated("city:triangles=20000", 4);
    let most_pieces = |max_cuts: u32| {
        let bvh = binary_sbvh(&mesh, |s| s.max_cuts = max_cuts).expect("builds");
        bvh.validate(&mesh).expect("validates");
        let mut pieces = vec![0u32; mesh.len()];
        for &id in bvh.prim_ids() {
            pieces[id as usize] += 1;
        }
        pieces.into_iter().max().expect("triangles")
    };
    assert!(most_pieces(64) > 8, "the ground is cut more than 3 times");
    for max_cuts in [0, 1, 3] {
        let most = most_pieces(max_cuts);
        assert!(most <= 1 << max_cuts, "max_cuts {max_cuts}: {most} pieces");
        if max_cuts == 3 {
            assert_eq!(most, 8, "the limit is reached, not undershot");
        }
    }
    let rays = raybench_testkit::random_rays_in(&mesh.bounds().enlarged(0.1), 3000, 4);
    let case = Case {
        name: "city, max_cuts 1".into(),
        seed: 4,
        mesh: mesh.clone(),
        rays,
    };
    let mut p = WideParams::sbvh();
    p.binary.spatial_splits.as_mut().unwrap().max_cuts = 1;
    let counts =
        check_case::<Bvh8>(&case, &p, &|b, m| b.validate(m)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(counts.mismatch, 0, "{counts:?}");
}

/// More cuts than a reference's count holds are refused before the build; both ends build.
#[test]
fn max_cuts_past_64_is_refused() {
    use raybench_accel::BuildError;
    let mesh = raybench_testkit::generated("soup:triangles=2000", 1);
    let with = |max_cuts: u32| binary_sbvh(&mesh, |s| s.max_cuts = max_cuts);
    for max_cuts in [65, u32::MAX] {
        assert!(
            matches!(with(max_cuts), Err(BuildError::Unsupported(ref m)) if m.contains("max_cuts")),
            "{max_cuts}"
        );
    }
    for max_cuts in [0, 64] {
        with(max_cuts).expect("builds");
    }
}
