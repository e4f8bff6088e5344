//! `raybench report`: charts, pictures and a small static site, drawn from `report.json` alone.
//!
//! Output layout under the chosen directory:
//! * `index.html` — the summary: the run, the answer per scene and workload, each structure's
//!   geometric means with their spread, the claims, links to every other page; a few screens
//!   tall whatever the suite;
//! * `scene-<slug>.html` — one per scene: its results, break-even chart and pictures;
//! * `charts.html` — the charts across scenes; `details.html` — every result, the agreement
//!   per class, notes and errors, the environment;
//! * `charts/*.svg` — build time, Mrays/s (Mqueries/s for closest-point workloads) and ratios
//!   to the reference per workload, memory per triangle, counters per query (bars per scene, or
//!   lines against the swept parameter when the report is a sweep), scaling curves with fitted
//!   exponents and theory slopes (when the scenes grow), break-even per scene, validation
//!   classes; one colour per structure throughout;
//! * `images/*.png` — per scene: the reference's shaded render and each counting structure's
//!   traversal-cost heatmap on one colour scale, at the full picture size when `raybench run`
//!   drew them (copied from beside the report), else drawn from the small planes in
//!   `report.json`; disagreement masks only for structures that disagree.
//!
//! The pages are static; a few lines of inline script sort the tables, and every page reads
//! the same without it. Every file is written atomically (a temporary file, then a rename).

mod answer;
mod break_even;
pub mod charts;
mod claims_section;
mod details_page;
mod environment;
mod figures;
pub mod fit;
mod geomeans;
mod legend;
pub mod lines;
pub mod names;
mod overlay;
mod page;
pub mod palette;
mod picture_files;
mod picture_section;
pub mod pictures;
mod scaling;
mod scene_page;
mod summary_page;
pub mod sweep;
mod sweep_charts;
mod tables;
pub mod ticks;

use crate::atomic::write_atomic;
use crate::report::run::Report;
use anyhow::{Context, Result};
use figures::all_charts;
use scaling::{Exponents, Sizes};
use std::path::{Path, PathBuf};
use sweep::Sweep;

/// Chart size in pixels (SVG user units).
const W: u32 = 1100;
const H: u32 = 520;

/// What `render` wrote, for the caller to print.
#[derive(Debug, Default)]
pub struct Rendered {
    pub charts: Vec<PathBuf>,
    pub images: Vec<PathBuf>,
    /// The summary page.
    pub index: PathBuf,
    /// Every page: the summary, the scene pages, the charts and the details.
    pub pages: Vec<PathBuf>,
}

/// A chart as the page shows it.
#[derive(Clone, Debug)]
pub(crate) struct ChartFile {
    pub file: String,
    pub caption: String,
    /// The scene a chart is about (a break-even chart), shown on its page; `None`: across
    /// scenes, shown on the charts page.
    pub scene: Option<String>,
}

/// Pictures of one scene, as a page shows them (paths relative to the page's directory).
#[derive(Clone, Debug)]
pub(crate) struct ScenePictures {
    pub scene: String,
    /// Pixel size of the picture files.
    pub width: u32,
    pub height: u32,
    /// The top of the scene's colour scale: the largest cost per pixel of any structure.
    pub max_cost: u64,
    /// Why the small planes of report.json were drawn instead of full-size files; `None` when
    /// the files are full size.
    pub fallback: Option<String>,
    /// The structure whose hits are shaded, and the render file.
    pub render: Option<(String, String)>,
    /// Per structure: its heatmap (absent: not counted) and mask (absent: agrees everywhere).
    pub structures: Vec<crate::pipeline::picture::StructurePicture>,
}

pub fn render(report: &Report, dir: &Path) -> Result<Rendered> {
    std::fs::create_dir_all(dir.join("charts"))
        .with_context(|| format!("creating {}", dir.display()))?;
    std::fs::create_dir_all(dir.join("images"))
        .with_context(|| format!("creating {}", dir.display()))?;
    let mut out = Rendered::default();
    let mut chart_files = Vec::new();
    let sweep = Sweep::detect(report);
    for c in all_charts(report, sweep.as_ref())? {
        let path = dir.join("charts").join(&c.file);
        write_atomic(&path, c.svg.as_bytes())?;
        out.charts.push(path);
        chart_files.push(ChartFile {
            file: format!("charts/{}", c.file),
            caption: c.caption,
            scene: c.scene,
        });
    }
    let mut claim_charts = Vec::new();
    for (file, svg) in claims_section::claim_charts(report)? {
        let path = dir.join(&file);
        write_atomic(&path, svg.as_bytes())?;
        out.charts.push(path);
        claim_charts.push(file);
    }
    let pictures = picture_files::write_pictures(report, dir, &mut out.images)?;
    let exponents = Sizes::of(report, sweep.as_ref()).map(|sizes| Exponents::of(report, &sizes));
    let site = page::Site::new(
        report,
        &chart_files,
        &pictures,
        sweep.as_ref(),
        exponents.as_ref(),
        &claim_charts,
    );
    let mut pages = vec![(
        page::SUMMARY_FILE.to_string(),
        summary_page::summary_page(&site),
    )];
    for (scene, file) in &site.scenes {
        pages.push((file.clone(), scene_page::scene_page(&site, scene)));
    }
    pages.push((
        page::CHARTS_FILE.to_string(),
        details_page::charts_page(&site),
    ));
    pages.push((
        page::DETAILS_FILE.to_string(),
        details_page::details_page(&site),
    ));
    // The summary last: a reader who finds `index.html` finds the pages it links.
    pages.rotate_left(1);
    for (file, html) in pages {
        let path = dir.join(file);
        write_atomic(&path, html.as_bytes())?;
        out.pages.push(path);
    }
    out.index = dir.join(page::SUMMARY_FILE);
    Ok(out)
}
