//! Coherent batches through Embree's 16-wide packet API (`rtcIntersect16`, `rtcOccluded16`):
//! the fair counterpart of the wide BVH's packet walk (`bvh8-packets`), which takes the same
//! sixteen consecutive rays a packet, one per AVX-512 lane. The rays are laid out as
//! `RTCRayHit16`s (structure of arrays, 64-byte aligned by type, as the call requires) when the
//! batch is prepared, outside timing; the timed path copies a packet to the stack (Embree writes
//! its answers into the rays) and calls Embree with the coherent-context flag, as the stream
//! entry does with `rtcIntersect1M`. Trade-off: Embree's hybrid traversal walks a packet
//! together only while enough of its lanes stay active and drops to single rays below that, so
//! the packet pays when the rays meet the same nodes (camera rays on large triangles) and costs
//! a little where they scatter. Caveats: `rtcOccluded16` reports some rays lying in a
//! triangle's plane as occluded where `rtcOccluded1` does not (docs/validation.md, E11), so the
//! scene calls [`occluded16`] only with `EmbreeParams::coherent_occluded16`, which no preset
//! sets. Lanes past the end of a batch (or of a traced range) are masked invalid; they hold
//! copies of the last ray so that nothing Embree might read is uninitialised or unchecked. Each
//! lane's ray is the one `rtcIntersect1` would get, field for field (tnear, tfar, mask all ones,
//! flags 0, geomID invalid).

use crate::rays::ValidRay;
use raybench_accel::Hit;
use raybench_embree_sys::{
    self as sys, RTC_INVALID_GEOMETRY_ID, RTCHit16, RTCRay16, RTCRayHit16, intersect_context,
};

/// Rays in a packet: `rtcIntersect16`'s width, and the wide BVH's packets'.
pub(crate) const PACKET16: usize = 16;

/// `rtcIntersect16`'s `valid` argument: -1 for a lane to trace, 0 for one to leave alone,
/// aligned as the packet (Embree loads it as one 64-byte vector).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct ValidMask([i32; PACKET16]);

const ALL_VALID: ValidMask = ValidMask([-1; PACKET16]);

impl ValidMask {
    /// The first `n` lanes valid.
    fn first(n: usize) -> ValidMask {
        ValidMask(std::array::from_fn(|l| if l < n { -1 } else { 0 }))
    }
}

/// A coherent batch as `RTCRayHit16` packets of [`PACKET16`] consecutive rays.
#[derive(Clone, Debug)]
pub(crate) struct Packets16 {
    packets: Vec<RTCRayHit16>,
    len: usize,
}

impl Packets16 {
    pub(crate) fn new(rays: &[ValidRay]) -> Packets16 {
        let packets = rays
            .chunks(PACKET16)
            .map(|chunk| {
                let lane = |l: usize| chunk[l.min(chunk.len() - 1)].ray_hit();
                let rows: [_; PACKET16] = std::array::from_fn(lane);
                let f = |get: fn(&sys::RTCRayHit) -> f32| rows.each_ref().map(get);
                let u = |get: fn(&sys::RTCRayHit) -> u32| rows.each_ref().map(get);
                RTCRayHit16 {
                    ray: RTCRay16 {
                        org_x: f(|r| r.ray.org_x),
                        org_y: f(|r| r.ray.org_y),
                        org_z: f(|r| r.ray.org_z),
                        tnear: f(|r| r.ray.tnear),
                        dir_x: f(|r| r.ray.dir_x),
                        dir_y: f(|r| r.ray.dir_y),
                        dir_z: f(|r| r.ray.dir_z),
                        time: f(|r| r.ray.time),
                        tfar: f(|r| r.ray.tfar),
                        mask: u(|r| r.ray.mask),
                        id: u(|r| r.ray.id),
                        flags: u(|r| r.ray.flags),
                    },
                    hit: RTCHit16 {
                        Ng_x: f(|r| r.hit.Ng_x),
                        Ng_y: f(|r| r.hit.Ng_y),
                        Ng_z: f(|r| r.hit.Ng_z),
                        u: f(|r| r.hit.u),
                        v: f(|r| r.hit.v),
                        primID: u(|r| r.hit.primID),
                        geomID: u(|r| r.hit.geomID),
                        instID: std::array::from_fn(|level| u_level(&rows, level)),
                    },
                }
            })
            .collect();
        Packets16 {
            packets,
            len: rays.len(),
        }
    }

    /// The packets of rays `first .. first + len` when `first` starts a packet (the harness's
    /// chunks start at multiples of 256); `None` otherwise, and the caller goes ray by ray.
    pub(crate) fn range(&self, first: usize, len: usize) -> Option<&[RTCRayHit16]> {
        let end = first.checked_add(len)?;
        (first.is_multiple_of(PACKET16) && end <= self.len)
            .then(|| &self.packets[first / PACKET16..end.div_ceil(PACKET16)])
    }
}

