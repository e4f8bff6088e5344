//! The tables of figures the pages share: results (all scenes, or one scene's rows), agreement
//! per class, the fitted scaling exponents, the sweep's sentence and the notes and errors.
//! Every table of numbers is `sortable` (see the page's script); a cell starts with the number
//! it sorts by.

use super::fit::PowerFit;
use super::names::{structure_names, workload_names};
use super::page::escape;
use super::scaling::Exponents;
use super::sweep::Sweep;
use super::ticks::tick_label;
use crate::report::run::{Report, throughput_unit};
use std::fmt::Write as _;

fn ratio(r: Option<f64>) -> String {
    r.map_or("-".into(), |r| format!("{r:.2}×"))
}

/// The results of `scenes`: one row per scene × structure with build time, memory, SAH cost,
/// each workload's throughput (each with its ratio to the reference) and the mismatch count.
/// The scene column is left out when the table holds one scene.
pub(crate) fn results_table(s: &mut String, report: &Report, scenes: &[String]) {
    let workloads = workload_names(report);
    let with_scene = scenes.len() != 1;
    s.push_str("<table class=\"sortable results\"><thead><tr>");
    if with_scene {
        s.push_str("<th class=\"l\">scene</th>");
    }
    s.push_str(
        "<th class=\"l\">structure</th><th>triangles</th><th>build ms (× ref)</th>\
         <th>bytes / triangle</th><th>SAH</th>",
    );
    for w in &workloads {
        let unit = throughput_unit(w);
        let _ = write!(s, "<th>{} {unit} (× ref)</th>", escape(w));
    }
    s.push_str("<th>mismatches</th></tr></thead>\n<tbody>\n");
    for scene in scenes {
        for st in structure_names(report) {
            let Some(r) = report
                .results
                .iter()
                .find(|r| &r.scene == scene && r.structure == st)
            else {
                continue;
            };
            s.push_str("<tr>");
            if with_scene {
                let _ = write!(s, "<td class=\"l\">{}</td>", escape(scene));
            }
            let _ = write!(
                s,
                "<td class=\"l st\">{}</td><td>{}</td><td title=\"fastest {:.1}, slowest {:.1} of {} \
                 runs\">{:.1} <small>({})</small></td><td>{:.1}</td><td>{}</td>",
                escape(&st),
                r.triangles.traced,
                r.build.min_ms,
                r.build.max_ms,
                r.build.runs,
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
                        let t = &x.mqueries_per_s;
                        let _ = write!(
                            s,
                            "<td title=\"slowest {:.2}, fastest {:.2} of {} runs\">{:.2} <small>({})</small></td>",
                            t.min,
                            t.max,
                            t.runs,
                            t.median,
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
    s.push_str("</tbody></table>\n");
}

pub(crate) fn sweep_note(s: &mut String, sweep: &Sweep) {
    let (first, last) = (&sweep.points[0], &sweep.points[sweep.points.len() - 1]);
    let _ = writeln!(
        s,
        "<p>A sweep of <b>{}</b> in <code>{}</code>, {} scenes from {} to {}: the charts draw \
         each structure as a line against it{}.</p>",
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
pub(crate) fn exponents_table(s: &mut String, e: &Exponents) {
    let n = &e.sizes.scenes;
    let _ = writeln!(
        s,
        "<h2 id=\"exponents\">Scaling exponents</h2>\n<p class=\"note\">Each quantity fitted as \
         ∝ N<sup>b</sup> by least squares on log–log axes over the {} scenes of <code>{}</code> \
         (N = {} to {} triangles); ± is the 95 % confidence interval (the slope's standard \
         error × Student's t, n − 2 degrees of freedom). Theory: log N gives b ≈ 0 (slightly \
         above over a finite range), N<sup>1/3</sup> (a uniform grid's cells along a ray) \
         b = 0.33, N (brute force) b = 1; a build in N log N shows b a little above 1.</p>",
        n.len(),
        escape(&e.sizes.family),
        tick_label(n[0].1),
        tick_label(n[n.len() - 1].1)
    );
    s.push_str(
        "<table class=\"sortable\"><thead><tr><th class=\"l\">structure</th><th>build time</th>",
    );
    for w in &e.workloads {
        let _ = write!(
            s,
            "<th>{} time per query</th><th>{} triangle tests per query</th>",
            escape(w),
            escape(w)
        );
    }
    s.push_str("</tr></thead>\n<tbody>\n");
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
    s.push_str("</tbody></table>\n");
}

/// Rays per validation class and structure, over `scenes`.
pub(crate) fn agreement_table(s: &mut String, report: &Report, scenes: &[String]) {
    s.push_str(
        "<table class=\"sortable agreement\"><thead><tr><th class=\"l\">structure</th><th>rays</th>\
         <th>both miss</th><th>exact</th><th>within tolerance</th><th>tie</th><th>boundary</th>\
         <th>edge ambiguous</th><th>mismatch</th><th>counted path differs</th></tr></thead>\n\
         <tbody>\n",
    );
    for st in structure_names(report) {
        let mut c = raybench_accel::classify::VerdictCounts::default();
        let mut differs = 0;
        let mut any = false;
        for w in report
            .results
            .iter()
            .filter(|r| r.structure == st && scenes.contains(&r.scene))
            .flat_map(|r| &r.workloads)
        {
            c += w.agreement.counts;
            differs += w.agreement.counted_path_differs;
            any = true;
        }
        if !any {
            continue;
        }
        let _ = writeln!(
            s,
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td{}>{}</td><td>{}</td></tr>",
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
    s.push_str("</tbody></table>\n");
}

pub(crate) fn notes(s: &mut String, report: &Report) {
    if report.notes.is_empty() && report.errors.is_empty() {
        return;
    }
    s.push_str("<h2 id=\"notes\">Notes and errors</h2>\n<ul>\n");
    for e in &report.errors {
        let _ = writeln!(s, "<li class=\"bad\">{}</li>", escape(e));
    }
    for n in &report.notes {
        let _ = writeln!(s, "<li>{}</li>", escape(n));
    }
    s.push_str("</ul>\n");
}
