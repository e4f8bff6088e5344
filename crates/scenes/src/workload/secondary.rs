//! Secondary rays: shadow and diffuse rays start on the surfaces the primary rays hit, so the
//! caller traces the primary rays once with the reference structure and passes its hits here;
//! every structure then traces the same secondary set.
//!
//! ## Where a secondary ray starts
//! The hit point `p` is rebuilt from the barycentrics on the triangle, then moved off the
//! surface along the triangle's geometric normal, flipped to face the incoming primary ray, by
//! `eps = max(|v0|∞, |v1|∞, |v2|∞) · 2^-16`.
//!
//! * Why this size: `p = (1-u-v) v0 + u v1 + v v2` is rounded in f32 to within a few ulps of the
//!   largest vertex coordinate, i.e. a few times `max|v|∞ · 2^-24`. `2^-16` is 256 such ulps,
//!   so the origin lands on the facing side and a ray does not re-hit its own triangle.
//! * Why it cannot overshoot small objects in a large scene: the scale is the hit triangle's
//!   own coordinates, not the scene's size. A teapot at the origin of a 1 km scene gets the
//!   teapot's epsilon. Overshooting needs geometry within `2^-16` (1.5e-5) of the surface
//!   relative to the triangle's own coordinate magnitude, i.e. features of fewer than 256 ulps,
//!   which f32 cannot shape anyway.
//!
//! Hits whose triangle has no usable normal (zero area, or a cross product that overflows) give
//! no secondary ray, and neither does any ray that would fail [`Ray::check`].

use crate::rng::{self, DIFFUSE_RAYS_STREAM};
use raybench_geom::{Ray, TriangleMesh, Vec3};

/// A primary hit as secondary workloads need it. Embree's barycentrics:
/// `p = (1-u-v) v0 + u v1 + v v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// Relative offset of a secondary ray's origin (see the module documentation).
const ORIGIN_OFFSET: f32 = 1.0 / 65536.0;
/// Shadow rays run over `(0, 1 - 2^-24]` of `light - origin`: they stop just short of the
/// light, so geometry exactly at the light's position does not count as a blocker.
pub const SHADOW_T_MAX: f32 = 1.0 - 1.0 / 16_777_216.0;

/// Where a secondary ray starts and which side of the surface it is on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The hit point moved off the surface towards the incoming ray (see the module docs).
    pub origin: Vec3,
    /// The same point moved the same distance to the other side (where refracted rays start).
    pub behind: Vec3,
    /// Unit normal on the side the primary ray came from.
    pub normal: Vec3,
    /// True when the ray arrived on the front (counter-clockwise) side: it is entering.
    pub front: bool,
}

/// The surface point of `hit` as every secondary ray (and the preview's shading) uses it;
/// `None` for a triangle with no usable normal (zero area, or a cross product that overflows).
pub fn surface_point(
    mesh: &TriangleMesh,
    incoming: &Ray,
    hit: &SurfaceHit,
) -> Option<SurfacePoint> {
    let tri = mesh.triangle(hit.prim as usize);
    // The cross product in f64: f32 overflows for triangles near 1e19 and underflows for tiny ones.
    let (a, b, c) = (tri.v0.as_dvec3(), tri.v1.as_dvec3(), tri.v2.as_dvec3());
    let geometric = (b - a).cross(c - a).try_normalize()?.as_vec3();
    let front = geometric.dot(incoming.dir()) <= 0.0;
    let normal = if front { geometric } else { -geometric };
    let scale = tri
        .v0
        .abs()
        .max(tri.v1.abs())
        .max(tri.v2.abs())
        .max_element();
    let point = tri.point_at(hit.u, hit.v);
    let offset = normal * (scale * ORIGIN_OFFSET);
    let (origin, behind) = (point + offset, point - offset);
    (origin.is_finite() && behind.is_finite()).then_some(SurfacePoint {
        origin,
        behind,
        normal,
        front,
    })
}

/// For every primary hit whose facing side sees the light, a ray from the hit towards `light`:
/// direction `light - origin` (not normalised), `t` in `(0, SHADOW_T_MAX]`, so `t = 1` would be
/// the light. Hits facing away from the light get no ray: the surface itself blocks the light,
/// and a ray from there would start behind its own triangle and test nothing meaningful.
///
/// # Panics
/// If `primary` and `hits` differ in length or a hit's `prim` is not a triangle of `mesh`
/// (both are caller bugs, not bad input).
pub fn shadow_rays(
    mesh: &TriangleMesh,
    light: Vec3,
    primary: &[Ray],
    hits: &[Option<SurfaceHit>],
) -> Vec<Ray> {
    assert_eq!(primary.len(), hits.len(), "one hit slot per primary ray");
    primary
        .iter()
        .zip(hits)
        .filter_map(|(ray, hit)| surface_point(mesh, ray, hit.as_ref()?))
        .filter_map(|s| {
            let to_light = light - s.origin;
            (s.normal.dot(to_light) > 0.0).then(|| Ray::new(s.origin, to_light, 0.0, SHADOW_T_MAX))
        })
        .filter(|r| r.check().is_ok())
        .collect()
}

/// For every primary hit, one cosine-weighted direction over the hemisphere of the facing
/// normal, `t` in `(0, inf]`. Ray `i`'s direction comes from its own stream (seed, index `i`
/// of `primary`), so it does not depend on which other primary rays hit.
///
/// # Panics
/// As [`shadow_rays`].
pub fn diffuse_rays(
    mesh: &TriangleMesh,
    primary: &[Ray],
    hits: &[Option<SurfaceHit>],
    seed: u64,
) -> Vec<Ray> {
    assert_eq!(primary.len(), hits.len(), "one hit slot per primary ray");
    primary
        .iter()
        .zip(hits)
        .enumerate()
        .filter_map(|(i, (ray, hit))| {
            let s = surface_point(mesh, ray, hit.as_ref()?)?;
            let mut rng = rng::item_stream(seed, DIFFUSE_RAYS_STREAM, i as u64);
            Some(Ray::infinite(
                s.origin,
                rng::cosine_hemisphere(&mut rng, s.normal),
            ))
        })
        .filter(|r| r.check().is_ok())
        .collect()
}
