//! Batches not marked coherent with `cone_packets` (`bvh8-packets`): the groups of sixteen
//! consecutive rays within the cone go as packets, the rest ray by ray, and every ray's answer
//! is its single-ray walk's, bit for bit but for exact ties. The batches here interleave beams
//! (within the cone) with groups of random rays and with groups that mix both, and are traced
//! whole and from offsets that start on and off a group boundary. On a CPU without AVX-512F the
//! batches go ray by ray and the checks still hold (and say so).

use raybench_accel::{Accel, Hit, PreparedRays};
use raybench_bvh::{Bvh8, WideParams};
use raybench_geom::Ray;
use raybench_testkit::{camera_ray_sets, random_rays_in};

/// Every ray of `rays[first..]` traced in one batch call against its own `intersect`; returns
/// the hits and the ties.
fn batch_against_single_rays(bvh: &Bvh8, rays: &[Ray], first: usize, what: &str) -> (usize, usize) {
    let prepared = bvh.prepare_rays(rays).expect("valid rays");
    assert!(
        matches!(prepared, PreparedRays::Native),
        "an incoherent batch"
    );
    let mut out: Vec<Option<Hit>> = vec![None; rays.len() - first];
    bvh.intersect_prepared(rays, &prepared, first, &mut out);
    let (mut hits, mut ties) = (0, 0);
    for (i, (ray, got)) in rays[first..].iter().zip(&out).enumerate() {
        let single = bvh.intersect(ray);
        if *got == single {
            hits += got.is_some() as usize;
            continue;
        }
        let tie = got
            .zip(single)
            .is_some_and(|(a, b)| a.prim != b.prim && a.t == b.t);
        assert!(
            tie,
            "{what}, ray {}: batch {got:?}, single ray {single:?}",
            first + i
        );
        ties += 1;
    }
    (hits, ties)
}

#[test]
fn cone_groups_answer_as_single_rays() {
    let params = WideParams::for_width(8).with_packets();
    assert!(params.cone_packets.is_some());
    let (mut hits, mut rays_seen, mut cones) = (0usize, 0usize, 0usize);
    for spec in [
        "plane:quads=64",
        "city",
        "sphere:triangles=5000",
        "teapot-in-stadium",
        "soup:triangles=20000",
        "hair",
    ] {
        let scene = raybench_testkit::scenes::generate(spec, 3).expect("generates");
        let bvh = Bvh8::build(scene.mesh.clone(), &params).expect("builds");
        bvh.validate(&scene.mesh).expect("valid");
        if !bvh.packet_walk() {
            eprintln!("no AVX-512F on this CPU: batches go ray by ray");
        }
        let [camera, _] = camera_ray_sets(&scene, 4_096);
        let random = random_rays_in(&scene.mesh.bounds(), camera.len(), 9);
        let step = scene.mesh.bounds().extent().length() * 1e-3;
        // Per group of sixteen: a beam (as mirror reflections off a flat surface: each camera
        // ray's origin moved along a line, its direction turned by up to 2.6 degrees), random
        // rays, or the two alternating ray by ray.
        let mut rays = Vec::with_capacity(camera.len());
        for (g, (c, r)) in camera.chunks(16).zip(random.chunks(16)).enumerate() {
            let d0 = c[0].dir().normalize();
            let side = d0.any_orthonormal_vector();
            let beam = c.iter().enumerate().map(|(i, c)| {
                let i = i as f32;
                Ray::infinite(c.origin() + side * (i * step), d0 + side * (i * 0.003))
            });
            match g % 3 {
                0 => rays.extend(beam),
                1 => rays.extend_from_slice(r),
                _ => rays.extend(beam.zip(r).enumerate().map(
                    |(i, (c, r))| {
                        if i % 2 == 0 { c } else { *r }
                    },
                )),
            }
        }
        cones += rays
            .chunks_exact(16)
            .filter(|g| {
                let d0 = g[0].dir().normalize();
                g.iter().all(|r| r.dir().normalize().dot(d0) > 0.996)
            })
            .count();
        for first in [0, 48, 5] {
            let (h, _) = batch_against_single_rays(&bvh, &rays, first, spec);
            hits += h;
            rays_seen += rays.len() - first;
        }
    }
    eprintln!("{rays_seen} rays, {hits} hits, {cones} groups within a cone");
    assert!(cones > 200, "only {cones} groups within a cone");
    assert!(hits > rays_seen / 4, "only {hits} hits of {rays_seen}");
}

/// A cosine outside `(0, 1]` is refused at build time, with the knob's name.
#[test]
fn a_cone_outside_zero_to_one_is_refused() {
    let mesh = raybench_testkit::generated("sphere:triangles=100", 1);
    for cos in [0.0, -0.5, 1.5, f32::NAN] {
        let params = WideParams {
            cone_packets: Some(cos),
            ..WideParams::for_width(8).with_packets()
        };
        let err = Bvh8::build(mesh.clone(), &params).err().expect("refused");
        assert!(err.to_string().contains("cone_packets"), "{err}");
    }
}
