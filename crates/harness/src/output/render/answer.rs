//! The answer first: per scene and workload, the structure that traces fastest, its margin over
//! the next one, and from how many queries it also wins once each structure's build is counted —
//! the crossing the break-even charts draw, as a number. Below that count a faster-building
//! structure wins, and the table names it.

use super::names::{scene_names, workload_names};
use super::page::escape;
use super::ticks::tick_label;
use crate::output::results::ratio_text;
use crate::report::run::Report;
use std::fmt::Write;

/// One scene × workload's answer.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Answer {
    pub fastest: String,
    /// The fastest's throughput over the next fastest's (`None` with one structure).
    pub margin: Option<(String, f64)>,
    /// Queries from which the fastest also wins with its build counted, and the structure that
    /// wins just below (`None` when the fastest also builds fastest, or ties).
    pub break_even: Option<(f64, String)>,
}

/// Relative build-time difference below which two builds count as equally fast.
const BUILD_NOISE: f64 = 0.1;

/// Build once, then trace `k` queries at `rate` per second: the total in seconds.
fn total(build_ms: f64, rate: f64, k: f64) -> f64 {
    build_ms / 1e3 + k / rate
}

/// The answer for `scene` and `workload`, from every structure with a positive throughput.
pub(crate) fn answer(report: &Report, scene: &str, workload: &str) -> Option<Answer> {
    let mut entries: Vec<(&str, f64, f64)> = report
        .results
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| {
            let w = r.workloads.iter().find(|w| w.workload == workload)?;
            let rate = w.mqueries_per_s.median * 1e6;
            (rate > 0.0 && rate.is_finite()).then_some((
                r.structure.as_str(),
                rate,
                r.build.median_ms,
            ))
        })
        .collect();
    // Fastest first; equal rates in the report's order.
    entries.sort_by(|a, b| b.1.total_cmp(&a.1));
    let &(fastest, rate, build) = entries.first()?;
    let margin = entries
        .get(1)
        .map(|&(next, next_rate, _)| (next.to_string(), rate / next_rate));
    // Each faster-building structure wins until its total meets the fastest's; the last such
    // crossing is where the fastest starts to win overall. Builds within BUILD_NOISE of each
    // other count as equal (two entries sharing one tree differ by about that here).
    let crossing = entries
        .iter()
        .filter(|&&(_, r, b)| b < build * (1.0 - BUILD_NOISE) && r < rate)
        .map(|&(_, r, b)| (build - b) / 1e3 / (1.0 / r - 1.0 / rate))
        .fold(None, |m: Option<f64>, k| Some(m.map_or(k, |m| m.max(k))));
    let break_even = crossing.and_then(|k| {
        let below = k * 0.999;
        let (winner, _, _) = entries
            .iter()
            .filter(|e| e.2 < build * (1.0 - BUILD_NOISE))
            .min_by(|a, b| total(a.2, a.1, below).total_cmp(&total(b.2, b.1, below)))?;
        (*winner != fastest).then(|| (k, winner.to_string()))
    });
    Some(Answer {
        fastest: fastest.to_string(),
        margin,
        break_even,
    })
}

/// The summary's first section: one row per scene with each workload's answer, the scene
/// linked to its page.
pub(crate) fn answer_section(
    s: &mut String,
    report: &Report,
    link: &dyn Fn(&str) -> Option<String>,
) {
    s.push_str(
        "<h2 id=\"answer\">The answer</h2>\n<p class=\"note\">Per scene and workload: the \
         structure with the highest throughput, how much faster it is than the next one, and \
         from how many queries it also wins when each structure's build is counted (below that, \
         the named structure wins because it builds faster). Medians of this run. A scene's \
         name leads to its page.</p>\n",
    );
    answer_table(s, report, &scene_names(report), link);
}

/// Under a scene's name: its triangles, and its mismatches when there are any.
fn scene_facts(report: &Report, scene: &str) -> String {
    let results: Vec<_> = report.results.iter().filter(|r| r.scene == scene).collect();
    let Some(first) = results.first() else {
        return String::new();
    };
    let bad: u64 = results
        .iter()
        .flat_map(|r| &r.workloads)
        .map(|w| w.agreement.counts.mismatch + w.agreement.counted_path_differs)
        .sum();
    let mut out = format!(
        "<br><small>{} triangles",
        tick_label(first.triangles.traced as f64)
    );
    if bad > 0 {
        let _ = write!(out, "; <span class=\"bad\">{bad} mismatches</span>");
    }
    out.push_str("</small>");
    out
}

/// The answer rows of `scenes`; a scene whose `link` is known is a link.
pub(crate) fn answer_table(
    s: &mut String,
    report: &Report,
    scenes: &[String],
    link: &dyn Fn(&str) -> Option<String>,
) {
    let workloads = workload_names(report);
    s.push_str("<table class=\"answer\"><tr><th class=\"l\">scene</th>");
    for w in &workloads {
        let _ = write!(s, "<th class=\"l\">{}</th>", escape(w));
    }
    s.push_str("</tr>\n");
    for scene in scenes {
        let name = match link(scene) {
            Some(file) => format!("<a href=\"{}\">{}</a>", escape(&file), escape(scene)),
            None => escape(scene),
        };
        let _ = write!(
            s,
            "<tr><td class=\"l\">{name}{}</td>",
            scene_facts(report, scene)
        );
        for w in &workloads {
            match answer(report, scene, w) {
                None => s.push_str("<td class=\"l\">–</td>"),
                Some(a) => {
                    let _ = write!(s, "<td class=\"l\"><b>{}</b>", escape(&a.fastest));
                    if let Some((next, m)) = &a.margin {
                        let _ = write!(
                            s,
                            " <span title=\"over {}\">{}×</span>",
                            escape(next),
                            ratio_text(*m)
                        );
                    }
                    if let Some((k, below)) = &a.break_even {
                        let _ = write!(
                            s,
                            "<br><small>from {} queries; below, {}</small>",
                            tick_label(*k),
                            escape(below)
                        );
                    }
                    s.push_str("</td>");
                }
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
}

#[cfg(test)]
mod tests {
    use super::total;

    #[test]
    fn the_crossing_is_where_the_totals_meet() {
        // Fast: 100 ms build, 10 M/s. Cheap: 10 ms build, 2 M/s. They meet at
        // 0.09 s / (1/2e6 - 1/1e7) = 225,000 queries.
        let (fb, fr, cb, cr): (f64, f64, f64, f64) = (100.0, 1e7, 10.0, 2e6);
        let k = (fb - cb) / 1e3 / (1.0 / cr - 1.0 / fr);
        assert!((k - 225_000.0).abs() < 1e-6, "{k}");
        assert!((total(fb, fr, k) - total(cb, cr, k)).abs() < 1e-12);
        assert!(total(fb, fr, k * 0.9) > total(cb, cr, k * 0.9));
        assert!(total(fb, fr, k * 1.1) < total(cb, cr, k * 1.1));
    }
}
