//! `raybench scene preview`: a shaded picture of a scene through its camera, so a person can
//! check a scene before measuring. One primary ray per pixel, traced with Embree (medium
//! quality, all cores), Lambert shading from the view's point light with a shadow ray, plus
//! ambient; misses show a sky gradient. [`preview`] writes it as a PNG.

use super::png::{check_size, write_png};
use anyhow::{Context, Result, anyhow};
use raybench_accel::Accel;
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::{Aabb, Ray, Vec3};
use raybench_scenes::{
    SHADOW_T_MAX, Scene, SceneSource, SurfaceHit, SurfacePoint, View, surface_point,
};
use rayon::prelude::*;
use std::path::Path;

/// The named view `name` of `scene` (error listing the names if unknown), or with `None` the
/// scene's default view and its name.
pub fn pick_view(scene: &Scene, name: Option<&str>) -> Result<(String, View)> {
    match name {
        Some(name) => scene
            .views
            .iter()
            .find(|v| v.name == name)
            .map(|v| (v.name.clone(), v.view))
            .ok_or_else(|| {
                let known: Vec<&str> = scene.views.iter().map(|v| v.name.as_str()).collect();
                anyhow!(
                    "scene `{}` has no view `{name}` (its views: {})",
                    scene.name,
                    known.join(", ")
                )
            }),
        None => {
            let name = scene
                .views
                .iter()
                .find(|v| v.view == scene.view)
                .map_or_else(|| "default".to_owned(), |v| v.name.clone());
            Ok((name, scene.view))
        }
    }
}

/// One camera ray per pixel of a `width × height` image, row-major from the top-left, with the
/// pinhole convention of [`raybench_scenes::primary_rays`] (which is used whenever it makes
/// exactly this size; otherwise the same construction is done here for any aspect).
pub fn camera_rays(view: &View, bounds: &Aabb, width: u32, height: u32) -> Vec<Ray> {
    let n = width as usize * height as usize;
    let (rays, w, h) = raybench_scenes::primary_rays(view, bounds, n);
    if (w, h) == (width, height) {
        rays
    } else {
        local_camera_rays(view, bounds, width, height)
    }
}

/// The construction of the primary workload's `CameraFrame` (raybench-scenes,
/// `workload/primary.rs`) for any `width × height`.
fn local_camera_rays(view: &View, bounds: &Aabb, width: u32, height: u32) -> Vec<Ray> {
    // The same steps as the primary workload's `CameraFrame`, in the same order, so both agree bit for
    // bit (tested): unusable views fall back to the default view of the bounds.
    let view = if view.is_usable() {
        *view
    } else {
        View::of_bounds(bounds)
    };
    let c = &view.camera;
    let forward = (c.target - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let half_height = (c.fov_y_deg.to_radians() * 0.5).tan();
    let half_width = half_height * width as f32 / height as f32;
    let (right, up) = (right * half_width, up * half_height);
    let (wf, hf) = (width as f32, height as f32);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let sx = (2 * u64::from(x) + 1) as f32 / wf - 1.0;
            let sy = 1.0 - (2 * u64::from(y) + 1) as f32 / hf;
            Ray::infinite(c.eye, forward + right * sx + up * sy)
        })
        .collect()
}

/// The sky behind everything, by image row: deep blue at the top to pale at the bottom. Every
/// pixel whose primary ray misses has exactly this colour.
pub fn background(y: u32, height: u32) -> [u8; 3] {
    const TOP: [f32; 3] = [70.0, 120.0, 200.0];
    const BOTTOM: [f32; 3] = [205.0, 222.0, 240.0];
    let s = (y as f32 + 0.5) / height.max(1) as f32;
    std::array::from_fn(|i| (TOP[i] + (BOTTOM[i] - TOP[i]) * s).round() as u8)
}

/// Surface colour (linear), a warm clay so surfaces never look like the blue sky.
const ALBEDO: [f32; 3] = [0.85, 0.62, 0.42];
/// Light every surface gets, lit or not, so shadowed and back-lit parts stay visible.
const AMBIENT: f32 = 0.12;

