//! The shared conformance suite for every BVH variant, `validate()` after every build.

use crate::on_threads;
use raybench_accel::Accel;
use raybench_bvh::{Bvh, Bvh4, Bvh8, Bvh16, BvhParams, BvhWide, Collapse, WideParams};
use raybench_testkit::conformance;

fn check(params: BvhParams) {
    let counts = conformance::<Bvh>(&params, &|bvh, mesh| bvh.validate(mesh));
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
}

#[test]
fn median_conforms() {
    check(BvhParams::median());
}

#[test]
fn sweep_conforms() {
    check(BvhParams::sweep());
}

#[test]
fn binned_conforms() {
    check(BvhParams::binned());
}

#[test]
fn binned_unordered_conforms() {
    check(BvhParams::binned_unordered());
}

#[test]
fn tiny_leaves_and_coarse_bins_conform() {
    // Extreme knobs exercise deep trees and forced splits.
    check(BvhParams {
        max_leaf_size: 1,
        bins: 2,
        ..BvhParams::binned()
    });
    check(BvhParams {
        max_leaf_size: 1,
        ..BvhParams::sweep()
    });
}

#[test]
fn binned_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Bvh>(&BvhParams::binned(), &|b, m| {
            b.validate(m)
        });
    eprintln!("real scenes checked: {checked}");
}

/// The defaults, the greedy collapse and, with tiny leaves, deep binary trees collapsed into
/// full wide nodes by each collapse.
fn wide_params(width: u32) -> [WideParams; 4] {
    let greedy = WideParams {
        collapse: Collapse::Greedy,
        ..WideParams::for_width(width)
    };
    let tiny = |collapse| WideParams {
        binary: BvhParams {
            max_leaf_size: 1,
            ..BvhParams::binned()
        },
        collapse,
        ..WideParams::for_width(width)
    };
    [
        WideParams::for_width(width),
        greedy,
        tiny(Collapse::Optimal),
        tiny(Collapse::Greedy),
    ]
}

/// The shared suite on a `W`-wide tree, both parameter sets.
fn wide_conforms_at<const W: usize>()
where
    BvhWide<W>: Accel<Params = WideParams>,
{
    for params in wide_params(W as u32) {
        let counts = conformance::<BvhWide<W>>(&params, &|b, mesh| b.validate(mesh));
        assert_eq!(counts.mismatch, 0, "{params:?}");
        assert!(counts.exact > 10_000, "{counts:?}");
    }
}

#[test]
fn wide_conforms() {
    wide_conforms_at::<8>();
}

#[test]
fn four_wide_conforms() {
    wide_conforms_at::<4>();
}

#[test]
fn sixteen_wide_conforms() {
    wide_conforms_at::<16>();
}

/// A tree is built only with its own width (the knob in the report is the tree's shape). Only
/// the 4-, 8- and 16-wide trees implement `Accel`: other widths do not compile.
#[test]
fn a_width_other_than_the_trees_is_refused() {
    use raybench_accel::BuildError;
    let mesh = raybench_testkit::generated("soup:triangles=100", 1);
    for r in [
        Bvh4::build(mesh.clone(), &WideParams::for_width(8)).map(|_| ()),
        Bvh8::build(mesh.clone(), &WideParams::for_width(4)).map(|_| ()),
        Bvh16::build(mesh.clone(), &WideParams::for_width(12)).map(|_| ()),
    ] {
        assert!(matches!(r, Err(BuildError::Unsupported(_))), "{r:?}");
    }
}

