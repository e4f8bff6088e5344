//! The picture files a page shows, per scene: the full-resolution PNGs `raybench run` wrote
//! beside the report (listed in its `pictures`), or, where those are absent, pictures drawn
//! from the small planes stored in `report.json` (one render, a heatmap per counting structure
//! on the scene's shared scale, a mask per disagreeing structure), with the reason said.

use super::ScenePictures;
use super::names::{scene_names, scene_slugs, slug};
use super::pictures;
use crate::pipeline::images::PrimaryImage;
use crate::pipeline::picture::{PictureSet, StructurePicture};
use crate::report::run::{Report, ResultEntry};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

pub(super) fn write_pictures(
    report: &Report,
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<Vec<ScenePictures>> {
    let mut out = Vec::new();
    let slugs = scene_slugs(report);
    for scene in scene_names(report) {
        let set = report.pictures.iter().find(|p| p.scene == scene);
        let missing = match set.map(|set| set.check_files(dir)) {
            Some(Ok(())) => {
                out.push(full_size(set.expect("matched")));
                continue;
            }
            Some(Err(why)) => why,
            None => "this report has no full-size pictures of it".to_string(),
        };
        let entries: Vec<&ResultEntry> = report
            .results
            .iter()
            .filter(|r| r.scene == scene && r.primary_image.is_some())
            .collect();
        if entries.is_empty() {
            continue;
        }
        let base = &slugs[&scene];
        let small = small_pictures(report, &scene, base, &entries, dir, written)
            .with_context(|| format!("the pictures of {scene}"))?;
        out.push(ScenePictures {
            fallback: Some(missing),
            ..small
        });
    }
    Ok(out)
}

/// The page's view of a scene's full-resolution files.
fn full_size(set: &PictureSet) -> ScenePictures {
    ScenePictures {
        scene: set.scene.clone(),
        width: set.width,
        height: set.height,
        max_cost: set.max_cost,
        fallback: None,
        render: Some((set.reference.clone(), set.render.clone())),
        structures: set.structures.clone(),
    }
}

/// A scene's pictures drawn from the planes stored in report.json (at most 160 pixels wide):
/// the render of the reference's plane (or the first structure's, if the reference has none),
/// heatmaps on the scene's shared scale, masks where a structure disagrees.
fn small_pictures(
    report: &Report,
    scene: &str,
    base: &str,
    entries: &[&ResultEntry],
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<ScenePictures> {
    let images: Vec<&PrimaryImage> = entries
        .iter()
        .filter_map(|r| r.primary_image.as_ref())
        .collect();
    let max = pictures::shared_max(&images);
    let shown = entries
        .iter()
        .find(|r| r.structure == report.run.reference)
        .unwrap_or(&entries[0]);
    let img = shown.primary_image.as_ref().expect("filtered");
    let render = format!("images/{base}--render.png");
    pictures::write(&pictures::shade_pixels(img)?, img, &dir.join(&render))?;
    written.push(dir.join(&render));
    let mut structures = Vec::new();
    let mut masks: Vec<(String, Vec<u8>)> = Vec::new();
    for r in entries {
        let img = r.primary_image.as_ref().expect("filtered");
        let file = |kind: &str| format!("images/{base}--{}-{kind}.png", slug(&r.structure));
        let heatmap = match pictures::heatmap_pixels(img, max)? {
            Some(px) => {
                let f = file("cost");
                pictures::write(&px, img, &dir.join(&f))?;
                written.push(dir.join(&f));
                Some(f)
            }
            None => None,
        };
        let levels = img.disagree_values().map_err(anyhow::Error::msg)?;
        let explained = levels.iter().filter(|&&l| l == 1).count() as u64;
        let mismatched = levels.iter().filter(|&&l| l >= 2).count() as u64;
        let mask = if explained + mismatched == 0 {
            None
        } else if let Some((f, _)) = masks.iter().find(|(_, l)| *l == levels) {
            Some(f.clone())
        } else {
            let f = file("disagree");
            pictures::write(&pictures::disagree_pixels(img)?, img, &dir.join(&f))?;
            written.push(dir.join(&f));
            masks.push((f.clone(), levels));
            Some(f)
        };
        structures.push(StructurePicture {
            structure: r.structure.clone(),
            heatmap,
            mask,
            explained_pixels: explained,
            mismatch_pixels: mismatched,
            pass_ms: 0.0,
        });
    }
    Ok(ScenePictures {
        scene: scene.to_string(),
        width: img.width,
        height: img.height,
        max_cost: max.into(),
        fallback: None,
        render: Some((shown.structure.clone(), render)),
        structures,
    })
}
