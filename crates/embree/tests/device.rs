//! The device: what it reports about Embree, its memory accounting, config errors.

mod common;

use common::{random_triangles, workload};
use raybench_accel::Accel;
use raybench_embree::{
    Device, EmbreeError, EmbreeInfo, EmbreeParams, EmbreeScene, ISA_FROM_CONFIG, ISA_INFERRED,
    infer_isa,
};
use std::sync::Arc;

#[test]
fn info_reports_debian_embree() {
    let device = Device::new("threads=1,start_threads=1,set_affinity=0").unwrap();
    let info = device.info();
    println!("{info:#?}");
    assert_eq!(info.version, "3.13.5");
    assert!(info.ray_mask_supported, "Debian builds with ray masks");
    assert!(!info.ignore_invalid_rays, "Debian aborts on invalid rays");
    assert!(!info.backface_culling);
    assert_eq!(info.tasking_system, "TBB");
    assert_eq!(info.config, "threads=1,start_threads=1,set_affinity=0");
    assert_eq!(
        (info.isa.as_str(), info.isa_source.as_str()),
        (infer_isa(), ISA_INFERRED)
    );
    let json = serde_json::to_string(&info).unwrap();
    assert_eq!(serde_json::from_str::<EmbreeInfo>(&json).unwrap(), info);
}

#[test]
fn pinned_isa_is_reported_from_the_config() {
    let params = EmbreeParams {
        threads: 1,
        isa: Some("sse2".into()),
        ..EmbreeParams::default()
    };
    let device = Device::shared(&params.config_string()).unwrap();
    let info = device.info();
    assert_eq!(
        (info.isa.as_str(), info.isa_source.as_str()),
        ("SSE2", ISA_FROM_CONFIG)
    );
    // And the SSE2 kernels answer like the others on a simple case.
    let mesh = random_triangles(0x5EED_0006, 100);
    let embree = EmbreeScene::build(mesh.clone(), &params).unwrap();
    let origin = raybench_geom::Vec3::new(0.5, 0.5, 3.0);
    let ray = raybench_geom::Ray::infinite(origin, mesh.triangle(5).centroid() - origin);
    assert!(embree.intersect(&ray).is_some());
}

#[test]
fn unusable_isa_fails_the_build_cleanly() {
    let params = EmbreeParams {
        isa: Some("avx2,threads=64".into()),
        ..EmbreeParams::default()
    };
    let err = EmbreeScene::build(random_triangles(1, 10), &params).unwrap_err();
    assert!(err.to_string().contains("isa"), "{err}");
    let unknown = EmbreeParams {
        isa: Some("pentium".into()),
        ..EmbreeParams::default()
    };
    assert!(EmbreeScene::build(random_triangles(1, 10), &unknown).is_err());
}

/// Embree runs SSE2 for an ISA name it does not know, without any error (checked with
/// `verbose=1`); the info says so instead of echoing the name.
#[test]
fn unknown_isa_name_is_reported_as_embrees_sse2_fallback() {
    let device = Device::new("threads=1,isa=pentium").unwrap();
    assert_eq!(device.info().isa, "SSE2");
}

#[test]
fn bad_config_value_is_a_device_creation_error() {
    let err = Device::new("threads=abc").unwrap_err();
    assert!(
        matches!(
            err,
            EmbreeError::DeviceCreation {
                code: "RTC_ERROR_UNKNOWN",
                ..
            }
        ),
        "{err}"
    );
    let err = EmbreeScene::build(
        random_triangles(1, 10),
        &EmbreeParams {
            threads: 1,
            ..EmbreeParams::default()
        },
    );
    assert!(err.is_ok(), "a good config still works afterwards");
}

/// The memory monitor sees the BVH: a scene's `memory()` grows with the mesh, and the
/// device's running count returns to where it was once the scenes are gone.
#[test]
fn memory_monitor_accounts_for_each_build() {
    let device = Arc::new(Device::new("threads=1,start_threads=1,set_affinity=0").unwrap());
    let baseline = device.allocated_bytes();
    let build = |n: usize| {
        let mesh = random_triangles(0x5EED_0007, n);
        EmbreeScene::build_on(device.clone(), mesh, &EmbreeParams::medium()).unwrap()
    };
    let small = build(1_000);
    let large = build(20_000);
    let (s, l) = (small.memory().nodes, large.memory().nodes);
    println!(
        "baseline {baseline} B, BVH 1k tris {s} B, 20k tris {l} B, buffers {} B, now {} B",
        large.build_stats().extra["buffer_bytes"],
        device.allocated_bytes()
    );
    assert!(
        s > 0 && l > 10 * s,
        "BVH memory must grow with the mesh: {s} vs {l}"
    );
    drop((small, large));
    let after = device.allocated_bytes();
    println!("after dropping both scenes: {after} B");
    assert!(
        after <= baseline + (l as i64) / 10,
        "freed memory is counted back"
    );
}

/// What a built scene holds on its device: its nodes and its vertex and index buffers.
fn held_bytes(scene: &EmbreeScene) -> u64 {
    scene.memory().nodes + scene.build_stats().extra["buffer_bytes"] as u64
}

