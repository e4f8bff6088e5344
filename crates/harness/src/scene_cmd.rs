//! `raybench scene list | export | preview`: see what scenes exist, write one as OBJ, and render
//! a shaded picture of it through its camera, so a person can check a scene before measuring.
//!
//! * [`write_generators`] and [`write_real_scenes`] print the scene part of both `raybench list`
//!   and `raybench scene list` (the latter adds each generator's named views).
//! * [`export`]: a scene spec or an OBJ path → an OBJ file, atomically, through
//!   [`raybench_scenes::write_obj`]; the file loads back bit for bit.
//! * [`render_preview`]: one primary ray per pixel, traced with Embree (medium quality, all
//!   cores), Lambert shading from the view's point light with a shadow ray, plus ambient; misses
//!   show a sky gradient. [`preview`] writes it as a PNG with plotters' bitmap backend.

use anyhow::{Context, Result, anyhow, bail};
use plotters::prelude::{BitMapBackend, DrawingBackend};
use raybench_accel::Accel;
use raybench_embree::{EmbreeParams, EmbreeScene};
use raybench_geom::{Aabb, Ray, Vec3};
use raybench_scenes::{
    GeneratorInfo, Kind, SHADOW_T_MAX, Scene, SceneSource, SurfaceHit, SurfacePoint, View,
    surface_point,
};
use rayon::prelude::*;
use std::io::{self, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

/// Where real OBJ scenes are looked for: `../shared/scenes` next to the repository.
pub fn real_scenes_dir() -> PathBuf {
    raybench_scenes::suites_dir().join("../../shared/scenes")
}

/// The `*.obj` files (any case) in [`real_scenes_dir`], sorted.
pub fn real_scenes() -> io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(real_scenes_dir())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("obj")))
        .collect();
    files.sort();
    Ok(files)
}

/// Triangle budget used to learn a generator's views: views come from the generator's layout,
/// not from its size, and a few hundred triangles cost nothing.
const VIEW_PROBE_TRIANGLES: u64 = 200;

/// The spec [`write_generators`] generates to learn the views of `info`: the generator at
/// [`VIEW_PROBE_TRIANGLES`] if it has a `triangles` parameter, else at its defaults.
pub fn view_probe_spec(info: &GeneratorInfo) -> String {
    match info.params.iter().find(|p| p.key == "triangles") {
        Some(p) => {
            let n = match p.kind {
                Kind::Count { min, max } => VIEW_PROBE_TRIANGLES.clamp(min, max),
                Kind::Real { .. } => VIEW_PROBE_TRIANGLES,
            };
            format!("{}:triangles={n}", info.name)
        }
        None => info.name.to_owned(),
    }
}

/// The names of `info`'s views, by generating it small; the error says what failed (a generator
/// error, or a panic, which is caught so one broken generator does not hide the others).
pub fn generator_views(info: &GeneratorInfo) -> Result<Vec<String>, String> {
    let spec = view_probe_spec(info);
    match catch_unwind(AssertUnwindSafe(|| raybench_scenes::generate(&spec, 1))) {
        Ok(Ok(scene)) => Ok(scene.views.into_iter().map(|v| v.name).collect()),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!(
            "generator spec `{spec}`: panicked: {}",
            panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into())
        )),
    }
}

/// Every generator with its description and parameters; with `views`, also its named views
/// (or why they could not be learned). Returns how many generators failed to generate.
pub fn write_generators(out: &mut dyn Write, views: bool) -> io::Result<usize> {
    let mut failed = 0;
    writeln!(
        out,
        "Scene generators (spec: name[:key=value,...]; every generator also takes view=NAME):"
    )?;
    for g in raybench_scenes::generators() {
        writeln!(out, "  {:<24} {}", g.name, g.description)?;
        for p in g.params {
            writeln!(out, "  {:<24}   {}: {}", "", p.key, p.describe())?;
        }
        if views {
            match generator_views(g) {
                Ok(names) => writeln!(out, "  {:<24}   views: {}", "", names.join(", "))?,
                Err(e) => {
                    failed += 1;
                    writeln!(out, "  {:<24}   views: ERROR: {e}", "")?;
                }
            }
        }
    }
    writeln!(
        out,
        "  {:<24} a Wavefront OBJ file (triangulated, positions only){}",
        "PATH.obj",
        if views { "; views: default" } else { "" }
    )?;
    Ok(failed)
}