/// Collapsing the same binary tree to 4 and to 8 children keeps every triangle in the same
/// leaves (with the slots left unfilled): both report the same leaves and references, and the
/// 8-wide tree is shallower and fuller.
#[test]
fn both_widths_share_the_leaves_and_differ_in_depth() {
    let mesh = raybench_testkit::generated("teapot:triangles=20000", 1);
    let unfilled = |width| WideParams {
        fill_slots: false,
        ..WideParams::for_width(width)
    };
    let four = Bvh4::build(mesh.clone(), &unfilled(4)).expect("builds");
    let eight = Bvh8::build(mesh.clone(), &unfilled(8)).expect("builds");
    let (s4, s8) = (four.build_stats(), eight.build_stats());
    assert_eq!((s4.leaves, s4.refs), (s8.leaves, s8.refs));
    assert!(s8.max_depth < s4.max_depth, "{s4:?} {s8:?}");
    assert!(four.nodes().len() > eight.nodes().len());
    // The 8-wide nodes hold more children than the 4-wide ones on average (not always more
    // than four: a binary node whose children are both leaves stays a node of two).
    let children = |s: &raybench_accel::BuildStats| s.extra["mean_children"];
    assert!(
        children(&s4) <= 4.0 && children(&s8) > children(&s4),
        "{s4:?} {s8:?}"
    );
    // The default trees fill their slots: more than four children per 8-wide node.
    let f4 = Bvh4::build(mesh.clone(), &WideParams::for_width(4)).expect("builds");
    let f8 = Bvh8::build(mesh.clone(), &WideParams::for_width(8)).expect("builds");
    let (f4, f8) = (f4.build_stats(), f8.build_stats());
    assert!(children(&f4) <= 4.0 && children(&f8) > 4.0, "{f4:?} {f8:?}");
}

/// Filling a node's empty slots by splitting leaves keeps the interior nodes and every
/// triangle, makes more and smaller leaves and fuller nodes, and lowers the SAH cost; the
/// filled tree validates. At both widths, on three kinds of scene.
#[test]
fn filling_slots_splits_leaves_and_lowers_the_sah() {
    fn check<const W: usize>(spec: &str)
    where
        BvhWide<W>: Accel<Params = WideParams>,
    {
        let mesh = raybench_testkit::generated(spec, 1);
        let with = |fill_slots| {
            let p = WideParams {
                fill_slots,
                ..WideParams::for_width(W as u32)
            };
            BvhWide::<W>::build(mesh.clone(), &p).expect("builds")
        };
        let (filled, plain) = (with(true), with(false));
        filled.validate(&mesh).expect("the filled tree validates");
        let (f, p) = (filled.build_stats(), plain.build_stats());
        let context = format!("{spec}, {W} wide: filled {f:?}, plain {p:?}");
        assert_eq!(filled.nodes().len(), plain.nodes().len(), "{context}");
        assert_eq!(f.refs, p.refs, "{context}");
        assert!(f.leaves > p.leaves, "{context}");
        assert!(
            f.extra["mean_children"] > p.extra["mean_children"],
            "{context}"
        );
        assert!(f.sah_cost < p.sah_cost, "{context}");
    }
    for spec in [
        "teapot:triangles=20000",
        "soup:triangles=5000",
        "grass:density=20",
    ] {
        check::<8>(spec);
        check::<4>(spec);
    }
}

/// The wide trees do not depend on the thread count: the collapse runs its larger subtrees on
/// rayon and places each child's nodes after its parent in slot order, as one thread makes
/// them. A small mesh too, whose phases are cut into tasks of a few hundred triangles.
#[test]
fn wide_trees_are_the_same_with_one_and_two_threads() {
    fn check<const W: usize>(mesh: &std::sync::Arc<raybench_geom::TriangleMesh>)
    where
        BvhWide<W>: Accel<Params = WideParams>,
    {
        let params = WideParams::for_width(W as u32);
        let build = |threads| {
            on_threads(threads, || {
                BvhWide::<W>::build(mesh.clone(), &params).expect("builds")
            })
        };
        let (one, two) = (build(1), build(2));
        assert!(one.nodes().len() > 20, "big enough to collapse in parallel");
        assert!(one.nodes() == two.nodes(), "{W} wide: nodes differ");
        assert!(one.tri4s() == two.tri4s(), "{W} wide: Tri4s differ");
    }
    for spec in ["teapot:triangles=20000", "teapot:triangles=2000"] {
        let mesh = raybench_testkit::generated(spec, 1);
        check::<8>(&mesh);
        check::<4>(&mesh);
        check::<16>(&mesh);
    }
}

