//! Workloads. Each is a pure function of its inputs and seed.
//!
//! [`Workload`] names every workload a run can ask for: five ray workloads (this module) and two
//! closest-point workloads ([`crate::points`]), so the CLI, suite manifests and reports take
//! one list. Code that only makes sense for rays asks [`Workload::is_point_query`] first.
//!
//! Primary and random rays come from the view and the bounds. Shadow and diffuse rays are
//! secondary: they start on the surfaces the primary rays hit, so the caller traces the primary
//! rays once with the reference structure and passes its hits here; every structure then
//! traces the same secondary set.
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

use crate::SceneError;
use crate::View;
use crate::points::PointWorkload;
use crate::rng::{self, DIFFUSE_RAYS_STREAM, RANDOM_RAYS_STREAM};
use raybench_geom::{Aabb, Ray, TriangleMesh, Vec3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// What a batch of queries asks of a structure: rays, or closest points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Workload {
    Primary,
    Random,
    Shadow,
    Diffuse,
    Whitted,
    /// Closest point, points near the surface ([`PointWorkload::Near`]).
    #[serde(rename = "points-near")]
    PointsNear,
    /// Closest point, points in the enlarged box ([`PointWorkload::Volume`]).
    #[serde(rename = "points-volume")]
    PointsVolume,
}

impl Workload {
    /// The ray workloads.
    pub const RAYS: [Workload; 5] = [
        Workload::Primary,
        Workload::Random,
        Workload::Shadow,
        Workload::Diffuse,
        Workload::Whitted,
    ];

    /// The closest-point workloads.
    pub const POINTS: [Workload; 2] = [Workload::PointsNear, Workload::PointsVolume];

    /// Every workload: the rays, then the points.
    pub const ALL: [Workload; 7] = [
        Workload::Primary,
        Workload::Random,
        Workload::Shadow,
        Workload::Diffuse,
        Workload::Whitted,
        Workload::PointsNear,
        Workload::PointsVolume,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            Workload::Primary => "primary",
            Workload::Random => "random",
            Workload::Shadow => "shadow",
            Workload::Diffuse => "diffuse",
            Workload::Whitted => "whitted",
            Workload::PointsNear => PointWorkload::Near.name(),
            Workload::PointsVolume => PointWorkload::Volume.name(),
        }
    }

    /// The closest-point workload this is, if it is one.
    pub fn point_workload(&self) -> Option<PointWorkload> {
        match self {
            Workload::PointsNear => Some(PointWorkload::Near),
            Workload::PointsVolume => Some(PointWorkload::Volume),
            _ => None,
        }
    }

    /// True for closest-point workloads (points, not rays).
    pub fn is_point_query(&self) -> bool {
        self.point_workload().is_some()
    }

    /// True when the query is "is anything in the way" (`occluded`), not the closest hit.
    pub fn any_hit(&self) -> bool {
        matches!(self, Workload::Shadow)
    }

    /// True when consecutive rays are coherent (camera rays in scanline order): the batch is
    /// prepared with `Accel::prepare_coherent_rays`, so structures may trace it in packets.
    pub fn coherent(&self) -> bool {
        matches!(self, Workload::Primary)
    }

    /// True when the rays start at the primary rays' hits.
    pub fn from_hits(&self) -> bool {
        matches!(
            self,
            Workload::Shadow | Workload::Diffuse | Workload::Whitted
        )
    }

    pub fn description(&self) -> &'static str {
        match self {
            Workload::Primary => {
                "camera rays through pixel centres: coherent, closest hit (ray casting)"
            }
            Workload::Random => {
                "origins uniform in the scene box enlarged by 5% per side, directions uniform on the sphere: incoherent, closest hit"
            }
            Workload::Shadow => {
                "from each primary hit that faces the light towards the light, ending just before it: any hit (occlusion)"
            }
            Workload::Diffuse => {
                "from each primary hit, cosine-weighted over the facing hemisphere: incoherent, closest hit (path tracing bounce)"
            }
            Workload::Whitted => {
                "Whitted's recursion from primary hits: mirror reflections, and refractions through transparent materials, until a maximum depth or a minimum contribution: closest hit"
            }
            Workload::PointsNear | Workload::PointsVolume => {
                self.point_workload().map_or("", |p| p.description())
            }
        }
    }
}

impl fmt::Display for Workload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Workload {
    type Err = SceneError;