/// The real OBJ scenes in [`real_scenes_dir`] with their sizes, or a note that it is absent.
pub fn write_real_scenes(out: &mut dyn Write) -> io::Result<()> {
    let dir = real_scenes_dir();
    let shown = dir.canonicalize().unwrap_or_else(|_| dir.clone());
    match real_scenes() {
        Ok(files) => {
            writeln!(out, "Real scenes ({}):", shown.display())?;
            if files.is_empty() {
                writeln!(out, "  (no .obj files)")?;
            }
            for f in files {
                let size = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
                let name = f.file_name().unwrap_or_default().to_string_lossy();
                writeln!(
                    out,
                    "  {name:<32} {:>8.1} MB  {}",
                    size as f64 / 1e6,
                    shown.join(&*name).display()
                )?;
            }
        }
        Err(_) => writeln!(
            out,
            "Real scenes: {} is absent (suites skip those files with a note)",
            dir.display()
        )?,
    }
    Ok(())
}

/// `raybench scene list`. Generators that fail are listed with their error (and counted on
/// stderr), not hidden; the listing itself still succeeds.
pub fn list(out: &mut dyn Write) -> io::Result<()> {
    let failed = write_generators(out, true)?;
    writeln!(out)?;
    write_real_scenes(out)?;
    out.flush()?;
    if failed > 0 {
        eprintln!("raybench: {failed} generator(s) failed to generate (see `views: ERROR` above)");
    }
    Ok(())
}

fn is_obj_path(name: &str) -> bool {
    Path::new(name)
        .extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("obj"))
}

/// `name` with `triangles=N` set: an error for an OBJ path, for a generator without a
/// `triangles` parameter (naming it and its parameters), and for a spec that sets it already.
/// An unknown generator is left as it is, for [`raybench_scenes::resolve`] to report.
pub fn with_triangles(name: &str, triangles: Option<u64>) -> Result<String> {
    let Some(n) = triangles else {
        return Ok(name.to_owned());
    };
    if is_obj_path(name) {
        bail!("--triangles {n}: `{name}` is an OBJ file; --triangles applies to generators");
    }
    let (gen_name, rest) = name.split_once(':').unwrap_or((name, ""));
    let Some(info) = raybench_scenes::generators()
        .iter()
        .find(|g| g.name.eq_ignore_ascii_case(gen_name.trim()))
    else {
        return Ok(name.to_owned());
    };
    if !info.params.iter().any(|p| p.key == "triangles") {
        let keys: Vec<&str> = info.params.iter().map(|p| p.key).collect();
        bail!(
            "--triangles {n}: generator `{}` has no `triangles` parameter (its parameters: {})",
            info.name,
            if keys.is_empty() {
                "none".to_owned()
            } else {
                keys.join(", ")
            }
        );
    }
    let sets_it = rest.split(',').any(|item| {
        item.split_once('=')
            .is_some_and(|(k, _)| k.trim() == "triangles")
    });
    if sets_it {
        bail!("--triangles {n} and `triangles=` in the spec `{name}`: give one of them");
    }
    Ok(if rest.trim().is_empty() {
        format!("{}:triangles={n}", gen_name.trim())
    } else {
        format!("{name},triangles={n}")
    })
}