/// The binary trees do not depend on how the build is cut into tasks: one thread with no
/// parallel ranges at all, and two threads splitting every range of more than 16 triangles,
/// make the same nodes and triangle order, for the binned builder, the wide trees' builder and
/// the Split BVH's.
#[test]
fn binary_trees_do_not_depend_on_the_task_grain() {
    let mesh = raybench_testkit::generated("teapot:triangles=3000", 2);
    for base in [
        BvhParams::binned(),
        WideParams::default().binary,
        WideParams::sbvh().binary,
    ] {
        let build = |threads, parallel_threshold| {
            let params = BvhParams {
                parallel_threshold,
                ..base.clone()
            };
            on_threads(threads, || {
                Bvh::build(mesh.clone(), &params).expect("builds")
            })
        };
        let (whole, split) = (build(1, u32::MAX), build(2, 16));
        assert!(whole.nodes().len() > 100);
        assert!(
            whole.nodes() == split.nodes(),
            "{:?}: nodes differ",
            base.builder
        );
        assert_eq!(whole.prim_ids(), split.prim_ids());
    }
}

/// The SSE kernels (what a CPU without AVX2 runs) answer like the AVX2 ones, at width `W`:
/// the same suite, and the same hits and counters ray for ray on a seeded scene, with leaves
/// small enough for one `Tri4` and large enough for several (the AVX2 leaf test takes two
/// `Tri4`s a pass).
fn sse_matches_avx2_at<const W: usize>()
where
    BvhWide<W>: Accel<Params = WideParams>,
{
    use raybench_accel::Counters;
    let sse = WideParams {
        node_simd: raybench_bvh::NodeSimd::Sse,
        ..WideParams::for_width(W as u32)
    };
    let counts = conformance::<BvhWide<W>>(&sse, &|b, mesh| b.validate(mesh));
    assert_eq!(counts.mismatch, 0);
    let mesh = raybench_testkit::generated("teapot:triangles=5000", 1);
    for max_leaf_size in [4, 16] {
        let with = |p: &WideParams| {
            let mut p = p.clone();
            p.binary.max_leaf_size = max_leaf_size;
            BvhWide::<W>::build(mesh.clone(), &p).expect("builds")
        };
        let (a, b) = (with(&WideParams::for_width(W as u32)), with(&sse));
        assert!(!b.uses_avx2());
        for ray in raybench_testkit::scenes::random_rays(&mesh.bounds(), 5_000, 7) {
            let (mut ca, mut cb) = (Counters::default(), Counters::default());
            assert_eq!(
                a.intersect_counted(&ray, &mut ca),
                b.intersect_counted(&ray, &mut cb)
            );
            assert_eq!(a.occluded(&ray), b.occluded(&ray));
            assert_eq!(ca, cb, "{ray:?}");
        }
    }
}

/// The batch loops exist twice on x86-64: with AVX-512's registers (what `Auto` runs on a CPU
/// with AVX-512F and VL) and AVX2 only (what `Avx2` always runs, and `Auto` without AVX-512).
/// The suite compares the batch path with the single-ray path ray for ray; here it runs on the
/// AVX2-only loops too, so a machine with AVX-512 tests both.
fn avx2_only_conforms_at<const W: usize>()
where
    BvhWide<W>: Accel<Params = WideParams>,
{
    let auto = BvhWide::<W>::build(
        raybench_testkit::generated("sphere:triangles=200", 1),
        &WideParams::for_width(W as u32),
    )
    .expect("builds");
    #[cfg(target_arch = "x86_64")]
    assert_eq!(
        auto.avx512_registers(),
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl"),
        "Auto uses AVX-512's registers exactly when the CPU has them"
    );
    let avx2 = WideParams {
        node_simd: raybench_bvh::NodeSimd::Avx2,
        ..WideParams::for_width(W as u32)
    };
    let counts = conformance::<BvhWide<W>>(&avx2, &|b, mesh| {
        if b.avx512_registers() {
            return Err("NodeSimd::Avx2 ran with AVX-512".into());
        }
        b.validate(mesh)
    });
    assert_eq!(counts.mismatch, 0);
}

#[test]
fn wide_avx2_only_kernel_conforms() {
    avx2_only_conforms_at::<8>();
    avx2_only_conforms_at::<4>();
    // Sixteen lanes: two 8-lane AVX2 passes instead of the one AVX-512 pass.
    avx2_only_conforms_at::<16>();
}

