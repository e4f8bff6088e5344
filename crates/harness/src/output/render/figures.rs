//! Every chart a report has data for: build time, throughput and ratios per workload, memory
//! per triangle, counters per query, scaling and break-even (see [`super::scaling`]), and the
//! validation classes per structure.

use super::charts::{self, Bars, Series};
use super::names::{entry, scene_names, scene_slugs, slug, structure_names, workload_names};
use super::scaling::{break_even_chart, scaling_chart};
use super::{H, W};
use crate::report::run::{Report, ResultEntry, throughput_unit};
use anyhow::Result;

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

/// Every chart the report has data for: (file name, caption, SVG).
pub(super) fn all_charts(report: &Report) -> Result<Vec<(String, String, String)>> {
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
                |r| find(r).map(|w| w.mqueries_per_s.median),
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

/// How many rays of an agreement class.
type ClassCount = fn(&raybench_accel::classify::VerdictCounts) -> u64;

fn agreement_chart(report: &Report) -> Bars {
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
        groups: structures,
        series,
        log_y: true,
    }
}
