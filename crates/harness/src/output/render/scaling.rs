//! Scaling with scene size: build time, time per ray and triangle tests per ray against the
//! triangle count N on log–log axes, each structure with its fitted exponent b (`∝ N^b`, see
//! [`super::fit`]) beside the theory curves. Drawn for a sweep whose scenes grow, or else for
//! the scene family (one generator) that comes in the most sizes, three or more.

use super::fit::{PowerFit, fit_power};
use super::lines::{Line, LineChart, Point, Reference, Tick, lines_svg};
use super::names::{scene_names, structure_names, workload_names};
use super::palette::Palette;
use super::sweep::Sweep;
use super::ticks::tick_label;
use super::{H, W};
use crate::report::run::{Report, ResultEntry};
use anyhow::Result;

/// The workload whose speed stands for a structure in scaling and break-even charts.
pub(super) fn timing_workload(report: &Report) -> Option<String> {
    let names = workload_names(report);
    names
        .iter()
        .find(|w| *w == "random")
        .or(names.first())
        .cloned()
}

/// The scenes a scaling chart is drawn over.
#[derive(Clone, Debug)]
pub(crate) struct Sizes {
    /// The generator (or file) the scenes come from.
    pub family: String,
    /// (scene, triangles traced), smallest first.
    pub scenes: Vec<(String, f64)>,
}

/// The generator (or file) a scene name comes from: `teapot:triangles=4000` → `teapot`.
fn family(scene: &str) -> &str {
    scene.split(':').next().unwrap_or(scene)
}

impl Sizes {
    /// A growing sweep's scenes, or else the scene family with the most distinct sizes if it
    /// has three: scaling is only meaningful along one kind of geometry, not across unrelated
    /// scenes.
    pub(crate) fn of(report: &Report, sweep: Option<&Sweep>) -> Option<Sizes> {
        if let Some(s) = sweep.filter(|s| s.is_size_sweep()) {
            return Some(Sizes {
                family: s.generator.clone(),
                scenes: s
                    .points
                    .iter()
                    .map(|p| (p.scene.clone(), p.triangles as f64))
                    .collect(),
            });
        }
        let mut best: Option<Sizes> = None;
        for name in scene_names(report) {
            let fam = family(&name);
            let mut scenes: Vec<(String, f64)> = Vec::new();
            for r in report.results.iter().filter(|r| family(&r.scene) == fam) {
                let n = r.triangles.traced as f64;
                if !scenes.iter().any(|(_, m)| *m == n) {
                    scenes.push((r.scene.clone(), n));
                }
            }
            scenes.sort_by(|a, b| a.1.total_cmp(&b.1));
            if scenes.len() >= 3 && best.as_ref().is_none_or(|b| scenes.len() > b.scenes.len()) {
                best = Some(Sizes {
                    family: fam.to_string(),
                    scenes,
                });
            }
        }
        best
    }
}

/// What one structure's measurement is at one size: a value and the spread of its runs.
type Measure = fn(&ResultEntry, &str) -> Option<(f64, Option<(f64, f64)>)>;

fn build_ms(r: &ResultEntry, _: &str) -> Option<(f64, Option<(f64, f64)>)> {
    let b = &r.build;
    Some((
        b.median_ms,
        (b.runs > 1 && b.min_ms < b.max_ms).then_some((b.min_ms, b.max_ms)),
    ))
}

/// Nanoseconds per query from the median throughput; the spread from the fastest and slowest
/// passes.
fn ns_per_ray(r: &ResultEntry, wl: &str) -> Option<(f64, Option<(f64, f64)>)> {
    let t = &r
        .workloads
        .iter()
        .find(|w| w.workload == wl)?
        .mqueries_per_s;
    (t.median > 0.0).then(|| {
        let spread =
            (t.runs > 1 && t.min > 0.0 && t.min < t.max).then(|| (1e3 / t.max, 1e3 / t.min));
        (1e3 / t.median, spread)
    })
}

fn tests_per_ray(r: &ResultEntry, wl: &str) -> Option<(f64, Option<(f64, f64)>)> {
    let c = r
        .workloads
        .iter()
        .find(|w| w.workload == wl)?
        .counters_per_query?;
    Some((c.prim_tests, None))
}

/// Each structure's points of `measure` over the sizes.
fn points(
    report: &Report,
    sizes: &Sizes,
    st: &str,
    wl: &str,
    measure: Measure,
    unit: &str,
) -> Vec<Point> {
    sizes
        .scenes
        .iter()
        .filter_map(|(scene, n)| {
            let r = report
                .results
                .iter()
                .find(|r| &r.scene == scene && r.structure == st)?;
            let (y, range) = measure(r, wl)?;
            Some(Point {
                x: *n,
                y,
                range,
                title: format!("{st}, {scene} ({n} triangles): {} {unit}", tick_label(y)),
            })
        })
        .collect()
}

fn fit(points: &[Point]) -> Option<PowerFit> {
    fit_power(&points.iter().map(|p| (p.x, p.y)).collect::<Vec<_>>())
}

/// Fitted exponents of every structure, for the page's table.
#[derive(Clone, Debug)]
pub(crate) struct Exponents {
    pub sizes: Sizes,
    pub workloads: Vec<String>,
    pub rows: Vec<ExponentRow>,
}

#[derive(Clone, Debug)]
pub(crate) struct ExponentRow {
    pub structure: String,
    pub build: Option<PowerFit>,
    /// Per workload of [`Exponents::workloads`]: time per query, and triangle tests per query.
    pub per_workload: Vec<(Option<PowerFit>, Option<PowerFit>)>,
}

