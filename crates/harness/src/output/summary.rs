//! The table printed at the end of a run: build time, throughput and agreement per scene ×
//! structure, each with its ratio to the reference measured in the same run.

use super::agreement::{agreement_sentence_of, class_counts};
use crate::report::run::{Report, is_point_workload};
use raybench_accel::classify::VerdictCounts;
use std::fmt::Write;

fn ratio(r: Option<f64>) -> String {
    r.map(|x| format!("{}x", sig(x)))
        .unwrap_or_else(|| "-".into())
}

/// Three significant digits however small the value (brute force runs at 1e-3 Mrays/s).
pub(crate) fn sig(x: f64) -> String {
    if x == 0.0 || x.abs() >= 100.0 {
        format!("{x:.0}")
    } else {
        let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    }
}

pub fn summary_table(report: &Report) -> String {
    let workloads = &report.run.workloads;
    let mut out = String::new();
    // The scene column fits the longest name (specs can be long), within reason.
    let sw = report
        .results
        .iter()
        .map(|r| r.scene.chars().count())
        .max()
        .unwrap_or(5)
        .clamp(5, 48);
    let _ = write!(
        out,
        "{:<sw$} {:<22} {:>10} {:>7}",
        "scene", "structure", "build ms", "x ref"
    );
    for w in workloads {
        // Closest-point workloads count queries, not rays.
        let unit = if is_point_workload(w) { "Mq/s" } else { "Mr/s" };
        let _ = write!(out, " {:>10} {:>7}", format!("{w} {unit}"), "x ref");
    }
    let _ = writeln!(out, " {:>9} {:>9}", "ambig.", "mismatch");
    // Other crates' structures (`peer-*`, registered last) under their own line in each scene.
    let mut peers_of: Option<&str> = None;
    for r in &report.results {
        if crate::registry::is_peer_name(&r.structure) && peers_of != Some(r.scene.as_str()) {
            peers_of = Some(&r.scene);
            let _ = writeln!(out, "{:<sw$} -- peers: other crates' structures --", "");
        }
        let _ = write!(
            out,
            "{:<sw$} {:<22} {:>10} {:>7}",
            truncate(&r.scene, sw),
            truncate(&r.structure, 22),
            sig(r.build.median_ms),
            ratio(r.build_ratio_to_reference)
        );
        for w in workloads {
            match r.workloads.iter().find(|x| &x.workload == w) {
                Some(x) => {
                    let _ = write!(
                        out,
                        " {:>10} {:>7}",
                        sig(x.mqueries_per_s.median),
                        ratio(x.speedup_vs_reference)
                    );
                }
                None if r.not_offered.contains(w) => {
                    let _ = write!(out, " {:>10} {:>7}", "not offered", "-");
                }
                None => {
                    let _ = write!(out, " {:>10} {:>7}", "-", "-");
                }
            }
        }
        let ambiguous: u64 = r
            .workloads
            .iter()
            .map(|w| w.agreement.counts.ambiguous())
            .sum();
        let mismatch: u64 = r
            .workloads
            .iter()
            .map(|w| w.agreement.counts.mismatch + w.agreement.counted_path_differs)
            .sum();
        let _ = writeln!(out, " {ambiguous:>9} {mismatch:>9}");
    }
    write_point_work(&mut out, report);
    write_intervals(&mut out, report);
    write_agreement(&mut out, report);
    write_claims(&mut out, report);
    for n in &report.notes {
        let _ = writeln!(out, "note: {n}");
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}

/// How precise each structure's ratios to the reference are: the half-width of their
/// confidence intervals (see `report/interval.rs`) relative to the ratio, median and widest,
/// for throughput and for build time apart (they have different numbers of rounds).
fn write_intervals(out: &mut String, report: &Report) {
    // Per structure: (relative half-width, where) for traces, and for builds.
    type Widths = Vec<(f64, String)>;
    let mut rows: Vec<(&str, Widths, Widths)> = Vec::new();
    let (mut trace_level, mut build_level) = (f64::INFINITY, f64::INFINITY);
    for r in report
        .results
        .iter()
        .filter(|r| r.structure != report.run.reference)
    {
        let at = match rows.iter().position(|(s, ..)| *s == r.structure) {
            Some(i) => i,
            None => {
                rows.push((&r.structure, Vec::new(), Vec::new()));
                rows.len() - 1
            }
        };
        if let (Some(i), Some(x)) = (r.build_ratio_interval, r.build_ratio_to_reference) {
            build_level = build_level.min(i.level);
            rows[at].2.push((i.relative_half_width(x), r.scene.clone()));
        }
        for w in &r.workloads {
            if let (Some(i), Some(x)) = (w.speedup_interval, w.speedup_vs_reference) {
                trace_level = trace_level.min(i.level);
                let place = format!("{} {}", r.scene, w.workload);
                rows[at].1.push((i.relative_half_width(x), place));
            }
        }
    }
    if trace_level.is_infinite() && build_level.is_infinite() {
        return;
    }
    let level = |l: f64| {
        if l.is_finite() {
            format!("{:.1} %", l * 100.0)
        } else {
            "-".into()
        }
    };
    let _ = writeln!(
        out,
        "\nRatio precision: each ratio to {} is the median of per-round ratios; half its \
         confidence interval as ± % of it (coverage: throughput {}, build {}):",
        report.run.reference,
        level(trace_level),
        level(build_level)
    );
    let describe = |mut widths: Widths| {
        if widths.is_empty() {
            return "-".to_string();
        }
        widths.sort_by(|a, b| a.0.total_cmp(&b.0));
        let median = widths[widths.len() / 2].0;
        let (widest, at) = &widths[widths.len() - 1];
        format!(
            "median ±{:.1} %, widest ±{:.1} % ({at})",
            median * 100.0,
            widest * 100.0
        )
    };
    for (structure, traces, builds) in rows {
        let _ = writeln!(
            out,
            "  {structure}: throughput {}; build {}",
            describe(traces),
            describe(builds)
        );
    }
}

/// Agreement with the reference per structure (all scenes and workloads) and overall, in the
/// words of [`super::agreement`], with the counts of every class.
fn write_agreement(out: &mut String, report: &Report) {
    let _ = writeln!(
        out,
        "\nAgreement with {} ({} threads, seed {}):",
        report.run.reference, report.run.threads, report.run.seed
    );
    let mut total = VerdictCounts::default();
    let mut structures: Vec<&str> = Vec::new();
    for r in &report.results {
        if !structures.contains(&r.structure.as_str()) {
            structures.push(&r.structure);
        }
    }
    for name in structures {
        // Rays and closest-point queries are stated apart: one bound over both would mix
        // two different questions.
        for (point_query, what) in [(false, "rays"), (true, "queries")] {
            let mut counts = VerdictCounts::default();
            let (mut counted_differs, mut counted_explained) = (0, 0);
            let workloads = report
                .results
                .iter()
                .filter(|r| r.structure == name)
                .flat_map(|r| &r.workloads)
                .filter(|w| w.point_query == point_query);
            for w in workloads {
                counts += w.agreement.counts;
                counted_differs += w.agreement.counted_path_differs;
                counted_explained += w.agreement.counted_path_explained;
            }
            if counts.total() == 0 && counted_differs == 0 {
                continue;
            }
            total += counts;
            let kind = if point_query { " (closest points)" } else { "" };
            let _ = writeln!(
                out,
                "  {name}{kind}: {}; {}{}",
                agreement_sentence_of(&counts, what),
                class_counts(&counts),
                counted_path_note(counted_differs, counted_explained)
            );
        }
    }
    // A ray is compared once per structure: the sum gets no bound of its own.
    let _ = writeln!(
        out,
        "  all structures: {} mismatches in {} comparisons",
        total.mismatch,
        total.total()
    );
}

/// The work behind each closest-point figure, per query: nodes and leaves (or cells) visited and
/// point–triangle distance tests. Only for structures that count (not Embree).
fn write_point_work(out: &mut String, report: &Report) {
    let rows: Vec<_> = report
        .results
        .iter()
        .flat_map(|r| r.workloads.iter().map(move |w| (r, w)))
        .filter(|(_, w)| w.point_query)
        .filter_map(|(r, w)| w.counters_per_query.map(|c| (r, w, c)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nClosest-point work per query (Mq/s = million queries per second):"
    );
    let _ = writeln!(
        out,
        "  {:<30} {:<22} {:<14} {:>9} {:>9} {:>9} {:>10}",
        "scene", "structure", "workload", "nodes", "leaves", "cells", "dist tests"
    );
    for (r, w, c) in rows {
        let _ = writeln!(
            out,
            "  {:<30} {:<22} {:<14} {:>9} {:>9} {:>9} {:>10}",
            truncate(&r.scene, 30),
            truncate(&r.structure, 22),
            w.workload,
            sig(c.nodes),
            sig(c.leaves),
            sig(c.cells),
            sig(c.prim_tests)
        );
    }
}

/// Said only when it happens: the counted walk answering differently without an explanation
/// is a bug of its own; explained differences (ties, edge-ambiguous rays) are counted apart.
pub(crate) fn counted_path_note(unexplained: u64, explained: u64) -> String {
    let mut note = String::new();
    if unexplained > 0 {
        note += &format!(
            "; the counted path answered differently from the timed path on {unexplained} rays"
        );
    }
    if explained > 0 {
        note += &format!(
            "; the timed and counted paths differ on {explained} rays, each one explained \
             (tie, edge-ambiguous, boundary or within tolerance)"
        );
    }
    note
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        s.chars().take(n - 1).chain(['~']).collect()
    }
}

/// The claims' verdicts, one line each; one line in all when the run measured none of them.
fn write_claims(out: &mut String, report: &Report) {
    use crate::report::claims::Verdict;
    let claims = &report.claims;
    if claims.iter().all(|c| c.verdict == Verdict::NotMeasured) {
        if !claims.is_empty() {
            let _ = writeln!(
                out,
                "claims: none measured in this run (`raybench run --suite claims` measures all {})",
                claims.len()
            );
        }
        return;
    }
    let _ = writeln!(
        out,
        "claims (rules and figures on the page and in report.json):"
    );
    for c in claims {
        let _ = writeln!(
            out,
            "  {:<24} {:<24} {}",
            c.id,
            c.verdict.text(),
            c.statement
        );
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn three_significant_digits() {
        assert_eq!(super::sig(0.001234), "0.00123");
        assert_eq!(super::sig(24.863), "24.9");
        assert_eq!(super::sig(1.0), "1.00");
        assert_eq!(super::sig(1234.5), "1234");
    }
}