/// A memory limit makes the build that would pass it fail with `MemoryLimit`
/// (`MemoryLimitReached` for the harness) wherever in the build the refused allocation falls,
/// as Embree's own memory-monitor regression tests cancel at random points: limits from 16 KiB
/// up to 4× what the scene takes, on one and two threads. Every refused build gives back what
/// it had taken, the limit is lifted afterwards, and the builds that fit give the same answers
/// as a build without a limit.
#[test]
fn a_memory_limit_refuses_the_build_wherever_it_binds_and_the_device_recovers() {
    let mesh = random_triangles(0x5EED_0008, 20_000);
    let rays = workload(&mesh, 0x5EED_0009, 2_000);
    for threads in [1, 2] {
        let config = format!("threads={threads},start_threads=1,set_affinity=0");
        let device = Arc::new(Device::new(&config).unwrap());
        let free =
            EmbreeScene::build_on(device.clone(), mesh.clone(), &EmbreeParams::medium()).unwrap();
        let needs = held_bytes(&free);
        let expected: Vec<_> = rays.iter().map(|r| free.intersect(r)).collect();
        drop(free);
        let baseline = device.allocated_bytes();
        let (mut refused, mut built) = (0, 0);
        let mut limit = 16u64 << 10;
        while limit < 4 * needs {
            let params = EmbreeParams {
                memory_limit_bytes: Some(limit),
                ..EmbreeParams::medium()
            };
            match EmbreeScene::build_on(device.clone(), mesh.clone(), &params) {
                Err(
                    e @ EmbreeError::MemoryLimit {
                        reached_bytes,
                        limit_bytes,
                    },
                ) => {
                    assert_eq!(limit_bytes, limit);
                    assert!(reached_bytes > limit, "{reached_bytes} at limit {limit}");
                    assert!(
                        matches!(
                            raybench_accel::BuildError::from(e),
                            raybench_accel::BuildError::MemoryLimitReached { .. }
                        ),
                        "limit {limit}"
                    );
                    refused += 1;
                }
                Err(e) => panic!("{threads} threads, limit {limit}: {e}"),
                Ok(scene) => {
                    let got: Vec<_> = rays.iter().map(|r| scene.intersect(r)).collect();
                    assert_eq!(got, expected, "{threads} threads, limit {limit}");
                    built += 1;
                }
            }
            assert_eq!(
                device.memory_limit(),
                None,
                "the limit is lifted after a build"
            );
            assert_eq!(
                device.allocated_bytes(),
                baseline,
                "{threads} threads, limit {limit}: what the build took is given back"
            );
            limit = limit * 3 / 2;
        }
        println!("{threads} threads: needs {needs} B; {refused} limits refused, {built} built");
        assert!(
            refused >= 10 && built >= 2,
            "{refused} refused, {built} built"
        );
    }
}

/// The limit bounds each build alone, as our builders' limits do: a scene already on the
/// device (another Embree entry's, in a run) is left out. Beside a scene larger than the limit,
/// a smaller scene that fits the limit alone still builds, with the answers it has alone, and
/// one refused is refused at what it would have held itself.
#[test]
fn a_memory_limit_leaves_out_the_scenes_already_on_the_device() {
    let small = random_triangles(0x5EED_000A, 20_000);
    let large = random_triangles(0x5EED_000B, 200_000);
    let rays = workload(&small, 0x5EED_000C, 1_000);
    let device = Arc::new(Device::new("threads=1,start_threads=1,set_affinity=0").unwrap());
    let alone =
        EmbreeScene::build_on(device.clone(), small.clone(), &EmbreeParams::medium()).unwrap();
    let small_needs = held_bytes(&alone);
    let expected: Vec<_> = rays.iter().map(|r| alone.intersect(r)).collect();
    drop(alone);
    let resident =
        EmbreeScene::build_on(device.clone(), large.clone(), &EmbreeParams::medium()).unwrap();
    let limit = 3 * small_needs;
    assert!(
        held_bytes(&resident) > limit,
        "the resident scene ({} B) must be past the limit ({limit} B) for the test to bind",
        held_bytes(&resident)
    );
    let with = |limit: u64| EmbreeParams {
        memory_limit_bytes: Some(limit),
        ..EmbreeParams::medium()
    };
    let beside = EmbreeScene::build_on(device.clone(), small.clone(), &with(limit)).unwrap();
    let got: Vec<_> = rays.iter().map(|r| beside.intersect(r)).collect();
    assert_eq!(got, expected);
    drop(beside);
    match EmbreeScene::build_on(device.clone(), small.clone(), &with(small_needs / 4)) {
        Err(EmbreeError::MemoryLimit {
            reached_bytes,
            limit_bytes,
        }) => {
            assert_eq!(limit_bytes, small_needs / 4);
            assert!(
                reached_bytes > limit_bytes && reached_bytes < held_bytes(&resident),
                "refused at {reached_bytes} B: the build's own bytes, not the device's"
            );
        }
        Err(e) => panic!("a quarter of what the scene needs: {e}"),
        Ok(_) => panic!("built within a quarter of what the scene needs"),
    }
    drop(resident);
}
