//! Whitted rays: from each hit, a mirror reflection and, through transparent materials, a
//! refraction, generation after generation.

use super::{SurfaceHit, SurfacePoint, surface_point};
use raybench_geom::{Ray, Vec3};
use serde::{Deserialize, Serialize};

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

    /// The children of one full-weight parent ray, with the default recursion control.
    fn first_generation(scene: &crate::Scene, ray: Ray, hit: SurfaceHit) -> (Vec<Ray>, Vec<f32>) {
        whitted_children(
            scene,
            &[ray],
            &[1.0],
            &[Some(hit)],
            &WhittedParams::default(),
        )
    }

    #[test]
    fn whitted_reflects_about_the_facing_normal() {
        let (scene, ray, hit) = plane_case(crate::Material::DEFAULT, Vec3::new(1.0, -1.0, 0.0));
        let (rays, w) = first_generation(&scene, ray, hit);
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
        let (rays, w) = first_generation(&scene, ray, hit);
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
        let (rays, w) = first_generation(&scene, ray, hit);
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
}
