//! Rays Debian's Embree would abort the process on never reach it. The real test is that this
//! process survives; a second test shows, in a child process, that it would not survive
//! without the check.

mod common;

use common::{presets, random_triangles};
use raybench_accel::Accel;
use raybench_embree::{Device, EmbreeParams, EmbreeScene, InvalidRay};
use raybench_geom::{Ray, RayError, Vec3};

fn bad_rays() -> [(Ray, RayError); 5] {
    let origin = Vec3::splat(0.5);
    let down = Vec3::new(0.0, 0.0, -1.0);
    [
        (
            Ray::infinite(Vec3::new(f32::NAN, 0.5, 0.5), down),
            RayError::NaN("origin.x"),
        ),
        (
            Ray::infinite(origin, Vec3::new(0.0, f32::INFINITY, -1.0)),
            RayError::TooLarge("dir.y", f32::INFINITY),
        ),
        (
            Ray::infinite(Vec3::new(0.5, 0.5, 1e19), down),
            RayError::TooLarge("origin.z", 1e19),
        ),
        (
            Ray::new(origin, down, -1.0, f32::INFINITY),
            RayError::NegativeTMin(-1.0),
        ),
        (
            Ray::new(origin, down, 0.0, f32::NAN),
            RayError::NaN("t_max"),
        ),
    ]
}

#[test]
fn invalid_rays_are_refused_without_reaching_embree() {
    let mesh = random_triangles(0x5EED_0004, 500);
    let origin = Vec3::new(0.5, 0.5, 2.0);
    let good = Ray::infinite(origin, mesh.triangle(0).centroid() - origin);
    for params in presets() {
        let embree = EmbreeScene::build(mesh.clone(), &params).unwrap();
        for (bad, expected) in bad_rays() {
            assert_eq!(embree.intersect(&bad), None);
            assert!(!embree.occluded(&bad));
            assert_eq!(embree.try_intersect(&bad), Err(expected));
            assert_eq!(embree.try_occluded(&bad), Err(expected));
            let batch = [good, good, bad, good];
            assert_eq!(embree.prepare_rays(&batch).unwrap_err(), expected);
            assert_eq!(
                embree.prepare_checked(&batch).unwrap_err(),
                InvalidRay {
                    index: 2,
                    error: expected
                }
            );
        }
        // The valid ray still works after all that.
        assert_eq!(embree.try_intersect(&good).map(|h| h.is_some()), Ok(true));
    }
}

/// Values at the edge of validity are accepted and traced (no abort): 1e18 < 1.844e18,
/// t_min = -0.0 (Embree's `tnear >= 0` holds), t_min > t_max (an empty interval).
#[test]
fn rays_at_the_edge_of_validity_are_traced() {
    let mesh = random_triangles(0x5EED_0005, 200);
    let embree = EmbreeScene::build(mesh, &EmbreeParams::medium()).unwrap();
    let down = Vec3::new(0.0, 0.0, -1.0);
    let far = Ray::infinite(Vec3::new(1e18, 0.5, 0.5), down);
    assert_eq!(embree.try_intersect(&far), Ok(None));
    let minus_zero = Ray::new(Vec3::new(0.5, 0.5, 2.0), down, -0.0, f32::INFINITY);
    assert!(embree.try_intersect(&minus_zero).is_ok());
    let empty = Ray::new(Vec3::new(0.5, 0.5, 2.0), down, 3.0, 1.0);
    assert_eq!(embree.try_intersect(&empty), Ok(None));
}

const PROBE_ENV: &str = "RAYBENCH_EMBREE_UNCHECKED_RAY_PROBE";

/// Positive control for the check: an unchecked NaN ray given straight to rtcIntersect1 kills
/// a child process with SIGABRT when the library does not ignore invalid rays (Debian).
#[cfg(unix)]
#[test]
fn unchecked_nan_ray_aborts_debian_embree_in_a_child_process() {
    use std::os::unix::process::ExitStatusExt;
    if std::env::var_os(PROBE_ENV).is_some() {
        raw::trace_nan_ray_unchecked();
        return; // reached only by an Embree that ignores invalid rays
    }
    let device = Device::new("threads=1").unwrap();
    if device.info().ignore_invalid_rays {
        println!("this Embree ignores invalid rays: nothing to show");
        return;
    }
    let output = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "unchecked_nan_ray_aborts_debian_embree_in_a_child_process",
            "--test-threads=1",
        ])
        .env(PROBE_ENV, "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("child: {:?}, stderr: {stderr}", output.status);
    assert_eq!(
        output.status.signal(),
        Some(6),
        "expected SIGABRT from Embree's assert"
    );
}

/// Raw FFI, on purpose bypassing the safe wrapper, for the child process above only.
#[cfg(unix)]
mod raw {
    use raybench_embree::sys;

    pub fn trace_nan_ray_unchecked() {
        // SAFETY: straight-line use of fresh handles, each checked for null; the one call that
        // is *not* sound on Debian's Embree (the NaN ray) is the point of this child process.
        unsafe {
            let device = sys::rtcNewDevice(c"threads=1".as_ptr());
            assert!(!device.is_null());
            let scene = sys::rtcNewScene(device);
            let geometry =
                sys::rtcNewGeometry(device, sys::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE);
            let vertices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTCFormat::RTC_FORMAT_FLOAT3,
                12,
                3,
            )
            .cast::<[f32; 3]>();
            let indices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTCFormat::RTC_FORMAT_UINT3,
                12,
                1,
            )
            .cast::<[u32; 3]>();
            assert!(!vertices.is_null() && !indices.is_null());
            for (i, v) in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
                .into_iter()
                .enumerate()
            {
                vertices.add(i).write_unaligned(v);
            }
            indices.write_unaligned([0, 1, 2]);
            sys::rtcCommitGeometry(geometry);
            sys::rtcAttachGeometry(scene, geometry);
            sys::rtcReleaseGeometry(geometry);
            sys::rtcCommitScene(scene);
            let mut rayhit = sys::RTCRayHit {
                ray: sys::RTCRay {
                    org_x: f32::NAN,
                    org_y: 0.25,
                    org_z: 1.0,
                    tnear: 0.0,
                    dir_x: 0.0,
                    dir_y: 0.0,
                    dir_z: -1.0,
                    time: 0.0,
                    tfar: f32::INFINITY,
                    mask: u32::MAX,
                    id: 0,
                    flags: 0,
                },
                hit: sys::RTCHit {
                    Ng_x: 0.0,
                    Ng_y: 0.0,
                    Ng_z: 0.0,
                    u: 0.0,
                    v: 0.0,
                    primID: sys::RTC_INVALID_GEOMETRY_ID,
                    geomID: sys::RTC_INVALID_GEOMETRY_ID,
                    instID: [sys::RTC_INVALID_GEOMETRY_ID],
                },
            };
            let mut context = sys::intersect_context();
            sys::rtcIntersect1(scene, &mut context, &mut rayhit);
            sys::rtcReleaseScene(scene);
            sys::rtcReleaseDevice(device);
        }
    }
}
