//! `raybench report`: charts, pictures and one static HTML page, drawn from `report.json` alone.
//!
//! Output layout under the chosen directory:
//! * `charts/*.svg` — build time, Mrays/s (Mqueries/s for closest-point workloads) and ratios
//!   to the reference per workload, memory per triangle, counters per query (bars per scene, or
//!   lines against the swept parameter when the report is a sweep), scaling curves with fitted
//!   exponents and theory slopes (when the scenes grow), break-even per scene, validation
//!   classes; one colour per structure throughout;
//! * `images/*.png` — per scene and structure: traversal-cost heatmap (one colour scale per
//!   scene), shaded render, disagreement mask; one legend colour bar;
//! * `index.html` — tables (with the fitted exponents of a size sweep), the charts, the
//!   pictures and the environment; no JavaScript.
//!
//! Every file is written atomically (a temporary file, then a rename).

mod answer;
mod break_even;
pub mod charts;
mod claims_section;
mod figures;
pub mod fit;
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
pub mod sweep;
mod sweep_charts;
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
    pub index: PathBuf,
}

/// A chart as the page shows it.
#[derive(Clone, Debug)]
pub(crate) struct ChartFile {
    pub file: String,
    pub caption: String,
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
    for (file, caption, svg) in all_charts(report, sweep.as_ref())? {
        let path = dir.join("charts").join(&file);
        write_atomic(&path, svg.as_bytes())?;
        out.charts.push(path);
        chart_files.push(ChartFile {
            file: format!("charts/{file}"),
            caption,
        });
    }
    let pictures = picture_files::write_pictures(report, dir, &mut out.images)?;
    let exponents = Sizes::of(report, sweep.as_ref()).map(|sizes| Exponents::of(report, &sizes));
    let page = page::page(
        report,
        &page::Extras {
            charts: &chart_files,
            pictures: &pictures,
            sweep: sweep.as_ref(),
            exponents: exponents.as_ref(),
        },
    );
    out.index = dir.join("index.html");
    write_atomic(&out.index, page.as_bytes())?;
    Ok(out)
}
