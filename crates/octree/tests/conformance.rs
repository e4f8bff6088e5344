//! The shared conformance suite for the octree, `validate()` after every build, plus rays
//! aimed at the octree's own geometry: axis-parallel, starting inside, exactly along split
//! planes, octant edges and corners.

use raybench_accel::{Accel, Counters};
use raybench_geom::Vec3;
use raybench_octree::{Octree, OctreeParams};
use raybench_testkit::points::{point_conformance, point_conformance_on_shared_scenes};
use raybench_testkit::{
    check_conformance, check_lattice, expect_too_large, generated, lattice_rays, lattice_scene,
    refused_rays,
};

fn check(params: OctreeParams) {
    check_conformance::<Octree>(&params, &|t, mesh| t.validate(mesh));
}

#[test]
fn default_conforms() {
    check(OctreeParams::default());
}

#[test]
fn extreme_knobs_conform() {
    // One triangle per leaf as deep as allowed; a single leaf; shallow with big leaves; and
    // the serial build path.
    check(OctreeParams {
        max_obj: 1,
        max_depth: Some(raybench_octree::MAX_DEPTH_LIMIT),
        ..OctreeParams::default()
    });
    check(OctreeParams {
        max_depth: Some(0),
        ..OctreeParams::default()
    });
    check(OctreeParams {
        max_obj: 64,
        max_depth: Some(3),
        parallel_threshold: u32::MAX,
        ..OctreeParams::default()
    });
}

#[test]
fn default_conforms_on_the_shared_scenes() {
    let checked = raybench_testkit::conformance_on_shared_scenes::<Octree>(
        &OctreeParams::default(),
        &|t, m| t.validate(m),
    );
    eprintln!("real scenes checked: {checked}");
}

#[test]
fn too_large_is_an_error_not_an_abort() {
    let mesh = generated("soup:triangles=2000", 1);
    for limit in [1024, 2000 * 72 + 4096] {
        let params = OctreeParams {
            memory_limit_bytes: limit,
            max_obj: 1,
            ..OctreeParams::default()
        };
        expect_too_large::<Octree>(&mesh, &params);
    }
}

#[test]
fn degenerate_inputs_stop_early() {
    // 1000 identical triangles, a single point, triangles with one centroid: one leaf. A fan
    // of needles from one vertex legitimately goes deep (each needle crosses many cells), but
    // stays bounded.
    for (spec, max_refs_per_tri) in [
        ("identical:triangles=1000", 1.0),
        ("identical:triangles=1000,size=0", 1.0),
        ("one-centroid:triangles=1000", 1.0),
        ("fan:triangles=5000", 1000.0),
    ] {
        let mesh = generated(spec, 1);
        let tree = Octree::build(mesh.clone(), &OctreeParams::default()).unwrap();
        tree.validate(&mesh).unwrap();
        let s = tree.build_stats();
        assert!(
            (s.refs as f64) <= max_refs_per_tri * mesh.len() as f64,
            "{spec}: {s:?}"
        );
    }
}

#[test]
fn rays_along_split_planes_edges_and_corners() {
    let mesh = lattice_scene();
    for params in [
        OctreeParams::default(),
        OctreeParams {
            max_obj: 1,
            ..OctreeParams::default()
        },
    ] {
        let tree = Octree::build(mesh.clone(), &params).unwrap();
        assert_eq!(tree.root_box().min, Vec3::ZERO);
        assert_eq!(tree.root_box().max, Vec3::splat(4.0));
        assert!(
            tree.build_stats().max_depth >= 3,
            "{:?}",
            tree.build_stats()
        );
        check_lattice::<Octree>("split-planes", &params, &|t, m| t.validate(m));
    }
}