/// Renders `scene` from `view` into `width × height` RGB pixels, row-major from the top-left.
///
/// Per pixel: the closest hit of the camera ray (Embree, medium quality, all cores); the
/// triangle's geometric normal flipped towards the camera; Lambert from `view.light` (a point
/// light, no falloff) if a shadow ray from the surface to the light is unoccluded, plus ambient;
/// gamma 2.2. Misses are [`background`]. Errors: Embree failing to build, or a bad size.
pub fn render_preview(scene: &Scene, view: &View, width: u32, height: u32) -> Result<Vec<[u8; 3]>> {
    check_size(width, height)?;
    let params = EmbreeParams::medium();
    let accel = <EmbreeScene as Accel>::build(scene.mesh.clone(), &params)
        .with_context(|| format!("building Embree ({}) for {}", params.name(), scene.name))?;
    let mesh = &scene.mesh;
    let rays = camera_rays(view, &mesh.bounds(), width, height);
    let mut pixels = vec![[0u8; 3]; rays.len()];
    pixels
        .par_chunks_mut(width as usize)
        .zip(rays.par_chunks(width as usize))
        .enumerate()
        .for_each(|(y, (row, rays))| {
            let sky = background(y as u32, height);
            for (pixel, ray) in row.iter_mut().zip(rays) {
                *pixel = match accel.intersect(ray) {
                    None => sky,
                    Some(hit) => shade(&accel, mesh, view.light, ray, hit),
                };
            }
        });
    Ok(pixels)
}

fn shade(
    accel: &EmbreeScene,
    mesh: &raybench_geom::TriangleMesh,
    light: Vec3,
    ray: &Ray,
    hit: raybench_accel::Hit,
) -> [u8; 3] {
    let surface = SurfaceHit {
        prim: hit.prim,
        u: hit.u,
        v: hit.v,
    };
    // Zero-area triangles are never hit, so a point without a normal is only ambient light.
    let Some(SurfacePoint { origin, normal, .. }) = surface_point(mesh, ray, &surface) else {
        return ALBEDO.map(|albedo| ((albedo * AMBIENT).powf(1.0 / 2.2) * 255.0).round() as u8);
    };
    let to_light = light - origin;
    let lambert = normal.dot(to_light.normalize_or_zero()).max(0.0);
    let lit = lambert > 0.0 && !accel.occluded(&Ray::new(origin, to_light, 0.0, SHADOW_T_MAX));
    let intensity = AMBIENT + (1.0 - AMBIENT) * if lit { lambert } else { 0.0 };
    ALBEDO.map(|albedo| ((albedo * intensity).powf(1.0 / 2.2) * 255.0).round() as u8)
}

/// What [`preview`] wrote.
#[derive(Debug)]
pub struct PreviewSummary {
    pub scene: String,
    pub view: String,
    pub triangles: usize,
    /// Fraction of pixels whose camera ray hit the scene.
    pub coverage: f64,
}

/// `raybench scene preview`: resolve, pick the view, render, write the PNG.
pub fn preview(
    name: &str,
    view: Option<&str>,
    width: u32,
    height: u32,
    seed: u64,
    out: &Path,
) -> Result<PreviewSummary> {
    check_size(width, height)?;
    let scene = raybench_scenes::resolve(name, seed)?;
    let (view_name, view) = pick_view(&scene, view)?;
    let pixels = render_preview(&scene, &view, width, height)?;
    write_png(&pixels, width, height, out).with_context(|| format!("writing {}", out.display()))?;
    let hits = pixels
        .chunks(width as usize)
        .enumerate()
        .map(|(y, row)| {
            let sky = background(y as u32, height);
            row.iter().filter(|&&p| p != sky).count()
        })
        .sum::<usize>();
    Ok(PreviewSummary {
        scene: match &scene.source {
            SceneSource::Obj { path, .. } => path.display().to_string(),
            SceneSource::Procedural { .. } => name.to_owned(),
        },
        view: view_name,
        triangles: scene.mesh.len(),
        coverage: hits as f64 / pixels.len() as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The local construction matches primary_rays bit for bit where both apply.
    #[test]
    fn camera_rays_follow_the_primary_rays_convention() {
        let scene = raybench_scenes::generate("sphere:triangles=200", 1).unwrap();
        let bounds = scene.mesh.bounds();
        let mut unusable = scene.view;
        unusable.camera.eye = unusable.camera.target;
        for view in [scene.view, unusable] {
            for (w, h) in [(160, 120), (64, 48), (4, 3)] {
                let (expected, ew, eh) = raybench_scenes::primary_rays(&view, &bounds, w * h);
                assert_eq!((ew, eh), (w as u32, h as u32));
                let local = local_camera_rays(&view, &bounds, w as u32, h as u32);
                let bits = |r: &[Ray]| r.iter().map(Ray::to_bits).collect::<Vec<_>>();
                assert_eq!(bits(&local), bits(&expected), "{w}×{h}");
            }
        }
        // A size primary_rays cannot make still has W×H rays, the centre one straight ahead.
        let rays = camera_rays(&scene.view, &bounds, 101, 101);
        assert_eq!(rays.len(), 101 * 101);
        let c = &scene.view.camera;
        let centre = rays[50 * 101 + 50].dir().normalize();
        assert!((centre - (c.target - c.eye).normalize()).length() < 1e-6);
    }
}
