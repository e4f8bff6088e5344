//! Break-even per scene: the total time to build a structure once and trace K rays, K from
//! 1e3 to 1e9, so that where two lines cross one structure starts to pay for its build. The
//! crossing the answer table quotes (from how many rays the fastest tracer wins with its build
//! counted) is marked with its ray count.

use super::answer::answer;
use super::lines::{Line, LineChart, Mark, Point, lines_svg};
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
    let crossing = answer(report, scene, &wl).and_then(|a| Some((a.break_even?, a.fastest)));
    // K from 1e3 to 1e9, wider by whole decades when the crossing lies outside.
    let (lo, hi) = match &crossing {
        Some(((k, _), _)) if k.is_finite() && *k > 0.0 => (
            k.log10().floor().clamp(0.0, 3.0),
            (k.log10().ceil() + 1.0).clamp(9.0, 15.0),
        ),
        _ => (3.0, 9.0),
    };
    let steps = (4.0 * (hi - lo)) as usize;
    let ks: Vec<f64> = (0..=steps)
        .map(|i| 10f64.powf(lo + (hi - lo) * i as f64 / steps as f64))
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
    let marks = crossing
        .and_then(|((k, below), fastest)| {
            let r = report
                .results
                .iter()
                .find(|r| r.scene == scene && r.structure == fastest)?;
            let rate = r
                .workloads
                .iter()
                .find(|w| w.workload == wl)?
                .mqueries_per_s
                .median
                * 1e6;
            Some(Mark {
                x: k,
                y: r.build.median_ms / 1e3 + k / rate,
                label: format!("{} rays", tick_label(k)),
                title: format!(
                    "From {} rays on, {fastest} takes the least time with its build counted; \
                     below, {below}",
                    tick_label(k)
                ),
            })
        })
        .into_iter()
        .collect();
    let chart = LineChart {
        title: format!("{}: build + trace K rays ({wl})", scene_label(sweep, scene)),
        x_desc: "rays traced (K)".into(),
        y_desc: "total seconds".into(),
        log_x: true,
        ticks: Vec::new(),
        lines,
        references: Vec::new(),
        marks,
    };
    if !chart.has_data() {
        return Ok(None);
    }
    Ok(Some(lines_svg(&[chart], W, H)?))
}
