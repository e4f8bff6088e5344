//! Every chart a report has data for: build time, throughput and ratios per workload, memory
//! per triangle, counters per query (bars per scene, or lines against the swept parameter for a
//! sweep, see [`super::sweep_charts`]), scaling and break-even (see [`super::scaling`]), and
//! the validation classes per structure.

use super::break_even::break_even_chart;
use super::charts::{self, Bars, Series};
use super::names::{
    entry, scene_label, scene_names, scene_slugs, slug, structure_names, workload_names,
};
use super::palette::Palette;
use super::scaling::{Sizes, scaling_chart};
use super::sweep::Sweep;
use super::sweep_charts::sweep_charts;
use super::{H, W};
use crate::report::run::{Report, ResultEntry, throughput_unit};
use anyhow::Result;
use plotters::style::RGBColor;

/// A drawn chart: (file name, caption, SVG).
pub(super) type Figure = (String, String, String);

/// Groups = scenes, one series per structure, `value` of each result.
fn bars(
    report: &Report,
    palette: &Palette,
    title: String,
    y_desc: &str,
    value: impl Fn(&ResultEntry) -> Option<f64>,
) -> Bars {
    let scenes = scene_names(report);
    let series = structure_names(report)
        .into_iter()
        .map(|st| Series {
            values: scenes
                .iter()
                .map(|sc| entry(report, sc, &st).and_then(&value))
                .collect(),
            color: palette.color(&st),
            name: st,
        })
        .collect();
    Bars {
        title,
        y_desc: y_desc.into(),
        groups: scenes.iter().map(|s| scene_label(None, s)).collect(),
        group_titles: scenes,
        series,
        log_y: true,
    }
}

/// Every chart the report has data for.
pub(super) fn all_charts(report: &Report, sweep: Option<&Sweep>) -> Result<Vec<Figure>> {
    let palette = Palette::for_report(report);
    let mut out = match sweep {
        Some(s) => sweep_charts(report, s, &palette)?,
        None => bar_charts(report, &palette)?,
    };
    if let Some(sizes) = Sizes::of(report, sweep)
        && let Some(svg) = scaling_chart(report, &sizes, &palette)?
    {
        out.push((
            "scaling.svg".into(),
            format!(
                "Scaling with scene size ({}), log–log: each structure's exponent b fitted by least \
                 squares with a 95 % interval, beside theory curves anchored at the smallest scene",
                sizes.family
            ),
            svg,
        ));
    }
    let slugs = scene_slugs(report);
    for scene in scene_names(report) {
        if let Some(svg) = break_even_chart(report, &scene, sweep, &palette)? {
            out.push((
                format!("break-even-{}.svg", slugs[&scene]),
                format!("{scene}: total time to build once and trace K rays"),
                svg,
            ));
        }
    }
    let reference = &report.run.reference;
    let agreement = agreement_chart(report);
    if agreement.has_data() {
        out.push((
            "agreement.svg".into(),
            format!("Agreement classes per structure against {reference}, all scenes and workloads (log scale)"),
            charts::bars_svg(&agreement, W, H)?,
        ));
    }
    Ok(out)
}

