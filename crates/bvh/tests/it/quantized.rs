//! The compressed 8-wide BVHs (`bvh8-compressed`, 8-bit planes, and `bvh8-compressed16`,
//! 16-bit): the shared suite with `validate()` after every build, and what they must share
//! with the float tree they are converted from.

use crate::on_threads;
use raybench_accel::{Accel, BuildError, Counters};
use raybench_bvh::wide::Plane;
use raybench_bvh::{Bvh8, BvhParams, BvhQuantized, NodeFormat, NodeSimd, WideParams};
use raybench_geom::{Ray, Vec3};
use raybench_testkit::{centroid_rays, check_conformance, generated, random_rays_in};
use std::sync::Arc;

fn quantized<P: Plane>() -> WideParams {
    WideParams {
        node_format: P::FORMAT,
        ..WideParams::for_width(8)
    }
}

/// Runs a generic check for both plane widths.
macro_rules! both_widths {
    ($check:ident) => {{
        $check::<u8>();
        $check::<u16>();
    }};
}

/// The defaults, tiny leaves (deep trees collapsed into full nodes) and the SSE kernel.
fn param_sets<P: Plane>() -> [WideParams; 3] {
    [
        quantized::<P>(),
        WideParams {
            binary: BvhParams {
                max_leaf_size: 1,
                ..BvhParams::binned()
            },
            ..quantized::<P>()
        },
        WideParams {
            node_simd: NodeSimd::Sse,
            ..quantized::<P>()
        },
    ]
}

#[test]
fn compressed_conforms() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        for params in param_sets::<P>() {
            check_conformance::<BvhQuantized<P>>(&params, &|b, mesh| b.validate(mesh));
        }
    }
    both_widths!(check);
}

#[test]
fn compressed_conforms_on_the_shared_scenes() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let checked = raybench_testkit::conformance_on_shared_scenes::<BvhQuantized<P>>(
            &quantized::<P>(),
            &|b, m| b.validate(m),
        );
        eprintln!("real scenes checked: {checked}");
    }
    both_widths!(check);
}

/// The float tree and its quantized form answer every ray alike, bit for bit, closest and any
/// hit, with either kernel; the quantized walk visits at least the float walk's nodes (its
/// boxes only grow) and visits the same leaves or more.
#[test]
fn answers_are_the_float_trees() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        for (spec, seed) in [
            ("teapot:triangles=20000", 1),
            ("soup:triangles=5000", 7),
            ("sphere:triangles=30000", 3),
            ("hair", 2),
        ] {
            let mesh = generated(spec, seed);
            let mut rays = random_rays_in(&mesh.bounds(), 3000, seed);
            rays.extend(centroid_rays(&mesh, 3000, seed));
            for simd in [NodeSimd::Auto, NodeSimd::Sse] {
                let float = Bvh8::build(
                    mesh.clone(),
                    &WideParams {
                        node_simd: simd,
                        ..WideParams::for_width(8)
                    },
                )
                .expect("builds");
                let q = BvhQuantized::<P>::build(
                    mesh.clone(),
                    &WideParams {
                        node_simd: simd,
                        ..quantized::<P>()
                    },
                )
                .expect("builds");
                q.validate(&mesh).expect("valid");
                let (mut cf, mut cq) = (Counters::default(), Counters::default());
                for ray in &rays {
                    let (a, b) = (float.intersect(ray), q.intersect(ray));
                    assert_eq!(
                        a.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits())),
                        b.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits())),
                        "{spec}: {ray:?}"
                    );
                    assert_eq!(float.occluded(ray), q.occluded(ray), "{spec}: {ray:?}");
                    assert_eq!(float.intersect_counted(ray, &mut cf), a);
                    assert_eq!(q.intersect_counted(ray, &mut cq), b);
                }
                assert!(cq.nodes >= cf.nodes, "{spec}: {cq:?} vs {cf:?}");
                assert!(cq.nodes > 0 && cq.leaves > 0);
            }
        }
    }
    both_widths!(check);
}

/// Same tree shape as the float tree: the same children in the same slots and the same
/// `Tri4`s, every decoded box holding its float box.
#[test]
fn the_tree_is_the_float_tree_with_outward_rounded_boxes() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let mesh = generated("teapot:triangles=20000", 1);
        let float = Bvh8::build(mesh.clone(), &WideParams::for_width(8)).expect("builds");
        let q = BvhQuantized::<P>::build(mesh, &quantized::<P>()).expect("builds");
        assert_eq!(float.nodes().len(), q.nodes().len());
        assert!(float.tri4s() == q.tri4s());
        for (f, n) in float.nodes().iter().zip(q.nodes()) {
            assert_eq!(f.children(), n.children());
            assert_eq!(f.child, n.child);
            for i in 0..n.children() {
                assert!(n.child_bounds(i).contains_box(&f.child_bounds(i)));
            }
        }
        // Half (8-bit planes) or three quarters (16-bit) of the float nodes' bytes.
        let quarters = if P::FORMAT == NodeFormat::Quantized {
            2
        } else {
            3
        };
        assert_eq!(
            std::mem::size_of_val(q.nodes()) * 4,
            std::mem::size_of_val(float.nodes()) * quarters
        );
    }
    both_widths!(check);
}