/// What [`export`] wrote.
#[derive(Debug)]
pub struct ExportSummary {
    /// The spec that makes this mesh again (with `--triangles` folded in).
    pub spec: String,
    pub vertices: usize,
    pub triangles: usize,
    /// Vertices of the scene's mesh not written (unused by any triangle).
    pub unused_vertices: usize,
    /// True when the file's vertex numbering differs from the scene's (see
    /// [`raybench_scenes::in_file_order`]); triangle order is always kept.
    pub renumbered: bool,
    /// Loader notes and removed-triangle counts of the scene, for the user.
    pub notes: Vec<String>,
}

/// `raybench scene export`: resolves `name` (generator spec or .obj path) with `triangles` and
/// `seed` and writes it to `out` as OBJ, atomically. Nothing is created when anything fails.
pub fn export(name: &str, triangles: Option<u64>, seed: u64, out: &Path) -> Result<ExportSummary> {
    let spec = with_triangles(name, triangles)?;
    let scene = raybench_scenes::resolve(&spec, seed)?;
    let source = serde_json::to_string(&scene.source)?;
    let header = format!(
        "raybench {} scene export\nspec: {spec}\nseed: {seed}\nsource: {source}\nscene: {}",
        env!("CARGO_PKG_VERSION"),
        scene.name
    );
    raybench_scenes::write_obj(&scene.mesh, &header, out)?;
    let written = raybench_scenes::in_file_order(&scene.mesh);
    let mut notes = scene.loader_notes.clone();
    let removed = scene.removed;
    if removed.total() > 0 {
        notes.push(format!(
            "{} triangles were removed before export (Embree would ignore them)",
            removed.total()
        ));
    }
    Ok(ExportSummary {
        spec,
        vertices: written.positions().len(),
        triangles: written.len(),
        unused_vertices: scene.mesh.positions().len() - written.positions().len(),
        renumbered: written != *scene.mesh,
        notes,
    })
}

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

/// Largest preview side, and largest pixel count (64 Mi pixels = 192 MiB of RGB).
pub const MAX_PREVIEW_SIDE: u32 = 16_384;
pub const MAX_PREVIEW_PIXELS: u64 = 1 << 26;

fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 || width > MAX_PREVIEW_SIDE || height > MAX_PREVIEW_SIDE {
        bail!("image size {width}×{height}: each side must be 1 to {MAX_PREVIEW_SIDE}");
    }
    if u64::from(width) * u64::from(height) > MAX_PREVIEW_PIXELS {
        bail!("image size {width}×{height}: more than {MAX_PREVIEW_PIXELS} pixels");
    }
    Ok(())
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

/// The construction of workload.rs's `CameraFrame` for any `width × height`.
fn local_camera_rays(view: &View, bounds: &Aabb, width: u32, height: u32) -> Vec<Ray> {
    // The same steps as workload.rs `CameraFrame`, in the same order, so both agree bit for
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

/// Writes RGB pixels (row-major from the top-left) as a PNG, atomically: a temporary `.png`
/// next to `out` (plotters picks the format from the extension), then a rename over `out`.
pub fn write_png(pixels: &[[u8; 3]], width: u32, height: u32, out: &Path) -> Result<()> {
    check_size(width, height)?;
    anyhow::ensure!(
        pixels.len() == width as usize * height as usize,
        "{} pixels for a {width}×{height} image",
        pixels.len()
    );
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "preview.png".into());
    let tmp = out.with_file_name(format!(".{name}.tmp-{}.png", std::process::id()));
    let result = (|| -> Result<()> {
        let flat: Vec<u8> = pixels.iter().flatten().copied().collect();
        let mut backend = BitMapBackend::new(&tmp, (width, height));
        backend
            .blit_bitmap((0, 0), (width, height), &flat)
            .map_err(|e| anyhow!("{}: {e}", tmp.display()))?;
        backend
            .present()
            .map_err(|e| anyhow!("{}: {e}", tmp.display()))?;
        drop(backend);
        std::fs::rename(&tmp, out)
            .with_context(|| format!("{} (renaming {} over it)", out.display(), tmp.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
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
            SceneSource::Obj { path } => path.display().to_string(),
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
