//! `index.html`: one static page (no JavaScript) with the tables, charts, pictures and the
//! environment fingerprint of a report.

use super::fit::PowerFit;
use super::names::{scene_names, structure_names, workload_names};
use super::scaling::Exponents;
use super::sweep::Sweep;
use super::ticks::tick_label;
use super::{ChartFile, ScenePictures};
use crate::report::run::{Report, throughput_unit};
use std::fmt::Write as _;

pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:24px;color:#222;max-width:1300px}\
table{border-collapse:collapse;margin:12px 0;font-size:13px}\
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}\
th{background:#f0f0f0}td.l,th.l{text-align:left}\
figure{margin:18px 0}figcaption{font-size:13px;color:#444}\
img.chart{max-width:100%;border:1px solid #ddd}\
img.px{image-rendering:pixelated;width:240px;border:1px solid #ddd}\
.bad{color:#c00;font-weight:bold}.holds{color:#080;font-weight:bold}.note{color:#555;font-size:13px}";

/// What the page shows beside the report itself.
pub(crate) struct Extras<'a> {
    pub charts: &'a [ChartFile],
    pub pictures: &'a [ScenePictures],
    /// The parameter the report sweeps, if any.
    pub sweep: Option<&'a Sweep>,
    /// Fitted exponents against N, when the scenes grow.
    pub exponents: Option<&'a Exponents>,
    /// The claim charts written (see [`super::claims_section`]).
    pub claim_charts: &'a [String],
}

pub(crate) fn page(report: &Report, extras: &Extras) -> String {
    let mut s = String::new();
    let env = &report.header.environment;
    let title = match &report.run.suite {
        Some(suite) => format!("raybench: suite {suite}"),
        None => "raybench report".to_string(),
    };
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\
         <style>{STYLE}</style></head><body>\n<h1>{}</h1>\n<p class=\"note\">{} at revision {}, \
         {} thread(s), seed {}, {} rays per workload; every answer checked against <b>{}</b>.</p>\n",
        escape(&title),
        escape(&title),
        escape(&env.timestamp),
        escape(&env.git_revision),
        report.run.threads,
        report.run.seed,
        report.run.rays,
        escape(&report.run.reference)
    );
    let mismatches = report.mismatches();
    let _ = writeln!(
        s,
        "<p class=\"{}\">{} mismatches in {} checked rays.</p>",
        if mismatches > 0 { "bad" } else { "note" },
        mismatches,
        report
            .results
            .iter()
            .flat_map(|r| &r.workloads)
            .map(|w| w.agreement.queries())
            .sum::<u64>()
    );
    if let Some(sweep) = extras.sweep {
        sweep_note(&mut s, sweep);
    }
    super::answer::answer_section(&mut s, report);
    super::claims_section::claims_section(&mut s, report, extras.claim_charts);
    results_table(&mut s, report);
    agreement_table(&mut s, report);
    if let Some(e) = extras.exponents {
        exponents_table(&mut s, e);
    }
    s.push_str("<h2>Charts</h2>\n");
    for c in extras.charts {
        let _ = writeln!(
            s,
            "<figure><img class=\"chart\" src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            escape(&c.file),
            escape(&c.caption),
            escape(&c.caption)
        );
    }
    super::picture_section::pictures_section(&mut s, extras.pictures);
    notes(&mut s, report);
    environment(&mut s, report);
    s.push_str("</body></html>\n");
    s
}

fn results_table(s: &mut String, report: &Report) {
    let workloads = workload_names(report);
    s.push_str(
        "<h2>Results</h2>\n<table><tr><th class=\"l\">scene</th><th class=\"l\">structure</th>\
                <th>triangles</th><th>build ms (× ref)</th><th>bytes / triangle</th><th>SAH</th>",
    );
    for w in &workloads {
        let unit = throughput_unit(w);
        let _ = write!(s, "<th>{} {unit} (× ref)</th>", escape(w));
    }
    s.push_str("<th>mismatches</th></tr>\n");
    for scene in scene_names(report) {
        for st in structure_names(report) {
            let Some(r) = report
                .results
                .iter()
                .find(|r| r.scene == scene && r.structure == st)
            else {
                continue;
            };
            let _ = write!(
                s,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{:.1} ({})</td>\
                 <td>{:.1}</td><td>{}</td>",
                escape(&scene),
                escape(&st),
                r.triangles.traced,
                r.build.median_ms,
                ratio(r.build_ratio_to_reference),
                r.memory_bytes as f64 / r.triangles.traced.max(1) as f64,
                r.build_stats
                    .sah_cost
                    .map_or("-".into(), |c| format!("{c:.2}"))
            );
            for w in &workloads {
                match r.workloads.iter().find(|x| &x.workload == w) {
                    Some(x) => {
                        let _ = write!(
                            s,
                            "<td>{:.2} ({})</td>",
                            x.mqueries_per_s.median,
                            ratio(x.speedup_vs_reference)
                        );
                    }
                    None => s.push_str("<td>-</td>"),
                }
            }
            let bad: u64 = r
                .workloads
                .iter()
                .map(|w| w.agreement.counts.mismatch + w.agreement.counted_path_differs)
                .sum();
            let _ = writeln!(
                s,
                "<td{}>{bad}</td></tr>",
                if bad > 0 { " class=\"bad\"" } else { "" }
            );
        }
    }
    s.push_str("</table>\n");
}

fn sweep_note(s: &mut String, sweep: &Sweep) {
    let (first, last) = (&sweep.points[0], &sweep.points[sweep.points.len() - 1]);
    let _ = writeln!(
        s,
        "<p>A sweep of <b>{}</b> in <code>{}</code>, {} scenes from {} to {}: the per-scene \
         charts draw each structure as a line against it{}.</p>",
        escape(&sweep.key),
        escape(&sweep.generator),
        sweep.points.len(),
        escape(&tick_label(first.value)),
        escape(&tick_label(last.value)),
        if sweep.log_x() {
            " on a logarithmic axis"
        } else {
            ""
        }
    );
}

/// Each structure's exponent b of `∝ N^b` per quantity, with its 95 % interval.
fn exponents_table(s: &mut String, e: &Exponents) {
    let n = &e.sizes.scenes;
    let _ = writeln!(
        s,
        "<h2>Scaling exponents</h2>\n<p class=\"note\">Each quantity fitted as ∝ N<sup>b</sup> by \
         least squares on log–log axes over the {} scenes of <code>{}</code> (N = {} to {} \
         triangles); ± is the 95 % confidence interval (the slope's standard error × Student's t, \
         n − 2 degrees of freedom). Theory: log N gives b ≈ 0 (slightly above over a finite \
         range), N<sup>1/3</sup> (a uniform grid's cells along a ray) b = 0.33, N (brute force) \
         b = 1; a build in N log N shows b a little above 1.</p>",
        n.len(),
        escape(&e.sizes.family),
        tick_label(n[0].1),
        tick_label(n[n.len() - 1].1)
    );
    s.push_str("<table><tr><th class=\"l\">structure</th><th>build time</th>");
    for w in &e.workloads {
        let _ = write!(
            s,
            "<th>{} time per query</th><th>{} triangle tests per query</th>",
            escape(w),
            escape(w)
        );
    }
    s.push_str("</tr>\n");
    let cell = |f: &Option<PowerFit>| f.map_or("-".to_string(), |f| f.text());
    for row in &e.rows {
        let _ = write!(
            s,
            "<tr><td class=\"l\">{}</td><td>{}</td>",
            escape(&row.structure),
            cell(&row.build)
        );
        for (time, tests) in &row.per_workload {
            let _ = write!(s, "<td>{}</td><td>{}</td>", cell(time), cell(tests));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
}

fn ratio(r: Option<f64>) -> String {
    r.map_or("-".into(), |r| format!("{r:.2}×"))
}

fn agreement_table(s: &mut String, report: &Report) {
    s.push_str(
        "<h2>Agreement</h2>\n<table><tr><th class=\"l\">structure</th><th>rays</th><th>both miss</th>\
         <th>exact</th><th>within tolerance</th><th>tie</th><th>boundary</th><th>edge ambiguous</th>\
         <th>mismatch</th><th>counted path differs</th></tr>\n",
    );
    for st in structure_names(report) {
        let mut c = raybench_accel::classify::VerdictCounts::default();
        let mut differs = 0;
        for w in report
            .results
            .iter()
            .filter(|r| r.structure == st)
            .flat_map(|r| &r.workloads)
        {
            c += w.agreement.counts;
            differs += w.agreement.counted_path_differs;
        }
        let _ = writeln!(
            s,
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td{}>{}</td><td>{}</td></tr>",
            escape(&st),
            c.total(),
            c.both_miss,
            c.exact,
            c.within_tolerance,
            c.tie,
            c.boundary,
            c.edge_ambiguous,
            if c.mismatch > 0 { " class=\"bad\"" } else { "" },
            c.mismatch,
            differs
        );
    }
    s.push_str("</table>\n");
}

fn notes(s: &mut String, report: &Report) {
    if report.notes.is_empty() && report.errors.is_empty() {
        return;
    }
    s.push_str("<h2>Notes and errors</h2>\n<ul>\n");
    for n in &report.notes {
        let _ = writeln!(s, "<li>{}</li>", escape(n));
    }
    for e in &report.errors {
        let _ = writeln!(s, "<li class=\"bad\">{}</li>", escape(e));
    }
    s.push_str("</ul>\n");
}

fn environment(s: &mut String, report: &Report) {
    s.push_str("<h2>Environment</h2>\n<table>\n");
    let env = serde_json::to_value(&report.header.environment).unwrap_or_default();
    let run = serde_json::to_value(&report.run).unwrap_or_default();
    for (section, value) in [("environment", env), ("run", run)] {
        if let serde_json::Value::Object(map) = value {
            for (k, v) in map {
                let text = match v {
                    serde_json::Value::String(t) => t,
                    other => other.to_string(),
                };
                let _ = writeln!(
                    s,
                    "<tr><td class=\"l\">{section}.{}</td><td class=\"l\">{}</td></tr>",
                    escape(&k),
                    escape(&text)
                );
            }
        }
    }
    s.push_str("</table>\n");
}
