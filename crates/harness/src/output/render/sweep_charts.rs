//! The per-scene charts of a sweep, drawn as lines against the swept parameter instead of bars
//! per scene: one line per structure, a marker at each measured scene, and bars from the
//! fastest to the slowest run where the report keeps them. Same files as the bar charts.

use super::figures::Figure;
use super::lines::{Line, LineChart, Point, Tick, lines_svg};
use super::names::{slug, structure_names, workload_names};
use super::palette::Palette;
use super::sweep::Sweep;
use super::ticks::tick_label;
use super::{H, W};
use crate::report::run::{CountersPerQuery, Report, ResultEntry, WorkloadResult, throughput_unit};
use anyhow::Result;

/// A value of one result, with the spread of its timed runs when there is one.
type Measure<'a> = &'a dyn Fn(&ResultEntry) -> Option<(f64, Option<(f64, f64)>)>;

/// The x ticks of a sweep: one per scene, the full scene name on hover.
pub(super) fn sweep_ticks(sweep: &Sweep) -> Vec<Tick> {
    sweep
        .points
        .iter()
        .map(|p| Tick {
            x: p.x,
            label: tick_label(p.x),
            title: Some(format!("{} ({} triangles)", p.scene, p.triangles)),
        })
        .collect()
}

/// One line per structure of `measure` against the swept parameter.
fn chart(
    report: &Report,
    sweep: &Sweep,
    palette: &Palette,
    (title, y_desc): (String, &str),
    measure: Measure,
) -> LineChart {
    let lines = structure_names(report)
        .into_iter()
        .map(|st| {
            let points = sweep
                .points
                .iter()
                .filter_map(|p| {
                    let r = report
                        .results
                        .iter()
                        .find(|r| r.scene == p.scene && r.structure == st)?;
                    let (y, range) = measure(r)?;
                    Some(Point {
                        x: p.x,
                        y,
                        range,
                        title: format!("{st}, {}: {} {y_desc}", p.scene, tick_label(y)),
                    })
                })
                .collect();
            Line {
                label: st.clone(),
                color: palette.color(&st),
                marker: palette.marker(&st),
                points,
            }
        })
        .filter(|l| !l.points.is_empty())
        .collect();
    LineChart {
        title,
        x_desc: sweep.x_desc(),
        y_desc: y_desc.to_string(),
        log_x: sweep.log_x(),
        ticks: sweep_ticks(sweep),
        lines,
        references: Vec::new(),
        marks: Vec::new(),
    }
}

fn workload<'a>(r: &'a ResultEntry, wl: &str) -> Option<&'a WorkloadResult> {
    r.workloads.iter().find(|w| w.workload == wl)
}

/// The spread of timed runs, when the report has more than one run and a real spread.
fn spread(runs: usize, min: f64, max: f64) -> Option<(f64, f64)> {
    (runs > 1 && min < max).then_some((min, max))
}

/// Every per-scene chart of a sweep report.
pub(super) fn sweep_charts(
    report: &Report,
    sweep: &Sweep,
    palette: &Palette,
) -> Result<Vec<Figure>> {
    let reference = report.run.reference.clone();
    let key = &sweep.key;
    let mut out = Vec::new();
    let mut push = |file: String, caption: String, panels: Vec<LineChart>| -> Result<()> {
        let panels: Vec<LineChart> = panels.into_iter().filter(LineChart::has_data).collect();
        if !panels.is_empty() {
            let height = if panels.len() > 1 { 420 } else { H };
            out.push((file, caption, lines_svg(&panels, W, height)?));
        }
        Ok(())
    };
    let line = |title: String, y_desc: &str, measure: Measure| {
        chart(report, sweep, palette, (title, y_desc), measure)
    };
    push(
        "build-ms.svg".into(),
        format!("Build time (median; bars: fastest to slowest build) against {key}"),
        vec![line(
            format!("Build time against {key}"),
            "ms (median)",
            &|r| {
                let b = &r.build;
                Some((b.median_ms, spread(b.runs, b.min_ms, b.max_ms)))
            },
        )],
    )?;
    push(
        "ratio-build.svg".into(),
        format!(
            "Build time relative to {reference} in the same run against {key} (lower is faster)"
        ),
        vec![line(
            format!("Build time / {reference} against {key}"),
            "ratio",
            &|r| r.build_ratio_to_reference.map(|v| (v, None)),
        )],
    )?;
    for wl in workload_names(report) {
        let unit = throughput_unit(&wl);
        push(
            format!("mrays-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` (median {unit}; bars: slowest to fastest pass) against {key}"
            ),
            vec![line(
                format!("{wl}: {unit} against {key}"),
                &format!("{unit} (median)"),
                &|r| {
                    let t = &workload(r, &wl)?.mqueries_per_s;
                    Some((t.median, spread(t.runs, t.min, t.max)))
                },
            )],
        )?;
        push(
            format!("ratio-{}.svg", slug(&wl)),
            format!(
                "Throughput on `{wl}` relative to {reference} in the same run against {key} (higher is faster)"
            ),
            vec![line(
                format!("{wl}: {unit} / {reference} against {key}"),
                "ratio",
                &|r| workload(r, &wl)?.speedup_vs_reference.map(|v| (v, None)),
            )],
        )?;
    }
    push(
        "memory-per-triangle.svg".into(),
        format!("Memory per triangle (bytes the structure holds / traced triangles) against {key}"),
        vec![line(
            format!("Memory per triangle against {key}"),
            "bytes",
            &|r| {
                (r.triangles.traced > 0)
                    .then(|| (r.memory_bytes as f64 / r.triangles.traced as f64, None))
            },
        )],
    )?;
    for wl in workload_names(report) {
        let per_ray = |f: fn(&CountersPerQuery) -> f64| {
            let wl = wl.clone();
            move |r: &ResultEntry| {
                let c = workload(r, &wl)?.counters_per_query.as_ref()?;
                Some((f(c), None))
            }
        };
        push(
            format!("counters-{}.svg", slug(&wl)),
            format!("Work per ray on `{wl}` against {key} (exact counters from the counted pass)"),
            vec![
                line(
                    format!("{wl}: nodes per ray (interior + leaves) against {key}"),
                    "per ray",
                    &per_ray(|c| c.nodes + c.leaves),
                ),
                line(
                    format!("{wl}: triangle tests per ray against {key}"),
                    "per ray",
                    &per_ray(|c| c.prim_tests),
                ),
                line(
                    format!("{wl}: cells stepped per ray against {key}"),
                    "per ray",
                    &per_ray(|c| c.cells),
                ),
            ],
        )?;
    }
    Ok(out)
}
