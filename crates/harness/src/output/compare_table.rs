//! What `raybench compare` prints: the two reports' figures side by side as a Markdown table
//! (scene × structure × workload), then every finding.

use crate::report::compare::{CompareOptions, Finding, Severity};
use crate::report::run::{Report, ResultEntry, WorkloadResult};
use std::fmt::Write as _;

/// One table row: scene, structure, workload and the figures side by side.
pub(crate) struct Row {
    scene: String,
    structure: String,
    workload: String,
    speed: (Option<f64>, Option<f64>),
    build: (Option<f64>, Option<f64>),
    counters: &'static str,
    mismatches: (u64, u64),
}

pub(crate) fn row(
    be: &ResultEntry,
    ne: &ResultEntry,
    bw: &WorkloadResult,
    nw: &WorkloadResult,
    comparable: bool,
) -> Row {
    Row {
        scene: be.scene.clone(),
        structure: be.structure.clone(),
        workload: bw.workload.clone(),
        speed: (bw.speedup_vs_reference, nw.speedup_vs_reference),
        build: (be.build_ratio_to_reference, ne.build_ratio_to_reference),
        counters: match (&bw.counters_total, comparable) {
            (None, _) => "-",
            (_, false) => "not comparable",
            (Some(_), true) if bw.counters_total == nw.counters_total => "same",
            _ => "CHANGED",
        },
        mismatches: (
            bw.agreement.counts.mismatch + bw.agreement.counted_path_differs,
            nw.agreement.counts.mismatch + nw.agreement.counted_path_differs,
        ),
    }
}

fn ratio_cell((b, n): (Option<f64>, Option<f64>), higher_is_better: bool) -> String {
    match (b, n) {
        (Some(b), Some(n)) => {
            let change = if higher_is_better {
                n / b - 1.0
            } else {
                b / n - 1.0
            };
            format!("{b:.3} → {n:.3} ({:+.1} %)", change * 100.0)
        }
        _ => "-".into(),
    }
}

pub(crate) fn markdown(
    base: &Report,
    new: &Report,
    rows: &[Row],
    findings: &[Finding],
    opts: &CompareOptions,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## raybench compare\n\nbase: {} ({}), new: {} ({})\n",
        base.header.environment.git_revision,
        base.header.environment.timestamp,
        new.header.environment.git_revision,
        new.header.environment.timestamp
    );
    let _ = writeln!(
        s,
        "Ratios are to `{}` in the same run (speed: higher is better; build: lower is better); \
         the change is positive when the new report is better. Timing threshold {:.0} %{}.\n",
        new.run.reference,
        opts.max_slowdown * 100.0,
        if opts.timing_advisory {
            ", advisory"
        } else {
            ""
        }
    );
    s.push_str(
        "| scene | structure | workload | speed ratio | build ratio | counters | mismatches |\n",
    );
    s.push_str("|---|---|---|---:|---:|---|---:|\n");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} → {} |",
            r.scene,
            r.structure,
            r.workload,
            ratio_cell(r.speed, true),
            ratio_cell(r.build, false),
            r.counters,
            r.mismatches.0,
            r.mismatches.1
        );
    }
    let regressions = findings
        .iter()
        .filter(|f| f.severity == Severity::Regression)
        .count();
    let _ = writeln!(
        s,
        "\n{} regression(s), {} advisory, {} note(s).",
        regressions,
        findings
            .iter()
            .filter(|f| f.severity == Severity::Advisory)
            .count(),
        findings
            .iter()
            .filter(|f| f.severity == Severity::Note)
            .count()
    );
    for f in findings {
        let tag = match f.severity {
            Severity::Regression => "REGRESSION",
            Severity::Advisory => "advisory",
            Severity::Note => "note",
        };
        let _ = writeln!(s, "- **{tag}**: {}", f.what);
    }
    s
}