    /// Case-insensitive workload name.
    fn from_str(s: &str) -> Result<Workload, SceneError> {
        Workload::ALL
            .into_iter()
            .find(|w| w.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| SceneError::UnknownWorkload { name: s.to_owned() })
    }
}

/// A primary hit as secondary workloads need it. Embree's barycentrics:
/// `p = (1-u-v) v0 + u v1 + v v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// Pinhole camera rays, one through the centre of each pixel of a `W × H` image with
/// `W × H ≈ n` and aspect 4:3, row-major from the top-left pixel, `t` in `(0, inf]`.
///
/// `bounds` is used only when `view` is unusable (eye on the target, up parallel to the view
/// direction, non-finite values, field of view outside (0°, 180°)): then the default view of
/// `bounds` is used, so every ray passes [`Ray::check`]. `n == 0` gives no rays and a 0 × 0 image.
pub fn primary_rays(view: &View, bounds: &Aabb, n: usize) -> (Vec<Ray>, u32, u32) {
    let view = if view.is_usable() {
        *view
    } else {
        View::of_bounds(bounds)
    };
    let (width, height) = image_size(n);
    let frame = CameraFrame::new(&view, width, height);
    let rays = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| frame.ray(x, y))
        .collect();
    (rays, width, height)
}

/// The 4:3 image with about `n` pixels: `W = round(sqrt(4n/3))`, `H = round(n / W)`.
fn image_size(n: usize) -> (u32, u32) {
    if n == 0 {
        return (0, 0);
    }
    let n = n as f64;
    let width = (n * 4.0 / 3.0).sqrt().round().max(1.0);
    let height = (n / width).round().max(1.0);
    (
        width.min(f64::from(u32::MAX)) as u32,
        height.min(f64::from(u32::MAX)) as u32,
    )
}

/// The camera's orthonormal frame, scaled so that image-plane offsets are in units of the
/// distance to the image plane.
struct CameraFrame {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: f32,
    height: f32,
}

impl CameraFrame {
    fn new(view: &View, width: u32, height: u32) -> CameraFrame {
        let c = &view.camera;
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let half_height = (c.fov_y_deg.to_radians() * 0.5).tan();
        // Square pixels: the horizontal half-extent follows the pixel grid's real aspect.
        let half_width = half_height * width.max(1) as f32 / height.max(1) as f32;
        CameraFrame {
            eye: c.eye,
            forward,
            right: right * half_width,
            up: up * half_height,
            width: width.max(1) as f32,
            height: height.max(1) as f32,
        }
    }

    fn ray(&self, x: u32, y: u32) -> Ray {
        // Pixel centres in [-1, 1]. A division, not a multiplication by 1/W, so the middle
        // pixel of an odd-sized image maps to exactly 0 (W * fl(1/W) need not be 1).
        let sx = (2 * u64::from(x) + 1) as f32 / self.width - 1.0;
        let sy = 1.0 - (2 * u64::from(y) + 1) as f32 / self.height;
        Ray::infinite(self.eye, self.forward + self.right * sx + self.up * sy)
    }
}

/// `n` rays with origins uniform in `bounds.enlarged(0.05)` and directions uniform on the unit
/// sphere. An empty or non-finite box is replaced by `[-1, 1]³`.
pub fn random_rays(bounds: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let usable = !bounds.is_empty() && bounds.min.is_finite() && bounds.max.is_finite();
    let region = if usable {
        bounds.enlarged(0.05)
    } else {
        Aabb::new(Vec3::splat(-1.0), Vec3::ONE)
    };
    let mut rng = rng::stream(seed, RANDOM_RAYS_STREAM);
    (0..n)
        .map(|_| {
            let origin = Vec3::new(
                rng::range_f32(&mut rng, region.min.x, region.max.x),
                rng::range_f32(&mut rng, region.min.y, region.max.y),
                rng::range_f32(&mut rng, region.min.z, region.max.z),
            );
            Ray::infinite(origin, rng::uniform_sphere(&mut rng))
        })
        .collect()
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

/// Adaptive recursion control of Whitted's ray tracer (CACM 1980): a branch stops at
/// `max_depth` bounces or when its contribution to the pixel falls below `min_contribution`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WhittedParams {
    pub max_depth: u32,
    pub min_contribution: f32,
}

impl Default for WhittedParams {
    /// Depth 5 and 1 % of a pixel: with the default material (20 % reflective) chains end after
    /// two bounces; mirrors and glass go deeper.
    fn default() -> Self {
        WhittedParams {
            max_depth: 5,
            min_contribution: 0.01,
        }
    }
}

