//! Full-resolution pictures of the primary view, drawn by an untimed pass after a structure's
//! timed workloads: primary rays at exactly `width × height` pixels from the workload's view,
//! traced through the counted walk (cost per pixel) and checked against the reference's closest
//! hits with the workloads' own checking code (disagreement per pixel).
//!
//! Nothing here is timed, and nothing here touches a workload's figures: the pass has its own
//! rays, counters and verdicts, and runs after every timed pass of the structure.
//!
//! Per scene one render (the reference's hits, shaded), one heatmap per structure that counts,
//! and a disagreement mask per structure that disagrees with the reference at some pixel. The
//! heatmaps share one logarithmic colour scale per scene, so they are written once the scene's
//! last structure is done; until then each heatmap is kept as `u16` log-quantized costs (half
//! the memory of exact `u32` costs, and finer than any 8-bit colour needs).

use super::check::{Sides, check_answers};
use super::images::shade;
use super::measure::{Answers, count_pass};
use super::workloads::reference_answers;
use crate::output::png::write_png;
use crate::output::render::pictures::{heat_rgb, mask_rgb, render_rgb};
use anyhow::{Context, Result};
use raybench_accel::Accel;
use raybench_accel::classify::Tolerance;
use raybench_geom::{Ray, TriangleMesh};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub use super::picture_set::{PictureSet, StructurePicture};

/// Bounds of `--picture-width`: 64 pixels is the smallest picture worth looking at; at 4096 a
/// scene's pictures hold about 2 GB with a dozen structures ([`picture_bytes`]).
pub const MIN_WIDTH: u32 = 64;
pub const MAX_WIDTH: u32 = 4096;
pub const DEFAULT_WIDTH: u32 = 640;

/// Rays per rayon task of the picture pass (run inside [`pool`]): each task counts its own rays,
/// so the per-pixel costs are exact whatever the thread count.
const CHUNK: usize = 4096;

/// `ln(1 + cost)` in steps of 1/2900: `ln(1 + u32::MAX) × 2900 = 64,325` fits a `u16`.
const LOG_STEPS: f64 = 2900.0;

/// Bytes a scene's picture pass holds per pixel while it runs: the ray (44), the reference's
/// and the structure's hits (20 each), the work, level and shade, and the RGB row of the PNG
/// being written, rounded up; plus 2 per counting structure for the waiting heatmaps.
const BYTES_PER_PIXEL: u64 = 128;
const BYTES_PER_HEATMAP_PIXEL: u64 = 2;

/// Bytes the pictures of one scene need at `width` with `structures` structures.
pub fn picture_bytes(width: u32, structures: usize) -> u64 {
    let pixels = u64::from(width) * u64::from(picture_height(width));
    pixels * (BYTES_PER_PIXEL + BYTES_PER_HEATMAP_PIXEL * structures as u64)
}

/// The pool picture passes run in: every core of the machine, whatever the run's `--threads`
/// (the pass is untimed and runs between timed passes, never beside one), with the run's FPU
/// state on every worker so its answers are the ones the timed threads would give.
pub(crate) fn pool(ftz: bool) -> Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    rayon::ThreadPoolBuilder::new()
        .num_threads(cores)
        .thread_name(|i| format!("raybench-picture-{i}"))
        .start_handler(move |_| raybench_embree::fpu::set_ftz_daz(ftz))
        .build()
        .context("creating the picture pass's thread pool")
}

/// The height of a `width`-wide picture at the workload's 4:3 aspect.
pub fn picture_height(width: u32) -> u32 {
    ((u64::from(width) * 3 + 2) / 4) as u32
}

/// One scene's picture pass in progress: the rays, the reference's answers and shade, and the
/// heatmaps waiting for the scene's maximum cost.
pub(crate) struct ScenePicturePass {
    scene: String,
    dir: PathBuf,
    base: String,
    width: u32,
    height: u32,
    reference_name: String,
    rays: Vec<Ray>,
    reference: Answers,
    shade: Vec<u8>,
    structures: Vec<StructurePicture>,
    /// (index into `structures`, log-quantized cost per pixel)
    heat: Vec<(usize, Vec<u16>)>,
    /// The masks written so far and their levels per pixel: structures that disagree at the
    /// same pixels in the same way (often every structure against one grazing decision of the
    /// reference) share one file instead of repeating a picture.
    masks: Vec<(String, Vec<u8>)>,
    max_cost: u64,
    elapsed: Duration,
}

