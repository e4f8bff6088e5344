//! Break-even per scene: the total time to build a structure once and trace K rays, K from
//! 1e3 to 1e9, so that where two lines cross one structure starts to pay for its build.

use super::lines::{Line, LineChart, Point, lines_svg};
use super::names::scene_label;
use super::palette::Palette;
use super::scaling::timing_workload;
use super::sweep::Sweep;
use super::ticks::tick_label;
use super::{H, W};
use crate::report::run::Report;
use anyhow::Result;

pub(super) fn break_even_chart(
    report: &Report,
    scene: &str,
    sweep: Option<&Sweep>,
    palette: &Palette,
) -> Result<Option<String>> {
    let Some(wl) = timing_workload(report) else {
        return Ok(None);
    };
    let ks: Vec<f64> = (0..=24)
        .map(|i| 10f64.powf(3.0 + 6.0 * i as f64 / 24.0))
        .collect();
    let lines: Vec<Line> = report
        .results
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| {
            let w = r.workloads.iter().find(|w| w.workload == wl)?;
            let rate = w.mqueries_per_s.median * 1e6;
            (rate > 0.0).then(|| {
                let build_s = r.build.median_ms / 1e3;
                let st = &r.structure;
                Line {
                    label: st.clone(),
                    color: palette.color(st),
                    marker: palette.marker(st),
                    points: ks
                        .iter()
                        .map(|&k| {
                            let y = build_s + k / rate;
                            Point {
                                x: k,
                                y,
                                range: None,
                                title: format!(
                                    "{st}: {} rays in {} s",
                                    tick_label(k),
                                    tick_label(y)
                                ),
                            }
                        })
                        .collect(),
                }
            })
        })
        .collect();
    let chart = LineChart {
        title: format!("{}: build + trace K rays ({wl})", scene_label(sweep, scene)),
        x_desc: "rays traced (K)".into(),
        y_desc: "total seconds".into(),
        log_x: true,
        ticks: Vec::new(),
        lines,
        references: Vec::new(),
    };
    if !chart.has_data() {
        return Ok(None);
    }
    Ok(Some(lines_svg(&[chart], W, H)?))
}