#[test]
fn wide_sse_kernel_conforms_and_matches_the_default() {
    sse_matches_avx2_at::<8>();
}

#[test]
fn four_wide_sse_kernel_conforms_and_matches_the_default() {
    sse_matches_avx2_at::<4>();
}

/// At 16 wide the default kernel is one 16-lane AVX-512 pass where the CPU has AVX-512F: the
/// SSE kernel's four passes answer and count as it does, ray for ray.
#[test]
fn sixteen_wide_sse_kernel_conforms_and_matches_the_default() {
    sse_matches_avx2_at::<16>();
}

#[test]
fn wide_conforms_on_the_shared_scenes() {
    let checked =
        raybench_testkit::conformance_on_shared_scenes::<Bvh8>(&WideParams::default(), &|b, m| {
            b.validate(m)
        });
    let four = raybench_testkit::conformance_on_shared_scenes::<Bvh4>(
        &WideParams::for_width(4),
        &|b, m| b.validate(m),
    );
    eprintln!("real scenes checked: {checked} (8 wide), {four} (4 wide)");
}

// ---- Closest-point queries --------------------------------------------------------------

/// Closest-point queries against brute force on the shared point suite, for every binary
/// variant (the walk ignores `ordered`: it always visits the nearer child first).
#[test]
fn binary_point_queries_conform() {
    use raybench_testkit::points::point_conformance;
    for params in [
        BvhParams::median(),
        BvhParams::sweep(),
        BvhParams::binned(),
        BvhParams {
            max_leaf_size: 1,
            bins: 2,
            ..BvhParams::binned()
        },
    ] {
        let counts = point_conformance::<Bvh>(&params, &|b, m| b.validate(m));
        assert_eq!(counts.mismatch, 0, "{}", params.name());
    }
}

#[test]
fn wide_point_queries_conform() {
    use raybench_testkit::points::point_conformance;
    let tiny = WideParams {
        binary: BvhParams {
            max_leaf_size: 1,
            ..BvhParams::binned()
        },
        ..WideParams::default()
    };
    for params in [WideParams::default(), tiny] {
        let counts = point_conformance::<Bvh8>(&params, &|b, m| b.validate(m));
        assert_eq!(counts.mismatch, 0, "{params:?}");
    }
    for params in wide_params(4) {
        let counts = point_conformance::<Bvh4>(&params, &|b, m| b.validate(m));
        assert_eq!(counts.mismatch, 0, "{params:?}");
    }
    let counts = point_conformance::<Bvh16>(&WideParams::for_width(16), &|b, m| b.validate(m));
    assert_eq!(counts.mismatch, 0);
}

#[test]
fn point_queries_conform_on_the_shared_scenes() {
    use raybench_testkit::points::point_conformance_on_shared_scenes;
    let binary = point_conformance_on_shared_scenes::<Bvh>(
        &BvhParams::binned(),
        &|b, m| b.validate(m),
        70,
        30,
    );
    let wide = point_conformance_on_shared_scenes::<Bvh8>(
        &WideParams::default(),
        &|b, m| b.validate(m),
        70,
        30,
    );
    eprintln!("point queries checked on {binary} + {wide} shared scenes");
}

/// A scene too large for the memory limit is refused before anything is allocated, by both
/// trees, with the estimate in the error.
#[test]
fn too_large_is_an_error_not_an_abort() {
    use raybench_accel::BuildError;
    let mesh = raybench_testkit::generated("soup:triangles=2000", 1);
    let small = BvhParams {
        memory_limit_bytes: 64 * 1024,
        ..BvhParams::binned()
    };
    let refused = |r: Result<(), BuildError>| match r {
        Err(BuildError::TooLarge {
            needed_bytes,
            limit_bytes,
        }) => assert!(needed_bytes > limit_bytes && limit_bytes == 64 * 1024),
        other => panic!("expected TooLarge, got {other:?}"),
    };
    refused(Bvh::build(mesh.clone(), &small).map(|_| ()));
    let wide = WideParams {
        binary: small.clone(),
        ..WideParams::default()
    };
    refused(Bvh8::build(mesh.clone(), &wide).map(|_| ()));
    let four = WideParams {
        width: 4,
        ..wide.clone()
    };
    refused(Bvh4::build(mesh.clone(), &four).map(|_| ()));
    // The default limit builds it.
    assert!(Bvh::build(mesh, &BvhParams::binned()).is_ok());
}