fn u_level(rows: &[sys::RTCRayHit; PACKET16], level: usize) -> [u32; PACKET16] {
    rows.each_ref().map(|r| r.hit.instID[level])
}

/// The valid mask of a packet answering `out_len` rays.
#[inline(always)]
fn mask_for(out_len: usize) -> ValidMask {
    if out_len >= PACKET16 {
        ALL_VALID
    } else {
        ValidMask::first(out_len)
    }
}

/// [`intersect_context`] with `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`.
fn coherent_context() -> sys::RTCIntersectContext {
    sys::RTCIntersectContext {
        flags: sys::RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
        ..intersect_context()
    }
}

/// Closest hits of `packets` into `out` (its first `out.len()` rays).
///
/// # Safety
///
/// `scene` must be a committed, live scene (the caller's `EmbreeScene` keeps it so).
pub(crate) unsafe fn intersect16(
    scene: sys::RTCScene,
    packets: &[RTCRayHit16],
    out: &mut [Option<Hit>],
) {
    for (packet, out) in packets.iter().zip(out.chunks_mut(PACKET16)) {
        let mut rh = *packet;
        let valid = mask_for(out.len());
        let mut context = coherent_context();
        // SAFETY: the scene is committed and alive (the caller's contract); `rh` and `valid`
        // are 64-byte aligned by type, as rtcIntersect16 requires; every lane, valid or not,
        // holds a ray that passed `Ray::check` (made from `ValidRay`s only); `context` is
        // initialised as rtcInitIntersectContext does, with the coherent flag.
        unsafe { sys::rtcIntersect16(valid.0.as_ptr(), scene, &mut context, &mut rh) };
        for (l, o) in out.iter_mut().enumerate() {
            *o = (rh.hit.geomID[l] != RTC_INVALID_GEOMETRY_ID).then(|| Hit {
                t: rh.ray.tfar[l],
                prim: rh.hit.primID[l],
                u: rh.hit.u[l],
                v: rh.hit.v[l],
            });
        }
    }
}

/// Any hits of `packets` into `out` (its first `out.len()` rays): `rtcOccluded16` sets an
/// occluded lane's `tfar` to -inf.
///
/// # Safety
///
/// `scene` must be a committed, live scene (the caller's `EmbreeScene` keeps it so).
pub(crate) unsafe fn occluded16(scene: sys::RTCScene, packets: &[RTCRayHit16], out: &mut [bool]) {
    for (packet, out) in packets.iter().zip(out.chunks_mut(PACKET16)) {
        let mut ray = packet.ray;
        let valid = mask_for(out.len());
        let mut context = coherent_context();
        // SAFETY: as in `intersect16`, with the ray half of the packet (`RTCRay16`, 64-byte
        // aligned by type).
        unsafe { sys::rtcOccluded16(valid.0.as_ptr(), scene, &mut context, &mut ray) };
        for (l, o) in out.iter_mut().enumerate() {
            *o = ray.tfar[l] == f32::NEG_INFINITY;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::{Ray, Vec3};

    #[test]
    fn packets_transpose_rays_and_pad_with_the_last() {
        let rays: Vec<ValidRay> = (0..20)
            .map(|i| {
                let r = Ray::new(Vec3::new(i as f32, 1.0, 2.0), Vec3::Z, 0.25, 9.0 + i as f32);
                ValidRay::new(&r).unwrap()
            })
            .collect();
        let p = Packets16::new(&rays);
        assert_eq!(p.packets.len(), 2);
        let second = &p.packets[1];
        assert_eq!(second.ray.org_x[..4], [16.0, 17.0, 18.0, 19.0]);
        assert!(second.ray.org_x[4..].iter().all(|&x| x == 19.0));
        assert_eq!(second.ray.tfar[3], 28.0);
        assert!(second.ray.mask.iter().all(|&m| m == u32::MAX));
        assert!(
            second
                .hit
                .geomID
                .iter()
                .all(|&g| g == RTC_INVALID_GEOMETRY_ID)
        );
        assert_eq!(p.range(0, 20).map(<[_]>::len), Some(2));
        assert_eq!(p.range(16, 4).map(<[_]>::len), Some(1));
        assert!(p.range(5, 4).is_none(), "a packet must start the range");
        assert!(p.range(16, 5).is_none(), "past the end");
        assert_eq!(mask_for(3).0[..4], [-1, -1, -1, 0]);
        assert_eq!(mask_for(40).0, [-1; 16]);
    }
}