impl Exponents {
    pub(crate) fn of(report: &Report, sizes: &Sizes) -> Exponents {
        let workloads = workload_names(report);
        let rows = structure_names(report)
            .into_iter()
            .map(|st| ExponentRow {
                build: fit(&points(report, sizes, &st, "", build_ms, "")),
                per_workload: workloads
                    .iter()
                    .map(|wl| {
                        (
                            fit(&points(report, sizes, &st, wl, ns_per_ray, "")),
                            fit(&points(report, sizes, &st, wl, tests_per_ray, "")),
                        )
                    })
                    .collect(),
                structure: st,
            })
            .collect();
        Exponents {
            sizes: sizes.clone(),
            workloads,
            rows,
        }
    }
}

/// A theory curve: its law, the exponent it stands for, its dash pattern, and `f(N)`.
struct Law {
    name: &'static str,
    exponent: &'static str,
    dash: (u32, u32),
    f: fn(f64) -> f64,
}

const LOG_N: Law = Law {
    name: "log N",
    exponent: "b ≈ 0",
    dash: (2, 3),
    f: f64::ln,
};
const CBRT_N: Law = Law {
    name: "N^(1/3)",
    exponent: "b = 0.33",
    dash: (9, 4),
    f: f64::cbrt,
};
const LINEAR_N: Law = Law {
    name: "N",
    exponent: "b = 1",
    dash: (16, 4),
    f: |n| n,
};
const N_LOG_N: Law = Law {
    name: "N log N",
    exponent: "b ≈ 1",
    dash: (6, 2),
    f: |n| n * n.ln(),
};

/// Theory curves anchored at the geometric mean of every line's value at the smallest size,
/// each labelled with the exponent it stands for and the one it shows over this range of N
/// (log N is not flat over three decades).
fn references(lines: &[Line], n0: f64, n1: f64, laws: &[&Law]) -> Vec<Reference> {
    let firsts: Vec<f64> = lines
        .iter()
        .filter_map(|l| l.points.first().filter(|p| p.x == n0).map(|p| p.y))
        .filter(|v| *v > 0.0)
        .collect();
    if firsts.is_empty() {
        return Vec::new();
    }
    let y0 = (firsts.iter().map(|v| v.ln()).sum::<f64>() / firsts.len() as f64).exp();
    laws.iter()
        .map(|law| {
            let points: Vec<(f64, f64)> = (0..=20)
                .map(|i| {
                    let n = n0 * (n1 / n0).powf(i as f64 / 20.0);
                    (n, y0 * (law.f)(n) / (law.f)(n0))
                })
                .collect();
            let here =
                fit_power(&points).map_or(String::new(), |f| format!(" ({:.2} here)", f.exponent));
            let here = if law.exponent.contains('≈') {
                here
            } else {
                String::new()
            };
            Reference {
                label: format!("∝ {}: {}{here}", law.name, law.exponent),
                dash: law.dash,
                points,
            }
        })
        .collect()
}

pub(super) fn scaling_chart(
    report: &Report,
    sizes: &Sizes,
    palette: &Palette,
) -> Result<Option<String>> {
    let wl = timing_workload(report).unwrap_or_default();
    let n0 = sizes.scenes[0].1;
    let n1 = sizes.scenes[sizes.scenes.len() - 1].1;
    let ticks: Vec<Tick> = sizes
        .scenes
        .iter()
        .map(|(scene, n)| Tick {
            x: *n,
            label: tick_label(*n),
            title: Some(scene.clone()),
        })
        .collect();
    let panel = |title: String, y_desc: &str, wl: &str, measure: Measure, laws: &[&Law]| {
        let lines: Vec<Line> = structure_names(report)
            .into_iter()
            .map(|st| {
                let pts = points(report, sizes, &st, wl, measure, y_desc);
                let label = match fit(&pts) {
                    Some(f) => format!("{st}: b = {}", f.text()),
                    None => st.clone(),
                };
                Line {
                    label,
                    color: palette.color(&st),
                    marker: palette.marker(&st),
                    points: pts,
                }
            })
            .filter(|l| !l.points.is_empty())
            .collect();
        LineChart {
            title,
            x_desc: "triangles traced (N)".into(),
            y_desc: y_desc.into(),
            log_x: true,
            ticks: ticks.clone(),
            references: references(&lines, n0, n1, laws),
            lines,
            marks: Vec::new(),
        }
    };
    let panels: Vec<LineChart> = [
        panel(
            format!(
                "{}: build time against triangles, fitted ∝ N^b",
                sizes.family
            ),
            "build ms",
            "",
            build_ms,
            &[&LINEAR_N, &N_LOG_N],
        ),
        panel(
            format!("Time per ray against triangles ({wl}), fitted ∝ N^b"),
            "ns per ray",
            &wl,
            ns_per_ray,
            &[&LOG_N, &CBRT_N, &LINEAR_N],
        ),
        panel(
            format!("Triangle tests per ray against triangles ({wl}), fitted ∝ N^b"),
            "tests per ray",
            &wl,
            tests_per_ray,
            &[&LOG_N, &CBRT_N, &LINEAR_N],
        ),
    ]
    .into_iter()
    .filter(LineChart::has_data)
    .collect();
    if panels.is_empty() {
        return Ok(None);
    }
    Ok(Some(lines_svg(&panels, W, H)?))
}
