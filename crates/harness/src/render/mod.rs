//! `raybench report`: charts, pictures and one static HTML page, drawn from `report.json` alone.
//!
//! Output layout under the chosen directory:
//! * `charts/*.svg` — build time, Mrays/s (Mqueries/s for closest-point workloads) and ratios to the reference per workload, memory per
//!   triangle, counters per ray, scaling curves with reference slopes (when one scene family
//!   comes in three or more sizes), break-even per scene, validation classes;
//! * `images/*.png` — per scene and structure: traversal-cost heatmap (one colour scale per
//!   scene), shaded render, disagreement mask; one legend colour bar;
//! * `index.html` — tables, the charts, the pictures and the environment; no JavaScript.
//!
//! Every file is written atomically (a temporary file, then a rename).

pub mod charts;
mod html;
pub mod pictures;

use crate::report::{Report, ResultEntry, throughput_unit};
use anyhow::{Context, Result};
use charts::{Bars, LogLog, Series};
use std::path::{Path, PathBuf};

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

/// Pictures of one scene.
#[derive(Clone, Debug)]
pub(crate) struct ScenePictures {
    pub scene: String,
    pub max_cost: u16,
    pub downsample: u32,
    /// (structure, heatmap file if counted, render file, mask file)
    pub rows: Vec<(String, Option<String>, String, String)>,
}

pub fn render(report: &Report, dir: &Path) -> Result<Rendered> {
    std::fs::create_dir_all(dir.join("charts"))
        .with_context(|| format!("creating {}", dir.display()))?;
    std::fs::create_dir_all(dir.join("images"))
        .with_context(|| format!("creating {}", dir.display()))?;
    let mut out = Rendered::default();
    let mut chart_files = Vec::new();
    for (file, caption, svg) in all_charts(report)? {
        let path = dir.join("charts").join(&file);
        write_atomic(&path, svg.as_bytes())?;
        out.charts.push(path);
        chart_files.push(ChartFile {
            file: format!("charts/{file}"),
            caption,
        });
    }
    let pictures = write_pictures(report, dir, &mut out.images)?;
    let page = html::page(report, &chart_files, &pictures);
    out.index = dir.join("index.html");
    write_atomic(&out.index, page.as_bytes())?;
    Ok(out)
}

/// Kept at this path for its callers; the one implementation is in [`crate::atomic`].
pub use crate::atomic::write_atomic;

/// A file-name-safe form of a name: lower-case letters and digits, everything else `-`
/// (`teapot.obj` → `teapot-obj`, so it never meets the generator `teapot`).
pub fn slug(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    let s = s.trim_matches('-').to_string();
    if s.is_empty() { "unnamed".into() } else { s }
}

/// File-name slugs for the report's scenes, made unique with a `-2`, `-3`… suffix when two
/// names map to the same slug (`a:b` and `a-b`).
pub(crate) fn scene_slugs(report: &Report) -> std::collections::HashMap<String, String> {
    let mut used = std::collections::HashSet::new();
    scene_names(report)
        .into_iter()
        .map(|name| {
            let base = slug(&name);
            let mut candidate = base.clone();
            let mut k = 2;
            while !used.insert(candidate.clone()) {
                candidate = format!("{base}-{k}");
                k += 1;
            }
            (name, candidate)
        })
        .collect()
}

pub(crate) fn scene_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = report.scenes.iter().map(|s| s.name.clone()).collect();
    for r in &report.results {
        if !names.contains(&r.scene) {
            names.push(r.scene.clone());
        }
    }
    names
}

pub(crate) fn structure_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in &report.results {
        if !names.contains(&r.structure) {
            names.push(r.structure.clone());
        }
    }
    names
}

pub(crate) fn workload_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for w in report.results.iter().flat_map(|r| &r.workloads) {
        if !names.contains(&w.workload) {
            names.push(w.workload.clone());
        }
    }
    names
}

fn entry<'a>(report: &'a Report, scene: &str, structure: &str) -> Option<&'a ResultEntry> {
    report
        .results
        .iter()
        .find(|r| r.scene == scene && r.structure == structure)
}