/// Empty and one-triangle meshes build, validate and answer (the root a leaf, no nodes).
#[test]
fn empty_and_single_triangle_meshes() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let empty = raybench_testkit::mesh(Vec::new(), Vec::new());
        let q = BvhQuantized::<P>::build(empty.clone(), &quantized::<P>()).expect("builds");
        q.validate(&empty).expect("valid");
        let ray = Ray::infinite(Vec3::ZERO, Vec3::X);
        assert!(q.intersect(&ray).is_none() && !q.occluded(&ray));
        assert!(q.closest_point(Vec3::ZERO, f32::INFINITY).is_none());

        let one = raybench_testkit::mesh(
            vec![
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
            ],
            vec![[0, 1, 2]],
        );
        let q = BvhQuantized::<P>::build(one.clone(), &quantized::<P>()).expect("builds");
        q.validate(&one).expect("valid");
        assert!(q.nodes().is_empty());
        assert_eq!(q.intersect(&ray).map(|h| (h.prim, h.t)), Some((0, 1.0)));
        assert!(q.occluded(&ray));
        assert_eq!(
            q.closest_point(Vec3::ZERO, f32::INFINITY).map(|h| h.prim),
            Some(0)
        );
    }
    both_widths!(check);
}

/// Each tree type is built only with its own node format, and the quantized one without the
/// packet walk (which reads float nodes).
#[test]
fn a_node_format_other_than_the_trees_is_refused() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let mesh = generated("soup:triangles=100", 1);
        for r in [
            Bvh8::build(mesh.clone(), &quantized::<P>()).map(|_| ()),
            // The other plane width.
            BvhQuantized::<P>::build(
                mesh.clone(),
                &WideParams {
                    node_format: match P::FORMAT {
                        NodeFormat::Quantized => NodeFormat::Quantized16,
                        _ => NodeFormat::Quantized,
                    },
                    ..WideParams::for_width(8)
                },
            )
            .map(|_| ()),
            BvhQuantized::<P>::build(mesh.clone(), &WideParams::for_width(8)).map(|_| ()),
            BvhQuantized::<P>::build(
                mesh.clone(),
                &WideParams {
                    coherent_packets: true,
                    ..quantized::<P>()
                },
            )
            .map(|_| ()),
        ] {
            assert!(matches!(r, Err(BuildError::Unsupported(_))), "{r:?}");
        }
    }
    both_widths!(check);
}

/// The quantized tree does not depend on the thread count.
#[test]
fn the_same_tree_with_one_and_two_threads() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let mesh: Arc<_> = generated("teapot:triangles=20000", 1);
        let build = |threads| {
            on_threads(threads, || {
                BvhQuantized::<P>::build(mesh.clone(), &quantized::<P>()).expect("builds")
            })
        };
        let (one, two) = (build(1), build(2));
        assert!(one.nodes().len() > 100);
        assert!(one.nodes() == two.nodes());
        assert!(one.tri4s() == two.tri4s());
    }
    both_widths!(check);
}

/// Rays that leave the scene through its outer box (shadow rays from a roof toward the sky)
/// end at the root, as in the float tree: the walk tests the root's children on their float
/// boxes, where the rounded-out boxes would let every such ray into the children it starts
/// on. The scene: a flat roof of 512 triangles at a height no power of two divides (0.7), over
/// one small triangle on the ground, so the roof is the top face of the scene's box; rays
/// start on the roof and go up. Checked with the counters.
#[test]
fn rays_leaving_the_scene_through_its_top_end_at_the_root() {
    fn check<P: Plane>()
    where
        BvhQuantized<P>: Accel<Params = WideParams>,
    {
        let (n, y) = (16, 0.7);
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                positions.push(Vec3::new(i as f32 / n as f32, y, j as f32 / n as f32));
            }
        }
        let at = |i: u32, j: u32| i * (n + 1) + j;
        let mut indices = Vec::new();
        for i in 0..n {
            for j in 0..n {
                indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let ground = positions.len() as u32;
        positions.extend([
            Vec3::new(0.9, 0.0, 0.9),
            Vec3::new(0.95, 0.0, 0.9),
            Vec3::new(0.9, 0.0, 0.95),
        ]);
        indices.push([ground, ground + 1, ground + 2]);
        let mesh = raybench_testkit::mesh(positions, indices);
        let rays: Vec<Ray> = (1..20)
            .flat_map(|i| (1..20).map(move |j| (i, j)))
            .map(|(i, j)| {
                let o = Vec3::new(i as f32 / 20.0, y, j as f32 / 20.0);
                Ray::new(o, Vec3::Y, 1e-4, f32::INFINITY)
            })
            .collect();
        let q = BvhQuantized::<P>::build(mesh.clone(), &quantized::<P>()).expect("builds");
        q.validate(&mesh).expect("valid");
        assert!(!q.nodes().is_empty(), "a tree with interior nodes");
        for any_hit in [false, true] {
            let mut c = Counters::default();
            for ray in &rays {
                let hit = if any_hit {
                    q.occluded_counted(ray, &mut c)
                } else {
                    q.intersect_counted(ray, &mut c).is_some()
                };
                assert!(!hit, "{ray:?} starts on the roof and leaves it");
            }
            assert_eq!(
                c.nodes,
                rays.len() as u64,
                "one node test a ray: the root's"
            );
            assert_eq!(c.leaves, 0, "no leaf entered");
        }
    }
    both_widths!(check);
}