/// The per-scene charts as bars, for a report that sweeps no parameter.
fn bar_charts(report: &Report, palette: &Palette) -> Result<Vec<Figure>> {
    let mut out = Vec::new();
    let reference = report.run.reference.clone();
    let mut push = |file: String, caption: String, chart: &Bars| -> Result<()> {
        if chart.has_data() {
            out.push((file, caption, charts::bars_svg(chart, W, H)?));
        }
        Ok(())
    };
    let bars = |title: String, y_desc: &str, value: &dyn Fn(&ResultEntry) -> Option<f64>| {
        bars(report, palette, title, y_desc, value)
    };
    push(
        "build-ms.svg".into(),
        "Build time (median), log scale".into(),
        &bars("Build time".into(), "ms (median)", &|r| {
            Some(r.build.median_ms)
        }),
    )?;
    push(
        "ratio-build.svg".into(),
        format!("Build time relative to {reference} in the same run (lower is faster)"),
        &bars(format!("Build time / {reference}"), "ratio", &|r| {
            r.build_ratio_to_reference
        }),
    )?;
    for wl in workload_names(report) {
        let find = |r: &ResultEntry| r.workloads.iter().find(|w| w.workload == wl).cloned();
        // Closest-point workloads count queries: same charts, their own unit.
        let unit = throughput_unit(&wl);
        push(
            format!("mrays-{}.svg", slug(&wl)),
            format!("Throughput on `{wl}` (median {unit}), log scale"),
            &bars(format!("{wl}: {unit}"), &format!("{unit} (median)"), &|r| {
                find(r).map(|w| w.mqueries_per_s.median)
            }),
        )?;
        push(
            format!("ratio-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` relative to {reference} in the same run (higher is faster)"
            ),
            &bars(format!("{wl}: {unit} / {reference}"), "ratio", &|r| {
                find(r).and_then(|w| w.speedup_vs_reference)
            }),
        )?;
    }
    push(
        "memory-per-triangle.svg".into(),
        "Memory per triangle (bytes the structure holds / traced triangles)".into(),
        &bars("Memory per triangle".into(), "bytes", &|r| {
            (r.triangles.traced > 0).then(|| r.memory_bytes as f64 / r.triangles.traced as f64)
        }),
    )?;

    for wl in workload_names(report) {
        let per_ray = |f: fn(&crate::report::run::CountersPerQuery) -> f64| {
            let wl = wl.clone();
            move |r: &ResultEntry| {
                r.workloads
                    .iter()
                    .find(|w| w.workload == wl)
                    .and_then(|w| w.counters_per_query.as_ref())
                    .map(f)
            }
        };
        let panels = [
            bars(
                format!("{wl}: nodes per ray (interior + leaves)"),
                "per ray",
                &per_ray(|c| c.nodes + c.leaves),
            ),
            bars(
                format!("{wl}: triangle tests per ray"),
                "per ray",
                &per_ray(|c| c.prim_tests),
            ),
            bars(
                format!("{wl}: cells stepped per ray"),
                "per ray",
                &per_ray(|c| c.cells),
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
    Ok(out)
}

/// How many rays of an agreement class.
type ClassCount = fn(&raybench_accel::classify::VerdictCounts) -> u64;

/// Rays per agreement class and structure: groups are structures, series the classes, in
/// colours that read as verdicts (green agrees, red is a mismatch).
fn agreement_chart(report: &Report) -> Bars {
    let structures = structure_names(report);
    let classes: [(&str, RGBColor, ClassCount); 5] = [
        (
            "agree (both miss, exact, within tolerance)",
            RGBColor(44, 160, 44),
            |c| c.both_miss + c.exact + c.within_tolerance,
        ),
        ("tie", RGBColor(31, 119, 180), |c| c.tie),
        ("boundary", RGBColor(148, 103, 189), |c| c.boundary),
        ("edge ambiguous", RGBColor(255, 127, 14), |c| {
            c.edge_ambiguous
        }),
        ("mismatch", RGBColor(214, 39, 40), |c| c.mismatch),
    ];
    let series = classes
        .iter()
        .map(|(name, color, f)| Series {
            name: name.to_string(),
            color: *color,
            values: structures
                .iter()
                .map(|st| {
                    let n: u64 = report
                        .results
                        .iter()
                        .filter(|r| &r.structure == st)
                        .flat_map(|r| &r.workloads)
                        .map(|w| f(&w.agreement.counts))
                        .sum();
                    (n > 0).then_some(n as f64)
                })
                .collect(),
        })
        .collect();
    Bars {
        title: "Rays per agreement class".into(),
        y_desc: "rays".into(),
        group_titles: structures.clone(),
        groups: structures,
        series,
        log_y: true,
    }
}