/// Groups = scenes, one series per structure, `value` of each result.
fn per_scene(
    report: &Report,
    value: impl Fn(&ResultEntry) -> Option<f64>,
) -> (Vec<String>, Vec<Series>) {
    let scenes = scene_names(report);
    let series = structure_names(report)
        .into_iter()
        .map(|st| Series {
            values: scenes
                .iter()
                .map(|sc| entry(report, sc, &st).and_then(&value))
                .collect(),
            name: st,
        })
        .collect();
    (scenes, series)
}

fn bars(
    report: &Report,
    title: String,
    y_desc: &str,
    log_y: bool,
    value: impl Fn(&ResultEntry) -> Option<f64>,
) -> Bars {
    let (groups, series) = per_scene(report, value);
    Bars {
        title,
        y_desc: y_desc.into(),
        groups,
        series,
        log_y,
    }
}

const W: u32 = 1100;
const H: u32 = 520;

/// Every chart the report has data for: (file name, caption, SVG).
pub fn all_charts(report: &Report) -> Result<Vec<(String, String, String)>> {
    let mut out = Vec::new();
    let reference = report.run.reference.clone();
    let mut push = |file: String, caption: String, chart: &Bars| -> Result<()> {
        if chart.has_data() {
            out.push((file, caption, charts::bars_svg(chart, W, H)?));
        }
        Ok(())
    };
    push(
        "build-ms.svg".into(),
        "Build time (median), log scale".into(),
        &bars(report, "Build time".into(), "ms (median)", true, |r| {
            Some(r.build.median_ms)
        }),
    )?;
    push(
        "ratio-build.svg".into(),
        format!("Build time relative to {reference} in the same run (lower is faster)"),
        &bars(
            report,
            format!("Build time / {reference}"),
            "ratio",
            true,
            |r| r.build_ratio_to_reference,
        ),
    )?;
    for wl in workload_names(report) {
        let find = |r: &ResultEntry| r.workloads.iter().find(|w| w.workload == wl).cloned();
        // Closest-point workloads count queries: same charts, their own unit.
        let unit = throughput_unit(&wl);
        push(
            format!("mrays-{}.svg", slug(&wl)),
            format!("Throughput on `{wl}` (median {unit}), log scale"),
            &bars(
                report,
                format!("{wl}: {unit}"),
                &format!("{unit} (median)"),
                true,
                |r| find(r).map(|w| w.mrays_per_s.median),
            ),
        )?;
        push(
            format!("ratio-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` relative to {reference} in the same run (higher is faster)"
            ),
            &bars(
                report,
                format!("{wl}: {unit} / {reference}"),
                "ratio",
                true,
                |r| find(r).and_then(|w| w.speedup_vs_reference),
            ),
        )?;
    }
    push(
        "memory-per-triangle.svg".into(),
        "Memory per triangle (bytes the structure holds / traced triangles)".into(),
        &bars(report, "Memory per triangle".into(), "bytes", true, |r| {
            (r.triangles.traced > 0).then(|| r.memory_bytes as f64 / r.triangles.traced as f64)
        }),
    )?;

    for wl in workload_names(report) {
        let per_ray = |f: fn(&crate::report::CountersPerRay) -> f64| {
            let wl = wl.clone();
            move |r: &ResultEntry| {
                r.workloads
                    .iter()
                    .find(|w| w.workload == wl)
                    .and_then(|w| w.counters_per_ray.as_ref())
                    .map(f)
            }
        };
        let panels = [
            bars(
                report,
                format!("{wl}: nodes per ray (interior + leaves)"),
                "per ray",
                true,
                per_ray(|c| c.nodes + c.leaves),
            ),
            bars(
                report,
                format!("{wl}: triangle tests per ray"),
                "per ray",
                true,
                per_ray(|c| c.prim_tests),
            ),
            bars(
                report,
                format!("{wl}: cells stepped per ray"),
                "per ray",
                true,
                per_ray(|c| c.cells),
            ),
        ];
        let panels: Vec<Bars> = panels.into_iter().filter(Bars::has_data).collect();
        if !panels.is_empty() {
            out.push((
                format!("counters-{}.svg", slug(&wl)),
                format!("Work per ray on `{wl}` (exact counters from the counted pass)"),
                charts::stacked_bars_svg(&panels, W, 420)?,
            ));
        }
    }
    if let Some(svg) = scaling_chart(report)? {
        out.push((
            "scaling.svg".into(),
            "Scaling with scene size, log–log, with reference slopes anchored at the smallest scene".into(),
            svg,
        ));
    }
    let slugs = scene_slugs(report);
    for scene in scene_names(report) {
        if let Some(svg) = break_even_chart(report, &scene)? {
            out.push((
                format!("break-even-{}.svg", slugs[&scene]),
                format!("{scene}: total time to build once and trace K rays"),
                svg,
            ));
        }
    }
    let validation = validation_chart(report);
    if validation.has_data() {
        out.push((
            "validation.svg".into(),
            format!("Validation classes per structure against {reference}, all scenes and workloads (log scale)"),
            charts::bars_svg(&validation, W, H)?,
        ));
    }
    Ok(out)
}