/// One generation of Whitted rays. For each parent ray that hit (`hits[i]`), with contribution
/// `weights[i]`: a mirror reflection weighted by the material's reflectance, and, for a
/// transparent material, a refracted ray (Snell's law, entering when the ray hits the front
/// face) weighted by its transmittance; under total internal reflection the transmitted share
/// goes to the reflection. A child is made only when its weight reaches `min_contribution`.
/// Returns the children and their weights; the caller traces them with the reference and calls
/// this again, up to `max_depth` generations.
///
/// # Panics
/// If the slices differ in length or a hit's `prim` is not a triangle of the scene.
pub fn whitted_children(
    scene: &crate::Scene,
    parents: &[Ray],
    weights: &[f32],
    hits: &[Option<SurfaceHit>],
    params: &WhittedParams,
) -> (Vec<Ray>, Vec<f32>) {
    assert!(
        parents.len() == hits.len() && parents.len() == weights.len(),
        "one hit and weight per parent"
    );
    let mut rays = Vec::new();
    let mut out_weights = Vec::new();
    for ((ray, hit), &weight) in parents.iter().zip(hits).zip(weights) {
        let Some(hit) = hit else { continue };
        let Some(s) = surface_point(&scene.mesh, ray, hit) else {
            continue;
        };
        let material = scene.material(hit.prim);
        let d = ray.dir().normalize();
        let refracted = (material.transmittance > 0.0)
            .then(|| refract(d, &s, material.ior))
            .flatten();
        let mut reflect_weight = weight * material.reflectance;
        match refracted {
            Some(t) => push_child(
                &mut rays,
                &mut out_weights,
                Ray::infinite(s.behind, t),
                weight * material.transmittance,
                params,
            ),
            None => reflect_weight += weight * material.transmittance, // total internal reflection
        }
        let reflected = d - s.normal * (2.0 * d.dot(s.normal));
        push_child(
            &mut rays,
            &mut out_weights,
            Ray::infinite(s.origin, reflected),
            reflect_weight,
            params,
        );
    }
    (rays, out_weights)
}

fn push_child(
    rays: &mut Vec<Ray>,
    weights: &mut Vec<f32>,
    ray: Ray,
    weight: f32,
    params: &WhittedParams,
) {
    if weight >= params.min_contribution && weight > 0.0 && ray.check().is_ok() {
        rays.push(ray);
        weights.push(weight);
    }
}

