//! The table printed at the end of a run: build time, throughput and agreement per scene ×
//! structure, each with its ratio to the reference measured in the same run.

use crate::report::Report;
use std::fmt::Write;

fn ratio(r: Option<f64>) -> String {
    r.map(|x| format!("{}x", sig(x)))
        .unwrap_or_else(|| "-".into())
}

/// Three significant digits however small the value (brute force runs at 1e-3 Mrays/s).
fn sig(x: f64) -> String {
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
        let _ = write!(out, " {:>10} {:>7}", format!("{w} Mr/s"), "x ref");
    }
    let _ = writeln!(out, " {:>9} {:>9}", "ambig.", "mismatch");
    for r in &report.results {
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
                        sig(x.mrays_per_s.median),
                        ratio(x.speedup_vs_reference)
                    );
                }
                None => {
                    let _ = write!(out, " {:>10} {:>7}", "-", "-");
                }
            }
        }
        let ambiguous: u64 = r
            .workloads
            .iter()
            .map(|w| w.validation.counts.ambiguous())
            .sum();
        let mismatch: u64 = r
            .workloads
            .iter()
            .map(|w| w.validation.counts.mismatch + w.validation.counted_path_differs)
            .sum();
        let _ = writeln!(out, " {ambiguous:>9} {mismatch:>9}");
    }
    let rays: u64 = report
        .results
        .iter()
        .flat_map(|r| &r.workloads)
        .map(|w| w.validation.rays())
        .sum();
    let _ = writeln!(
        out,
        "\n{} mismatches in {rays} validated rays against {} ({} threads, seed {}).",
        report.mismatches(),
        report.run.reference,
        report.run.threads,
        report.run.seed
    );
    if rays > 0 && report.mismatches() == 0 {
        let _ = writeln!(
            out,
            "95% upper bound on the mismatch rate: {:.1e} (rule of three).",
            3.0 / rays as f64
        );
    }
    for n in &report.notes {
        let _ = writeln!(out, "note: {n}");
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        s.chars().take(n - 1).chain(['~']).collect()
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
