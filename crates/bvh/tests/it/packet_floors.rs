//! Packets handed to the single-ray walk (`WideParams::packet_floors`): a packet whose walk
//! shared few nodes and `Tri4`s among its rays sends the next packets of its window of 256 rays
//! ray by ray. Checked here: the packets so handed over answer exactly as the single-ray walk
//! (ties included, which is what shows they were handed over), the decisions are the same
//! whether a batch comes in one call or in the harness's chunks of 256 rays (so the answers are
//! the same on any number of threads), and the shared suite holds with the registry's floors.
//! On a CPU without AVX2 every batch is traced ray by ray and the checks say so.

use raybench_accel::Accel;
use raybench_bvh::{Bvh8, PacketFloors, WideParams};
use raybench_geom::Ray;
use raybench_testkit::{camera_ray_sets, conformance, scenes, shadow_ray_sets};

fn packets(floors: PacketFloors) -> WideParams {
    WideParams {
        coherent_packets: true,
        packet_floors: floors,
        ..WideParams::for_width(8)
    }
}

/// Rays per window: the first packet of each is always walked as a packet.
const WINDOW: usize = 256;

/// The tree of a generated scene with `floors`, and its ray sets: camera rays from outside and
/// from inside, and shadow rays from their hits. `None` (said) without the packet walk.
fn tree_and_rays(spec: &str, seed: u64, floors: PacketFloors) -> Option<(Bvh8, Vec<Vec<Ray>>)> {
    let scene = scenes::generate(spec, seed).expect("generates");
    let bvh = Bvh8::build(scene.mesh.clone(), &packets(floors)).expect("builds");
    if !bvh.packet_walk() {
        eprintln!("no AVX2 on this CPU: the packet walk is not used, nothing to check");
        return None;
    }
    let rays = camera_ray_sets(&scene, 6_000)
        .into_iter()
        .chain(shadow_ray_sets(&scene, &bvh, 6_000))
        .collect();
    Some((bvh, rays))
}

#[test]
fn packets_under_the_floors_are_traced_ray_by_ray() {
    // No packet carries 17 rays a visit: every packet after a window's first goes ray by ray.
    let never = PacketFloors {
        node: 17.0,
        tri4: 17.0,
    };
    let (mut handed, mut ties_in_packets) = (0usize, 0usize);
    for spec in ["city", "plane:quads=64", "teapot-in-stadium"] {
        let Some((bvh, ray_sets)) = tree_and_rays(spec, 3, never) else {
            return;
        };
        for rays in ray_sets {
            let prepared = bvh.prepare_coherent_rays(&rays).expect("valid rays");
            let mut hits = vec![None; rays.len()];
            bvh.intersect_prepared(&rays, &prepared, 0, &mut hits);
            let mut occluded = vec![false; rays.len()];
            bvh.occluded_prepared(&rays, &prepared, 0, &mut occluded);
            for (i, ray) in rays.iter().enumerate() {
                let single = bvh.intersect(ray);
                assert_eq!(occluded[i], bvh.occluded(ray), "{spec}: ray {i}: any hit");
                if i % WINDOW < 16 {
                    // Walked as a packet: the same answer but for ties.
                    ties_in_packets += (hits[i] != single) as usize;
                    continue;
                }
                assert_eq!(hits[i], single, "{spec}: ray {i} was not traced ray by ray");
                handed += single.is_some() as usize;
            }
        }
    }
    eprintln!("{handed} hits traced ray by ray; {ties_in_packets} ties in the packets walked");
    assert!(handed > 10_000, "only {handed} hits handed over");
    // From inside the city, packets meet coincident faces and break ties their own way: had
    // the later packets been walked as packets too, they would have differed the same way.
    assert!(
        ties_in_packets > 0,
        "no ties in the packets walked: the test cannot tell a packet from a ray-by-ray walk"
    );
}

#[test]
fn windows_decide_alike_in_one_call_and_in_chunks() {
    for spec in ["city", "sphere:triangles=60000", "grass"] {
        let Some((bvh, ray_sets)) = tree_and_rays(spec, 5, PacketFloors::MEASURED) else {
            return;
        };
        for rays in ray_sets {
            let prepared = bvh.prepare_coherent_rays(&rays).expect("valid rays");
            let mut whole = vec![None; rays.len()];
            bvh.intersect_prepared(&rays, &prepared, 0, &mut whole);
            let mut whole_any = vec![false; rays.len()];
            bvh.occluded_prepared(&rays, &prepared, 0, &mut whole_any);
            for chunk in [WINDOW, 2 * WINDOW] {
                let mut chunked = vec![None; rays.len()];
                let mut chunked_any = vec![false; rays.len()];
                for first in (0..rays.len()).step_by(chunk) {
                    let end = (first + chunk).min(rays.len());
                    bvh.intersect_prepared(&rays, &prepared, first, &mut chunked[first..end]);
                    bvh.occluded_prepared(&rays, &prepared, first, &mut chunked_any[first..end]);
                }
                assert!(
                    whole == chunked,
                    "{spec}: closest hits differ in chunks of {chunk}"
                );
                assert!(
                    whole_any == chunked_any,
                    "{spec}: any hits differ in chunks of {chunk}"
                );
            }
        }
    }
}

#[test]
fn the_registry_floors_conform() {
    let counts = conformance::<Bvh8>(&packets(PacketFloors::MEASURED), &|b, mesh| {
        b.validate(mesh)
    });
    assert_eq!(counts.mismatch, 0);
    assert!(
        counts.exact > 10_000,
        "the suite must exercise hits: {counts:?}"
    );
}