// ---- The packet walk of coherent batches --------------------------------------------------

/// The packet walk (`coherent_packets`) under the shared suite (whose coherent-batch check
/// holds it to brute force), and on every case's rays bit-identical to the single-ray walk but
/// for ties: each lane computes its ray's single-ray arithmetic, and walks only the boxes its
/// ray entered. Without AVX2 the batches are walked ray by ray and both checks still hold.
#[test]
fn packet_walk_conforms() {
    fn at<const W: usize>()
    where
        BvhWide<W>: Accel<Params = WideParams>,
    {
        for params in wide_params(W as u32) {
            let params = WideParams {
                coherent_packets: true,
                ..params
            };
            let counts = conformance::<BvhWide<W>>(&params, &|b, mesh| b.validate(mesh));
            assert_eq!(counts.mismatch, 0, "{params:?}");
            for case in raybench_testkit::seeded_cases()
                .into_iter()
                .chain(raybench_testkit::edge_cases())
            {
                let bvh = BvhWide::<W>::build(case.mesh.clone(), &params).expect("builds");
                let rays = raybench_testkit::valid_rays(&case);
                // Ties are common here (rays along shared edges are what some cases are for).
                raybench_testkit::packets_against_single_rays(&bvh, &case.mesh, &rays, &case.name);
            }
        }
    }
    at::<8>();
    at::<4>();
    at::<16>();
}

/// Camera rays in scanline order, as the `primary` workload makes them, on scenes of every kind and
/// from views whose rays point into several octants (an eye inside the scene looking along an axis,
/// so the image crosses the other two axes' planes): the packet walk answers every ray as the
/// single-ray walk does, bit for bit, except on exact ties between two triangles (19,680 of the
/// 20,049 rays from inside the city, which meet pairs of coincident faces there; 20 of 20,000
/// elsewhere, with leaves of at most 8 triangles). Returns without checking (and says so) on a CPU
/// without AVX2 (sixteen lanes with AVX-512F, eight with AVX2 alone).
#[test]
fn packet_walk_answers_camera_rays_as_the_single_ray_walk() {
    use raybench_accel::PreparedRays;
    let params = WideParams {
        coherent_packets: true,
        ..WideParams::for_width(8)
    };
    let (mut hits, mut ties, mut mixed_packets) = (0usize, 0usize, 0usize);
    for spec in [
        "teapot-in-stadium",
        "city",
        "soup:triangles=20000",
        "hair",
        "plane:quads=64",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let mesh = scene.mesh.clone();
        let bvh = Bvh8::build(mesh.clone(), &params).expect("builds");
        if !bvh.packet_walk() {
            eprintln!("no AVX2 on this CPU: the packet walk is not used, nothing to compare");
            return;
        }
        for rays in raybench_testkit::camera_ray_sets(&scene, 20_000) {
            let prepared = bvh.prepare_coherent_rays(&rays).expect("rays are valid");
            assert!(matches!(prepared, PreparedRays::Foreign(_)));
            let (h, t) = raybench_testkit::packets_against_single_rays(&bvh, &mesh, &rays, spec);
            hits += h;
            ties += t;
            mixed_packets += rays
                .chunks(16)
                .filter(|c| {
                    let octant = |r: &raybench_geom::Ray| r.inv_dir().to_array().map(|x| x < 0.0);
                    c.iter().any(|r| octant(r) != octant(&c[0]))
                })
                .count();
        }
    }
    eprintln!("camera rays: {hits} identical hits, {ties} ties, {mixed_packets} mixed packets");
    assert!(hits > 50_000, "only {hits} hits: the test proves little");
    assert!(
        mixed_packets > 20,
        "only {mixed_packets} packets span octants"
    );
}
