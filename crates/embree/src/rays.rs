//! Rays in Embree's layout. A [`ValidRay`] can only be made from a ray that passed
//! `Ray::check`, so holding one is the proof that it will not abort Debian's Embree.

use crate::error::InvalidRay;
use raybench_accel::Hit;
use raybench_embree_sys::{
    RTC_INVALID_GEOMETRY_ID, RTC_MAX_INSTANCE_LEVEL_COUNT, RTCHit, RTCRay, RTCRayHit,
};
use raybench_geom::{Ray, RayError};

/// Every ray reaching Embree has all mask bits set: Debian's build has ray masks compiled in
/// and geometry's default mask is all ones; a 0 mask would miss everything.
const RAY_MASK: u32 = 0xFFFF_FFFF;

/// An `RTCRayHit` built from a checked ray, ready for `rtcIntersect1` (or, through its `ray`
/// field, `rtcOccluded1`). 16-byte aligned by type, as Embree requires.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct ValidRay(RTCRayHit);

impl ValidRay {
    pub(crate) fn new(ray: &Ray) -> Result<ValidRay, RayError> {
        ray.check()?;
        Ok(ValidRay(RTCRayHit {
            ray: rtc_ray(ray),
            hit: no_hit(),
        }))
    }

    pub(crate) fn ray_hit(self) -> RTCRayHit {
        self.0
    }
}

/// Every field written explicitly (no zero-filled defaults).
fn rtc_ray(ray: &Ray) -> RTCRay {
    let (o, d) = (ray.origin(), ray.dir());
    RTCRay {
        org_x: o.x,
        org_y: o.y,
        org_z: o.z,
        tnear: ray.t_min(),
        dir_x: d.x,
        dir_y: d.y,
        dir_z: d.z,
        time: 0.0,
        tfar: ray.t_max(),
        mask: RAY_MASK,
        id: 0,
        flags: 0,
    }
}

fn no_hit() -> RTCHit {
    RTCHit {
        Ng_x: 0.0,
        Ng_y: 0.0,
        Ng_z: 0.0,
        u: 0.0,
        v: 0.0,
        primID: RTC_INVALID_GEOMETRY_ID,
        geomID: RTC_INVALID_GEOMETRY_ID,
        instID: [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
    }
}

/// The closest hit `rtcIntersect1` left in `rh`, if any.
#[inline(always)]
pub(crate) fn hit_of(rh: &RTCRayHit) -> Option<Hit> {
    (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID).then_some(Hit {
        t: rh.ray.tfar,
        prim: rh.hit.primID,
        u: rh.hit.u,
        v: rh.hit.v,
    })
}

/// `rtcOccluded1` marks an occluded ray by setting `tfar` to -inf.
#[inline(always)]
pub(crate) fn occluded_of(ray: &RTCRay) -> bool {
    ray.tfar == f32::NEG_INFINITY
}

/// A batch of rays converted to Embree's layout and checked, made outside timing by
/// [`crate::EmbreeScene::prepare_checked`] or `Accel::prepare_rays`.
#[derive(Clone, Debug, Default)]
pub struct PreparedEmbreeRays {
    rays: Vec<ValidRay>,
    /// Trace through Embree's stream API with the coherent flag
    /// ([`crate::EmbreeParams::coherent_stream`]).
    coherent: bool,
    /// The same rays as 16-wide packets, for `rtcIntersect16`/`rtcOccluded16`
    /// ([`crate::EmbreeParams::coherent_packet16`]).
    packets16: Option<crate::packet16::Packets16>,
}

impl PreparedEmbreeRays {
    /// Checks and converts `rays`; the error names the first bad ray by index.
    pub fn new(rays: &[Ray]) -> Result<PreparedEmbreeRays, InvalidRay> {
        let rays = rays
            .iter()
            .enumerate()
            .map(|(index, ray)| ValidRay::new(ray).map_err(|error| InvalidRay { index, error }))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PreparedEmbreeRays {
            rays,
            coherent: false,
            packets16: None,
        })
    }

    /// The same rays, also laid out as 16-wide packets.
    pub(crate) fn with_packets16(self) -> PreparedEmbreeRays {
        let packets16 = Some(crate::packet16::Packets16::new(&self.rays));
        PreparedEmbreeRays { packets16, ..self }
    }

    pub(crate) fn packets16(&self) -> Option<&crate::packet16::Packets16> {
        self.packets16.as_ref()
    }

    /// The same rays, to be traced through the stream API as a coherent batch or not.
    pub(crate) fn coherent(self, coherent: bool) -> PreparedEmbreeRays {
        PreparedEmbreeRays { coherent, ..self }
    }

    pub(crate) fn is_coherent(&self) -> bool {
        self.coherent
    }

    pub fn len(&self) -> usize {
        self.rays.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    pub(crate) fn slice(&self, first: usize, len: usize) -> &[ValidRay] {
        &self.rays[first..first + len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Vec3;

    #[test]
    fn conversion_writes_every_field() {
        let ray = Ray::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, -0.0, -1.0),
            0.5,
            7.0,
        );
        let rh = ValidRay::new(&ray).unwrap().ray_hit();
        let r = rh.ray;
        assert_eq!([r.org_x, r.org_y, r.org_z], [1.0, 2.0, 3.0]);
        assert_eq!(r.dir_y.to_bits(), (-0.0f32).to_bits(), "sign of zero kept");
        assert_eq!((r.tnear, r.tfar, r.time), (0.5, 7.0, 0.0));
        assert_eq!((r.mask, r.id, r.flags), (u32::MAX, 0, 0));
        assert_eq!(rh.hit.geomID, RTC_INVALID_GEOMETRY_ID);
        assert_eq!(rh.hit.instID, [RTC_INVALID_GEOMETRY_ID]);
        assert_eq!(hit_of(&rh), None);
    }

    #[test]
    fn batch_error_names_the_ray() {
        let good = Ray::infinite(Vec3::ZERO, Vec3::X);
        let bad = Ray::new(Vec3::ZERO, Vec3::X, -1.0, 1.0);
        let err = PreparedEmbreeRays::new(&[good, good, bad, good]).unwrap_err();
        assert_eq!(err.index, 2);
        assert_eq!(err.error, RayError::NegativeTMin(-1.0));
        assert_eq!(err.to_string(), "ray 2: t_min = -1e0 is negative");
    }
}
