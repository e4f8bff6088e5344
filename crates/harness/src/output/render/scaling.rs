//! Charts along scene size: scaling with the triangle count (when one scene family comes in
//! three or more sizes) and the break-even of build and trace time per scene.

use super::charts::{self, LogLog};
use super::names::{scene_names, structure_names, workload_names};
use super::{H, W};
use crate::report::run::Report;
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

/// A named reference curve `f(N)`.
type Curve = (&'static str, fn(f64) -> f64);

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

pub(super) fn scaling_chart(report: &Report) -> Result<Option<String>> {
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
                && w.mqueries_per_s.median > 0.0
            {
                t.push((n, 1e3 / w.mqueries_per_s.median));
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

pub(super) fn break_even_chart(report: &Report, scene: &str) -> Result<Option<String>> {
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
            let rate = w.mqueries_per_s.median * 1e6;
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