#[test]
fn walks_are_bounded_and_counted() {
    let mesh = lattice_scene();
    let tree = Octree::build(mesh, &OctreeParams::default()).unwrap();
    let mut total = Counters::default();
    for r in lattice_rays() {
        tree.intersect_counted(&r, &mut total);
    }
    assert!(total.mailbox_skips > 0, "{total:?}");
    assert!(total.leaves > 0 && total.nodes > 0, "{total:?}");
    for r in refused_rays() {
        let mut c = Counters::default();
        let _ = tree.intersect_counted(&r, &mut c);
        assert!(c.nodes + c.leaves <= 64, "{r:?}: {c:?}");
    }
}

// ---- Closest-point queries --------------------------------------------------------------

#[test]
fn point_queries_conform() {
    for params in [
        OctreeParams::default(),
        // One triangle per leaf as deep as allowed, and a single leaf.
        OctreeParams {
            max_obj: 1,
            max_depth: Some(raybench_octree::MAX_DEPTH_LIMIT),
            ..OctreeParams::default()
        },
        OctreeParams {
            max_depth: Some(0),
            ..OctreeParams::default()
        },
    ] {
        let counts = point_conformance::<Octree>(&params, &|t, m| t.validate(m));
        assert_eq!(counts.mismatch, 0, "{}", params.name());
    }
}

#[test]
fn point_queries_conform_on_the_shared_scenes() {
    let checked = point_conformance_on_shared_scenes::<Octree>(
        &OctreeParams::default(),
        &|t, m| t.validate(m),
        70,
        30,
    );
    eprintln!("real scenes checked: {checked}");
}

// ---- The depth limit adapts to the scene ----------------------------------------------------

#[test]
fn a_tiny_teapot_in_a_stadium_is_subdivided_to_its_own_scale() {
    // A 1 cm teapot in a 1 km stadium: cells of the textbook MAX_DEPTH (2^-20 of the root,
    // about 1 mm) still hold hundreds of its triangles; the adaptive limit goes deeper.
    let spec = "teapot-in-stadium:size_ratio=1e-5,stadium_triangles=4000,teapot_triangles=6000";
    let scene = raybench_testkit::scenes::generate(spec, 1).unwrap();
    let mesh = scene.mesh.clone();
    let crowded = |t: &Octree| t.build_stats().extra["leaves_over_64_not_sharing_a_point"];
    let fixed = OctreeParams {
        max_depth: Some(20),
        ..OctreeParams::default()
    };
    let shallow = Octree::build(mesh.clone(), &fixed).unwrap();
    shallow.validate(&mesh).unwrap();
    assert_eq!(shallow.depth_limit(), 20);
    assert!(crowded(&shallow) > 0.0, "{:?}", shallow.build_stats());
    let params = OctreeParams::default();
    let tree = Octree::build(mesh.clone(), &params).unwrap();
    tree.validate(&mesh).unwrap();
    assert!(tree.depth_limit() > 20, "{}", tree.depth_limit());
    assert_eq!(crowded(&tree), 0.0, "{:?}", tree.build_stats());
    // And the answers, for camera rays at the teapot.
    let [rays, _] = raybench_testkit::camera_ray_sets(&scene, 2000);
    let case = raybench_testkit::Case {
        name: spec.into(),
        seed: 1,
        mesh: mesh.clone(),
        rays,
    };
    let counts = raybench_testkit::check_case::<Octree>(&case, &params, &|t, m| t.validate(m))
        .unwrap_or_else(|e| panic!("{spec}: {e}"));
    assert_eq!(counts.mismatch, 0);
}

#[test]
fn the_depth_limit_never_falls_below_the_textbook_one() {
    // Needles as long as the scene: its smallest triangle alone would allow 2 levels.
    let mesh = generated("fan:triangles=2000", 1);
    let tree = Octree::build(mesh.clone(), &OctreeParams::default()).unwrap();
    tree.validate(&mesh).unwrap();
    assert_eq!(tree.depth_limit(), raybench_octree::build::DEPTH_FLOOR);
    assert!(tree.build_stats().max_depth > 2, "{:?}", tree.build_stats());
}