/// Snell's law for unit `d` through the surface at `s`; `None` under total internal reflection.
fn refract(d: Vec3, s: &SurfacePoint, ior: f32) -> Option<Vec3> {
    let eta = if s.front { 1.0 / ior } else { ior };
    let cos_i = -d.dot(s.normal);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| d * eta + s.normal * (eta * cos_i - k.sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_is_about_n_pixels_at_four_to_three() {
        for n in [1usize, 2, 100, 20_000, 100_000, 1_000_003] {
            let (w, h) = image_size(n);
            let pixels = (w * h) as f64;
            assert!(
                (pixels - n as f64).abs() <= 0.5 * w.max(h) as f64 + 1.0,
                "{n}: {w}x{h}"
            );
            if n >= 20_000 {
                assert!(
                    (w as f64 / h as f64 - 4.0 / 3.0).abs() < 0.05,
                    "{n}: {w}x{h}"
                );
            }
        }
        assert_eq!(image_size(0), (0, 0));
    }

    /// A flat plane at y = 0 (normals +y) with one material everywhere, and a ray that hits it
    /// at (0.25, 0, 0.25) from above along `dir`, or from below when `dir.y > 0`.
    fn plane_case(material: crate::Material, dir: Vec3) -> (crate::Scene, Ray, SurfaceHit) {
        let mut scene = crate::generate("plane:quads=2,tilt_deg=0", 0).unwrap();
        scene.materials = vec![material];
        let target = Vec3::new(0.25, 0.0, 0.25);
        let ray = Ray::infinite(target - dir, dir);
        let prim = (0..scene.mesh.len())
            .find(|&i| scene.mesh.triangle(i).intersect_moller(&ray).is_some())
            .expect("the ray hits the plane") as u32;
        let h = scene
            .mesh
            .triangle(prim as usize)
            .intersect_moller(&ray)
            .unwrap();
        (
            scene,
            ray,
            SurfaceHit {
                prim,
                u: h.u,
                v: h.v,
            },
        )
    }

    #[test]
    fn whitted_reflects_about_the_facing_normal() {
        let (scene, ray, hit) = plane_case(crate::Material::DEFAULT, Vec3::new(1.0, -1.0, 0.0));
        let (rays, w) = whitted_children(
            &scene,
            &[ray],
            &[1.0],
            &[Some(hit)],
            &WhittedParams::default(),
        );
        assert_eq!(rays.len(), 1);
        assert_eq!(w, vec![0.2]);
        let d = rays[0].dir();
        assert!(
            (d - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6,
            "{d}"
        );
        assert!(rays[0].origin().y > 0.0, "starts above the plane");
    }

    #[test]
    fn whitted_refracts_through_glass_and_reflects_the_rest() {
        let glass = crate::Material::GLASS;
        let (scene, ray, hit) = plane_case(glass, Vec3::new(0.5, -1.0, 0.0));
        let (rays, w) = whitted_children(
            &scene,
            &[ray],
            &[1.0],
            &[Some(hit)],
            &WhittedParams::default(),
        );
        assert_eq!(
            w,
            vec![glass.transmittance, glass.reflectance],
            "refraction first, then reflection"
        );
        let (t, r) = (rays[0].dir(), rays[1].dir());
        assert!(
            rays[0].origin().y < 0.0 && t.y < 0.0,
            "refracted ray continues below"
        );
        assert!(
            rays[1].origin().y > 0.0 && r.y > 0.0,
            "reflected ray goes back up"
        );
        // Snell: sin θt = sin θi / n, with both measured from the normal.
        let d = ray.dir().normalize();
        let sin_i = (1.0 - d.y * d.y).sqrt();
        let sin_t = (1.0 - t.y * t.y).sqrt();
        assert!(
            (sin_t - sin_i / glass.ior).abs() < 1e-5,
            "{sin_t} vs {}",
            sin_i / glass.ior
        );
    }

    #[test]
    fn whitted_total_internal_reflection_keeps_the_light() {
        // Leaving glass (hitting the back face from below) at a grazing angle: no refraction.
        let glass = crate::Material::GLASS;
        let (scene, ray, hit) = plane_case(glass, Vec3::new(1.0, 0.2, 0.0));
        let (rays, w) = whitted_children(
            &scene,
            &[ray],
            &[1.0],
            &[Some(hit)],
            &WhittedParams::default(),
        );
        assert_eq!(rays.len(), 1);
        assert_eq!(w, vec![glass.reflectance + glass.transmittance]);
        assert!(
            rays[0].dir().y < 0.0 && rays[0].origin().y < 0.0,
            "reflected back below"
        );
    }

    #[test]
    fn whitted_stops_below_the_minimum_contribution() {
        let (scene, ray, hit) = plane_case(crate::Material::DEFAULT, Vec3::new(0.0, -1.0, 0.0));
        let params = WhittedParams::default();
        // 0.04 · 0.2 = 0.008 < 0.01: no child. 0.05 · 0.2 = 0.01: a child.
        assert!(
            whitted_children(&scene, &[ray], &[0.04], &[Some(hit)], &params)
                .0
                .is_empty()
        );
        assert_eq!(
            whitted_children(&scene, &[ray], &[0.05], &[Some(hit)], &params)
                .0
                .len(),
            1
        );
        assert!(
            whitted_children(&scene, &[ray], &[1.0], &[None], &params)
                .0
                .is_empty(),
            "misses end"
        );
    }

    #[test]
    fn workload_names_round_trip() {
        for w in Workload::ALL {
            assert_eq!(w.name().parse::<Workload>().unwrap(), w);
            assert_eq!(w.name().to_uppercase().parse::<Workload>().unwrap(), w);
            assert_eq!(
                serde_json::to_string(&w).unwrap(),
                format!("\"{}\"", w.name())
            );
        }
        let err = "glossy".parse::<Workload>().unwrap_err().to_string();
        assert!(err.contains("glossy") && err.contains("diffuse"), "{err}");
        let points: Vec<Workload> = Workload::ALL
            .into_iter()
            .filter(Workload::is_point_query)
            .collect();
        assert_eq!(points, Workload::POINTS);
        assert!(Workload::RAYS.iter().all(|w| w.point_workload().is_none()));
        assert_eq!(
            Workload::PointsVolume.point_workload(),
            Some(PointWorkload::Volume)
        );
    }
}
