//! The record of a scene's full-resolution pictures in `report.json`, and the checks a reader
//! makes before it trusts the files a report names (a report may come from anywhere).

use crate::atomic::write_atomic;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A scene's full-resolution pictures as recorded in `report.json` (`pictures[]`; see
/// docs/report-format.md, "Pictures"). File names are relative to the report's directory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PictureSet {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// The largest traversal cost of any counting structure at any pixel: the top of the
    /// scene's colour scale (0 when no structure counts).
    pub max_cost: u64,
    /// The structure whose closest hits are shaded in the render (the run's reference).
    pub reference: String,
    pub render: String,
    /// One entry per structure measured on the scene, in the run's order.
    pub structures: Vec<StructurePicture>,
    /// Wall time of the scene's untimed picture passes (the reference's and every structure's),
    /// milliseconds: what the pictures added to the run.
    pub pass_ms: f64,
}

/// One structure's pictures of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StructurePicture {
    pub structure: String,
    /// The traversal-cost heatmap; absent for a structure that cannot count (Embree).
    pub heatmap: Option<String>,
    /// The disagreement mask; absent when the structure agrees with the reference at every
    /// pixel. Structures that disagree at the same pixels in the same way share one file.
    pub mask: Option<String>,
    /// Pixels that differ from the reference for an explained reason (tie, boundary,
    /// edge-ambiguous).
    pub explained_pixels: u64,
    /// Pixels that are mismatches.
    pub mismatch_pixels: u64,
    /// Wall time of this structure's picture pass (counted walk, check, mask), milliseconds.
    #[serde(default)]
    pub pass_ms: f64,
}

impl PictureSet {
    /// Every file the set lists, once each (structures may share a mask), as paths relative
    /// to the report's directory.
    pub fn files(&self) -> Vec<&String> {
        let mut files = vec![&self.render];
        for st in &self.structures {
            for f in st.heatmap.iter().chain(st.mask.iter()) {
                if !files.contains(&f) {
                    files.push(f);
                }
            }
        }
        files
    }

    /// `Ok` when every file of the set is in `dir` as a PNG of the set's size; otherwise why not.
    pub fn check_files(&self, dir: &Path) -> Result<(), String> {
        for file in self.files() {
            if !is_safe_name(file) {
                return Err(format!(
                    "the report names an unusable picture file {file:?}"
                ));
            }
            match png_size(&dir.join(file)) {
                Some(size) if size == (self.width, self.height) => {}
                Some((w, h)) => {
                    return Err(format!(
                        "{file} is {w}×{h} pixels, not the {}×{} the report records",
                        self.width, self.height
                    ));
                }
                None => {
                    return Err(format!(
                        "the full-size files were not found beside the report ({file} is missing \
                         or not a PNG)"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A listed file name is `images/` and a plain file name ending in `.png`: a report never makes
/// the page (or the copy) reach outside `images/`.
pub fn is_safe_name(file: &str) -> bool {
    let Some(name) = file.strip_prefix("images/") else {
        return false;
    };
    name.len() > 4
        && name.len() <= 200
        && name.ends_with(".png")
        && !name.starts_with('.')
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"._-".contains(&b))
}

/// Width and height from a PNG's header, or `None` if it is not a readable PNG.
fn png_size(path: &Path) -> Option<(u32, u32)> {
    let file = std::fs::File::open(path).ok()?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .ok()?;
    let info = reader.info();
    Some((info.width, info.height))
}

/// Copies the full-resolution files of `sets` from `from` (the report's directory) into `to`,
/// for a report drawn elsewhere. A set whose files are absent or unusable is skipped: the page
/// then draws that scene from the small planes and says so. Returns the files copied.
pub fn copy_pictures(sets: &[PictureSet], from: &Path, to: &Path) -> Result<Vec<PathBuf>> {
    let mut copied = Vec::new();
    for set in sets {
        if set.check_files(from).is_err() {
            continue;
        }
        std::fs::create_dir_all(to.join("images"))
            .with_context(|| format!("creating {}", to.join("images").display()))?;
        for file in set.files() {
            let bytes = std::fs::read(from.join(file))
                .with_context(|| format!("reading {}", from.join(file).display()))?;
            write_atomic(&to.join(file), &bytes)?;
            copied.push(to.join(file));
        }
    }
    Ok(copied)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_plain_png_names_under_images_are_used() {
        assert!(is_safe_name("images/teapot--bvh8-binned-cost-640x480.png"));
        for bad in [
            "images/../report.json",
            "images/a/b.png",
            "/etc/passwd.png",
            "images/.png",
            "images/.hidden.png",
            "images/a.svg",
            "charts/a.png",
            "images/a b.png",
            "images/a\\b.png",
        ] {
            assert!(!is_safe_name(bad), "{bad}");
        }
    }
}
