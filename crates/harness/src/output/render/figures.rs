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

/// A drawn chart and the scene it is about, if one (its page shows it).
pub(super) struct Drawn {
    pub file: String,
    pub caption: String,
    pub svg: String,
    pub scene: Option<String>,
}

impl Drawn {
    fn across((file, caption, svg): Figure) -> Drawn {
        Drawn {
            file,
            caption,
            svg,
            scene: None,
        }
    }
}

/// A value of one result, with the lowest and highest of its timed runs when it has them.
type Measure<'a> = &'a dyn Fn(&ResultEntry) -> Option<(f64, Option<(f64, f64)>)>;

/// The spread of timed runs, when there was more than one run and a real spread.
fn runs(runs: usize, min: f64, max: f64) -> Option<(f64, f64)> {
    (runs > 1 && min < max).then_some((min, max))
}

/// Groups = scenes, one series per structure, `value` of each result.
fn bars(report: &Report, palette: &Palette, title: String, y_desc: &str, value: Measure) -> Bars {
    let scenes = scene_names(report);
    let series = structure_names(report)
        .into_iter()
        .map(|st| {
            let measured: Vec<_> = scenes
                .iter()
                .map(|sc| entry(report, sc, &st).and_then(value))
                .collect();
            Series {
                values: measured.iter().map(|m| m.map(|m| m.0)).collect(),
                ranges: measured.iter().map(|m| m.and_then(|m| m.1)).collect(),
                color: palette.color(&st),
                name: st,
            }
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
pub(super) fn all_charts(report: &Report, sweep: Option<&Sweep>) -> Result<Vec<Drawn>> {
    let palette = Palette::for_report(report);
    let across = match sweep {
        Some(s) => sweep_charts(report, s, &palette)?,
        None => bar_charts(report, &palette)?,
    };
    let mut out: Vec<Drawn> = across.into_iter().map(Drawn::across).collect();
    if let Some(sizes) = Sizes::of(report, sweep)
        && let Some(svg) = scaling_chart(report, &sizes, &palette)?
    {
        out.push(Drawn::across((
            "scaling.svg".into(),
            format!(
                "Scaling with scene size ({}), log–log: each structure's exponent b fitted by least \
                 squares with a 95 % interval, beside theory curves anchored at the smallest scene",
                sizes.family
            ),
            svg,
        )));
    }
    let slugs = scene_slugs(report);
    for scene in scene_names(report) {
        if let Some(svg) = break_even_chart(report, &scene, sweep, &palette)? {
            out.push(Drawn {
                file: format!("break-even-{}.svg", slugs[&scene]),
                caption: format!(
                    "{scene}: total time to build once and trace K rays; the ring marks where \
                     the fastest tracer starts to win with its build counted"
                ),
                svg,
                scene: Some(scene),
            });
        }
    }
    let reference = &report.run.reference;
    let agreement = agreement_panels(report);
    if agreement.iter().any(Bars::has_data) {
        out.push(Drawn::across((
            "agreement.svg".into(),
            format!(
                "Agreement with {reference} per validation class, all scenes and workloads: one \
                 panel per class on its own linear scale, in queries per million each structure \
                 answered (structures ran on different numbers of scenes)"
            ),
            charts::stacked_bars_svg(&agreement, W, 270)?,
        )));
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
    let bars =
        |title: String, y_desc: &str, value: Measure| bars(report, palette, title, y_desc, value);
    let plain = |v: Option<f64>| v.map(|v| (v, None));
    push(
        "build-ms.svg".into(),
        "Build time (median; error bars: fastest to slowest build), log scale".into(),
        &bars("Build time".into(), "ms (median)", &|r| {
            let b = &r.build;
            Some((b.median_ms, runs(b.runs, b.min_ms, b.max_ms)))
        }),
    )?;
    push(
        "ratio-build.svg".into(),
        format!(
            "Build time relative to {reference} in the same run (lower is faster; error bars: \
             the ratio's confidence interval over the rounds)"
        ),
        &bars(format!("Build time / {reference}"), "ratio", &|r| {
            let band = r.build_ratio_interval.map(|i| (i.lo, i.hi));
            r.build_ratio_to_reference.map(|x| (x, band))
        }),
    )?;
    for wl in workload_names(report) {
        let find = |r: &ResultEntry| r.workloads.iter().find(|w| w.workload == wl).cloned();
        // Closest-point workloads count queries: same charts, their own unit.
        let unit = throughput_unit(&wl);
        push(
            format!("mrays-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` (median {unit}; error bars: slowest to fastest pass), \
                 log scale"
            ),
            &bars(format!("{wl}: {unit}"), &format!("{unit} (median)"), &|r| {
                find(r).map(|w| {
                    let t = &w.mqueries_per_s;
                    (t.median, runs(t.runs, t.min, t.max))
                })
            }),
        )?;
        push(
            format!("ratio-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` relative to {reference} in the same run (higher is faster; \
                 error bars: the ratio's confidence interval over the rounds)"
            ),
            &bars(format!("{wl}: {unit} / {reference}"), "ratio", &|r| {
                let w = find(r)?;
                let band = w.speedup_interval.map(|i| (i.lo, i.hi));
                w.speedup_vs_reference.map(|x| (x, band))
            }),
        )?;
    }
    push(
        "memory-per-triangle.svg".into(),
        "Memory per triangle (bytes the structure holds / traced triangles)".into(),
        &bars("Memory per triangle".into(), "bytes", &|r| {
            plain(
                (r.triangles.traced > 0).then(|| r.memory_bytes as f64 / r.triangles.traced as f64),
            )
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
                    .map(|c| (f(c), None))
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

/// The validation classes, each with a colour that reads as a verdict (greens agree, red is a
/// mismatch).
const CLASSES: [(&str, RGBColor, ClassCount); 7] = [
    ("both miss", RGBColor(116, 196, 118), |c| c.both_miss),
    ("exact", RGBColor(44, 160, 44), |c| c.exact),
    ("within tolerance", RGBColor(0, 109, 44), |c| {
        c.within_tolerance
    }),
    ("tie", RGBColor(31, 119, 180), |c| c.tie),
    ("boundary", RGBColor(148, 103, 189), |c| c.boundary),
    ("edge ambiguous", RGBColor(255, 127, 14), |c| {
        c.edge_ambiguous
    }),
    ("mismatch", RGBColor(214, 39, 40), |c| c.mismatch),
];

/// One panel per validation class, structures on x, each on its own linear scale: a log
/// scale over all classes together let 99.9 % of agreeing rays hide every other class, and
/// a share per structure (a stacked bar) does the same. Values are per million queries, as
/// structures skipped on large scenes answered fewer queries than the others. A class no
/// query fell in keeps its panel, empty, with "no query" in its title.
fn agreement_panels(report: &Report) -> Vec<Bars> {
    let structures = structure_names(report);
    let totals: Vec<(raybench_accel::classify::VerdictCounts, u64)> = structures
        .iter()
        .map(|st| {
            let mut c = raybench_accel::classify::VerdictCounts::default();
            for w in report
                .results
                .iter()
                .filter(|r| &r.structure == st)
                .flat_map(|r| &r.workloads)
            {
                c += w.agreement.counts;
            }
            let total = c.total();
            (c, total)
        })
        .collect();
    CLASSES
        .iter()
        .map(|(name, color, f)| {
            let all: u64 = totals.iter().map(|(c, _)| f(c)).sum();
            let values = totals
                .iter()
                .map(|(c, total)| {
                    let n = f(c);
                    (n > 0 && *total > 0).then(|| n as f64 * 1e6 / *total as f64)
                })
                .collect();
            Bars {
                title: if all == 0 {
                    format!("{name}: no query in any structure")
                } else {
                    format!("{name}: {all} queries in all")
                },
                y_desc: "per million queries".into(),
                group_titles: structures.clone(),
                groups: structures.clone(),
                series: vec![Series {
                    name: name.to_string(),
                    color: *color,
                    values,
                    ranges: Vec::new(),
                }],
                log_y: false,
            }
        })
        .collect()
}
