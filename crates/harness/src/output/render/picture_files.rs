//! The PNG files of a report's per-pixel pictures: per scene and structure a traversal-cost
//! heatmap on the scene's shared colour scale, a shaded render and a disagreement mask, plus
//! the colour bar.

use super::ScenePictures;
use super::names::{scene_names, scene_slugs, slug};
use super::pictures;
use crate::report::run::{Report, ResultEntry};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

pub(super) fn write_pictures(
    report: &Report,
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<Vec<ScenePictures>> {
    let legend = dir.join("images").join("legend-viridis.png");
    pictures::write_legend(&legend)?;
    written.push(legend);
    let mut out = Vec::new();
    let slugs = scene_slugs(report);
    for scene in scene_names(report) {
        let entries: Vec<&ResultEntry> = report
            .results
            .iter()
            .filter(|r| r.scene == scene && r.primary_image.is_some())
            .collect();
        if entries.is_empty() {
            continue;
        }
        let images: Vec<_> = entries
            .iter()
            .filter_map(|r| r.primary_image.as_ref())
            .collect();
        let max = pictures::shared_max(&images);
        let mut rows = Vec::new();
        for r in &entries {
            let img = r.primary_image.as_ref().expect("filtered");
            let base = format!("{}--{}", slugs[&scene], slug(&r.structure));
            let file = |kind: &str| format!("images/{base}-{kind}.png");
            let row = (|| -> Result<_> {
                let heat = match pictures::heatmap_pixels(img, max)? {
                    Some(px) => {
                        let f = file("cost");
                        pictures::write(&px, img, &dir.join(&f))?;
                        written.push(dir.join(&f));
                        Some(f)
                    }
                    None => None,
                };
                let render = file("render");
                pictures::write(&pictures::shade_pixels(img)?, img, &dir.join(&render))?;
                let mask = file("disagree");
                pictures::write(&pictures::disagree_pixels(img)?, img, &dir.join(&mask))?;
                written.push(dir.join(&render));
                written.push(dir.join(&mask));
                Ok((r.structure.clone(), heat, render, mask))
            })()
            .with_context(|| format!("the pictures of {scene} / {}", r.structure))?;
            rows.push(row);
        }
        out.push(ScenePictures {
            scene,
            max_cost: max,
            downsample: images[0].downsample,
            rows,
        });
    }
    Ok(out)
}