impl ScenePicturePass {
    /// Traces the picture rays once with the reference. `dir` is the run's output directory;
    /// files go to `dir/images/<base>--…`.
    pub(crate) fn start(
        dir: &Path,
        base: String,
        width: u32,
        scene: &raybench_scenes::Scene,
        reference: &dyn Accel,
        reference_name: &str,
        threads: usize,
    ) -> Result<ScenePicturePass> {
        let start = Instant::now();
        let height = picture_height(width);
        let mesh = &scene.mesh;
        let rays = raybench_scenes::primary_rays_sized(&scene.view, &mesh.bounds(), width, height);
        let answers = reference_answers(reference, &rays, false, threads)?;
        let hits = answers.closest().unwrap_or_default();
        let shade = rays
            .iter()
            .zip(hits)
            .map(|(r, h)| shade(mesh, r, h.as_ref()))
            .collect();
        std::fs::create_dir_all(dir.join("images"))
            .with_context(|| format!("creating {}", dir.join("images").display()))?;
        Ok(ScenePicturePass {
            scene: scene.name.clone(),
            dir: dir.to_owned(),
            base,
            width,
            height,
            reference_name: reference_name.to_string(),
            rays,
            reference: answers,
            shade,
            structures: Vec::new(),
            heat: Vec::new(),
            masks: Vec::new(),
            max_cost: 0,
            elapsed: start.elapsed(),
        })
    }

    /// One structure's picture: its counted walk over the picture rays (in parallel chunks on
    /// the run's pool, each with its own counters), the disagreement per pixel, and the mask
    /// written now if it disagrees anywhere (a mask needs no shared scale).
    pub(crate) fn add(
        &mut self,
        name: &str,
        accel: &dyn Accel,
        mesh: &TriangleMesh,
        reference: &dyn Accel,
        tol: &Tolerance,
    ) -> Result<()> {
        let start = Instant::now();
        let parts: Vec<(Answers, Vec<u32>)> = self
            .rays
            .par_chunks(CHUNK)
            .map(|chunk| {
                let (answers, _, work) = count_pass(accel, chunk, false);
                (answers, work)
            })
            .collect();
        let mut hits = Vec::with_capacity(self.rays.len());
        let mut work = Vec::with_capacity(self.rays.len());
        for (answers, w) in parts {
            hits.extend_from_slice(answers.closest().unwrap_or_default());
            work.extend(w);
        }
        let ours = Answers::Closest(hits);
        let mut entry = StructurePicture {
            structure: name.to_string(),
            heatmap: None,
            mask: None,
            explained_pixels: 0,
            mismatch_pixels: 0,
            pass_ms: 0.0,
        };
        // The reference agrees with itself by definition; its counted walk may still decide a
        // grazing ray differently from its batch path, which the workloads report already.
        if name != self.reference_name {
            let sides = Sides {
                ours: accel,
                reference,
                reference_name: &self.reference_name,
            };
            let (_, levels) = check_answers(mesh, &self.rays, &ours, &self.reference, &sides, tol);
            entry.explained_pixels = levels.iter().filter(|&&l| l == 1).count() as u64;
            entry.mismatch_pixels = levels.iter().filter(|&&l| l >= 2).count() as u64;
            if entry.explained_pixels + entry.mismatch_pixels > 0 {
                entry.mask = Some(self.mask_file(name, levels)?);
            }
        }
        if accel.has_counters() {
            self.max_cost = self
                .max_cost
                .max(work.iter().copied().max().unwrap_or(0).into());
            let quantized = work.iter().map(|&c| log_step(c)).collect();
            self.heat.push((self.structures.len(), quantized));
        }
        entry.pass_ms = start.elapsed().as_secs_f64() * 1e3;
        self.structures.push(entry);
        self.elapsed += start.elapsed();
        Ok(())
    }

    /// Writes the render and the heatmaps (on the scene's shared scale) and returns the record.
    pub(crate) fn finish(mut self) -> Result<PictureSet> {
        let start = Instant::now();
        let render = self.file("render");
        self.write(&render_rgb(&self.shade), &render)?;
        let top = log_step(self.max_cost.min(u64::from(u32::MAX)) as u32);
        let heat = std::mem::take(&mut self.heat);
        let written: Vec<(usize, String)> = heat
            .par_iter()
            .map(|(i, quantized)| {
                let name = slug(&self.structures[*i].structure);
                let file = self.file(&format!("{name}-cost"));
                self.write(&heat_rgb(quantized, top), &file)?;
                Ok((*i, file))
            })
            .collect::<Result<_>>()?;
        for (i, file) in written {
            self.structures[i].heatmap = Some(file);
        }
        self.elapsed += start.elapsed();
        Ok(PictureSet {
            scene: self.scene,
            width: self.width,
            height: self.height,
            max_cost: self.max_cost,
            reference: self.reference_name,
            render,
            structures: self.structures,
            pass_ms: self.elapsed.as_secs_f64() * 1e3,
        })
    }