/// The workload whose speed stands for a structure in scaling and break-even charts.
fn timing_workload(report: &Report) -> Option<String> {
    let names = workload_names(report);
    names
        .iter()
        .find(|w| *w == "random")
        .or(names.first())
        .cloned()
}

/// A named reference curve `f(N)`.
type Curve = (&'static str, fn(f64) -> f64);

/// How many rays of a validation class.
type ClassCount = fn(&raybench_accel::classify::VerdictCounts) -> u64;

/// The generator (or file) a scene name comes from: `teapot:triangles=4000` → `teapot`.
fn family(scene: &str) -> &str {
    scene.split(':').next().unwrap_or(scene)
}

/// The scene family with the most distinct sizes, if it has at least three: scaling is only
/// meaningful along one kind of geometry (the `sweep-*` suites), not across unrelated scenes.
fn scaling_family(report: &Report) -> Option<(String, Vec<u64>)> {
    let mut best: Option<(String, Vec<u64>)> = None;
    for name in scene_names(report) {
        let fam = family(&name);
        let mut sizes: Vec<u64> = report
            .results
            .iter()
            .filter(|r| family(&r.scene) == fam)
            .map(|r| r.triangles.traced)
            .collect();
        sizes.sort_unstable();
        sizes.dedup();
        if sizes.len() >= 3 && best.as_ref().is_none_or(|b| sizes.len() > b.1.len()) {
            best = Some((fam.to_string(), sizes));
        }
    }
    best
}

fn scaling_chart(report: &Report) -> Result<Option<String>> {
    let Some((fam, sizes)) = scaling_family(report) else {
        return Ok(None);
    };
    let wl = timing_workload(report);
    let mut build = Vec::new();
    let mut trace = Vec::new();
    for st in structure_names(report) {
        let mut b = Vec::new();
        let mut t = Vec::new();
        for r in report
            .results
            .iter()
            .filter(|r| r.structure == st && family(&r.scene) == fam)
        {
            let n = r.triangles.traced as f64;
            b.push((n, r.build.median_ms));
            if let Some(w) = r
                .workloads
                .iter()
                .find(|w| Some(&w.workload) == wl.as_ref())
                && w.mrays_per_s.median > 0.0
            {
                t.push((n, 1e3 / w.mrays_per_s.median));
            }
        }
        b.sort_by(|x, y| x.0.total_cmp(&y.0));
        t.sort_by(|x, y| x.0.total_cmp(&y.0));
        build.push((st.clone(), b));
        trace.push((st, t));
    }
    let n0 = sizes[0] as f64;
    let n1 = *sizes.last().unwrap() as f64;
    let reference = |series: &[(String, Vec<(f64, f64)>)], curves: &[Curve]| {
        // Anchored at the geometric mean of every series' value at the smallest scene.
        let firsts: Vec<f64> = series
            .iter()
            .filter_map(|(_, p)| p.first().filter(|q| q.0 == n0).map(|q| q.1))
            .filter(|v| *v > 0.0)
            .collect();
        if firsts.is_empty() {
            return Vec::new();
        }
        let y0 = (firsts.iter().map(|v| v.ln()).sum::<f64>() / firsts.len() as f64).exp();
        curves
            .iter()
            .map(|(name, f)| {
                let pts = (0..=20)
                    .map(|i| {
                        let n = n0 * (n1 / n0).powf(i as f64 / 20.0);
                        (n, y0 * f(n) / f(n0))
                    })
                    .collect();
                (name.to_string(), pts)
            })
            .collect()
    };
    let build_refs = reference(&build, &[("∝ N", |n| n), ("∝ N log N", |n| n * n.ln())]);
    let trace_refs = reference(
        &trace,
        &[
            ("∝ log N", |n| n.ln()),
            ("∝ N^(1/3)", |n| n.cbrt()),
            ("∝ N", |n| n),
        ],
    );
    let panels = [
        LogLog {
            title: format!("{fam}: build time against triangles"),
            x_desc: "triangles".into(),
            y_desc: "build ms".into(),
            series: build,
            references: build_refs,
        },
        LogLog {
            title: format!(
                "Time per ray against triangles ({})",
                wl.unwrap_or_default()
            ),
            x_desc: "triangles".into(),
            y_desc: "ns per ray".into(),
            series: trace,
            references: trace_refs,
        },
    ];
    if !panels[0].has_data() {
        return Ok(None);
    }
    Ok(Some(charts::loglog_svg(&panels, W, H)?))
}

fn break_even_chart(report: &Report, scene: &str) -> Result<Option<String>> {
    let Some(wl) = timing_workload(report) else {
        return Ok(None);
    };
    let ks: Vec<f64> = (0..=24)
        .map(|i| 10f64.powf(3.0 + 6.0 * i as f64 / 24.0))
        .collect();
    let series: Vec<(String, Vec<(f64, f64)>)> = report
        .results
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| {
            let w = r.workloads.iter().find(|w| w.workload == wl)?;
            let rate = w.mrays_per_s.median * 1e6;
            (rate > 0.0).then(|| {
                let build_s = r.build.median_ms / 1e3;
                (
                    r.structure.clone(),
                    ks.iter().map(|&k| (k, build_s + k / rate)).collect(),
                )
            })
        })
        .collect();
    let chart = LogLog {
        title: format!(
            "{}: build + trace K rays ({wl})",
            scene.trim_end_matches(".obj")
        ),
        x_desc: "rays traced (K)".into(),
        y_desc: "total seconds".into(),
        series,
        references: Vec::new(),
    };
    if !chart.has_data() {
        return Ok(None);
    }
    Ok(Some(charts::loglog_svg(&[chart], W, H)?))
}