    /// The mask file for `levels`: an earlier structure's when they are the same, else a new one.
    fn mask_file(&mut self, name: &str, levels: Vec<u8>) -> Result<String> {
        if let Some((file, _)) = self.masks.iter().find(|(_, l)| *l == levels) {
            return Ok(file.clone());
        }
        let file = self.file(&format!("{}-disagree", slug(name)));
        let pixels = mask_rgb(&self.shade, &levels, self.width as usize);
        self.write(&pixels, &file)?;
        self.masks.push((file.clone(), levels));
        Ok(file)
    }

    /// `images/<base>--<what>-<W>x<H>.png`: the size in the name keeps these apart from the
    /// small pictures `raybench report` draws from report.json's planes.
    fn file(&self, what: &str) -> String {
        format!(
            "images/{}--{what}-{}x{}.png",
            self.base, self.width, self.height
        )
    }

    fn write(&self, pixels: &[[u8; 3]], file: &str) -> Result<()> {
        write_png(pixels, self.width, self.height, &self.dir.join(file))
    }
}

/// A cost on the quantized log scale: `round(ln(1 + c) × LOG_STEPS)`.
fn log_step(c: u32) -> u16 {
    ((1.0 + f64::from(c)).ln() * LOG_STEPS).round() as u16
}

fn slug(name: &str) -> String {
    crate::output::render::names::slug(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_are_three_quarters_of_the_width_rounded() {
        assert_eq!(picture_height(640), 480);
        assert_eq!(picture_height(64), 48);
        assert_eq!(picture_height(365), 274);
        assert_eq!(picture_height(4096), 3072);
    }

    /// The reference against itself and an agreeing twin get no mask; a structure built on a
    /// smaller sphere (it answers for other geometry) gets one, with mismatches counted, shared
    /// with a second structure that disagrees at the same pixels in the same way; every
    /// structure counts, so each gets a heatmap, and the files are `width × height`.
    #[test]
    fn masks_are_written_only_for_structures_that_disagree() {
        use raybench_accel::{BruteForce, BruteForceParams};
        let load = |spec: &str| {
            raybench_scenes::SceneRequest::Spec(spec.into())
                .load(1)
                .unwrap()
                .unwrap()
        };
        let scene = load("sphere:triangles=200");
        let smaller = load("sphere:triangles=200,radius=0.6");
        assert_eq!(scene.mesh.len(), smaller.mesh.len());
        let params = BruteForceParams::default();
        let reference = BruteForce::build(scene.mesh.clone(), &params).unwrap();
        let twin = BruteForce::build(scene.mesh.clone(), &params).unwrap();
        let wrong = BruteForce::build(smaller.mesh.clone(), &params).unwrap();
        let dir = std::env::temp_dir().join(format!("raybench-picture-{}", std::process::id()));
        let mut pass =
            ScenePicturePass::start(&dir, "s".into(), 64, &scene, &reference, "ref", 1).unwrap();
        let tol = Tolerance::default();
        let structures = [
            ("ref", &reference),
            ("twin", &twin),
            ("wrong", &wrong),
            ("wrong-too", &wrong),
        ];
        for (name, accel) in structures {
            pass.add(name, accel, &scene.mesh, &reference, &tol)
                .unwrap();
        }
        let set = pass.finish().unwrap();
        assert_eq!((set.width, set.height), (64, 48));
        assert_eq!(set.render, "images/s--render-64x48.png");
        let masks: Vec<_> = set.structures.iter().map(|s| s.mask.is_some()).collect();
        assert_eq!(masks, [false, false, true, true]);
        // The same disagreement is one file, not two copies.
        assert_eq!(set.structures[3].mask, set.structures[2].mask);
        assert_eq!(set.files().len(), 1 + 4 + 1);
        assert!(set.structures[2].mismatch_pixels > 0);
        assert_eq!(
            set.structures[1].explained_pixels + set.structures[1].mismatch_pixels,
            0
        );
        assert!(set.structures.iter().all(|s| s.heatmap.is_some()));
        assert!(
            set.max_cost >= 200,
            "brute force tests every triangle: {}",
            set.max_cost
        );
        assert_eq!(set.check_files(&dir), Ok(()));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn log_steps_fit_u16_and_keep_order() {
        assert_eq!(log_step(0), 0);
        assert!(log_step(u32::MAX) > log_step(u32::MAX - 1_000_000));
        assert!(log_step(1) < log_step(2) && log_step(99) < log_step(100));
        assert!(u32::from(log_step(u32::MAX)) < 65_535);
    }
}