fn validation_chart(report: &Report) -> Bars {
    let structures = structure_names(report);
    let classes: [(&str, ClassCount); 5] = [
        ("agree (both miss, exact, within tolerance)", |c| {
            c.both_miss + c.exact + c.within_tolerance
        }),
        ("tie", |c| c.tie),
        ("boundary", |c| c.boundary),
        ("edge ambiguous", |c| c.edge_ambiguous),
        ("mismatch", |c| c.mismatch),
    ];
    let series = classes
        .iter()
        .map(|(name, f)| Series {
            name: name.to_string(),
            values: structures
                .iter()
                .map(|st| {
                    let n: u64 = report
                        .results
                        .iter()
                        .filter(|r| &r.structure == st)
                        .flat_map(|r| &r.workloads)
                        .map(|w| f(&w.validation.counts))
                        .sum();
                    (n > 0).then_some(n as f64)
                })
                .collect(),
        })
        .collect();
    Bars {
        title: "Rays per validation class".into(),
        y_desc: "rays".into(),
        groups: structures,
        series,
        log_y: true,
    }
}

fn write_pictures(
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
            rows.push((r.structure.clone(), heat, render, mask));
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

#[cfg(test)]
mod tests {
    use super::slug;

    #[test]
    fn slugs_keep_files_and_generators_apart() {
        assert_eq!(slug("teapot.obj"), "teapot-obj");
        assert_ne!(slug("teapot.obj"), slug("teapot"));
        assert_eq!(slug("sphere:triangles=2000"), "sphere-triangles-2000");
        assert_eq!(slug("::"), "unnamed");
    }
}
