//! What `raybench compare` prints, in three formats: Markdown for people and pull-request
//! comments (the verdict first, then the findings, then the rows, bounded to fit a comment),
//! JSON for scripts, and JUnit XML for CI test views. Every format writes a change the same
//! way ([`Change`]: a slowdown, "12.5 % slower").

use crate::report::compare::{Change, CompareOptions, Comparison, Finding, Severity};
use crate::report::run::{Report, ResultEntry, WorkloadResult};
use serde::Serialize;
use std::fmt::Write as _;

/// A pull-request comment holds 65,536 characters; the Markdown stays under this.
pub const MARKDOWN_LIMIT: usize = 60_000;

/// One table row: scene, structure, workload and the figures side by side.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub structure: String,
    pub workload: String,
    /// The throughput ratio's change (absent for the reference and when either lacks it).
    pub speed: Option<Change>,
    /// The build time ratio's change.
    pub build: Option<Change>,
    /// `same`, `CHANGED`, `not comparable`, or `-` for a structure without counters.
    pub counters: &'static str,
    pub mismatches: (u64, u64),
    /// Whether anything in the row changed: counters, mismatches, or a timing ratio by more
    /// than the threshold either way.
    pub changed: bool,
}

impl Row {
    fn label(&self) -> String {
        format!("{} / {} / {}", self.scene, self.structure, self.workload)
    }

    /// The larger slowdown of the row's two ratios, for ordering rows worst first.
    fn worst(&self) -> f64 {
        let s = |c: &Option<Change>| c.map_or(f64::NEG_INFINITY, |c| c.slowdown);
        s(&self.speed).max(s(&self.build))
    }
}

pub(crate) fn row(
    be: &ResultEntry,
    ne: &ResultEntry,
    bw: &WorkloadResult,
    nw: &WorkloadResult,
    comparable: bool,
    opts: &CompareOptions,
) -> Row {
    let is_reference = bw.agreement.reference == be.structure;
    let speed = bw
        .speedup_vs_reference
        .zip(nw.speedup_vs_reference)
        .filter(|&(b, n)| !is_reference && b > 0.0 && n > 0.0)
        .map(|(b, n)| Change::new((b, bw.speedup_interval), (n, nw.speedup_interval), true));
    let build = be
        .build_ratio_to_reference
        .zip(ne.build_ratio_to_reference)
        .filter(|&(b, n)| !is_reference && b > 0.0 && n > 0.0)
        .map(|(b, n)| {
            let (bi, ni) = (be.build_ratio_interval, ne.build_ratio_interval);
            Change::new((b, bi), (n, ni), false)
        });
    let counters = match (&bw.counters_total, comparable) {
        (None, _) => "-",
        (_, false) => "not comparable",
        (Some(_), true) if bw.counters_total == nw.counters_total => "same",
        _ => "CHANGED",
    };
    let mismatches = (
        bw.agreement.counts.mismatch + bw.agreement.counted_path_differs,
        nw.agreement.counts.mismatch + nw.agreement.counted_path_differs,
    );
    let moved = |c: &Option<Change>| c.is_some_and(|c| c.slowdown.abs() > opts.max_slowdown);
    Row {
        scene: be.scene.clone(),
        structure: be.structure.clone(),
        workload: bw.workload.clone(),
        changed: counters == "CHANGED"
            || mismatches.0 != mismatches.1
            || moved(&speed)
            || moved(&build),
        speed,
        build,
        counters,
        mismatches,
    }
}

fn change_cell(c: &Option<Change>) -> String {
    match c {
        Some(c) => format!("{:.3} → {:.3} ({})", c.base, c.new, c.words()),
        None => "-".into(),
    }
}

/// How the Markdown is cut down.
#[derive(Clone, Copy, Debug)]
pub struct MarkdownLimits {
    /// Rows shown, worst first (all of them with `usize::MAX`).
    pub max_rows: usize,
    /// Findings shown per severity.
    pub max_findings: usize,
    /// Only rows where something changed.
    pub only_changed: bool,
}

fn verdict(c: &Comparison) -> String {
    let count = |s: Severity| c.findings.iter().filter(|f| f.severity == s).count();
    let (r, a, n) = (
        count(Severity::Regression),
        count(Severity::Advisory),
        count(Severity::Note),
    );
    if r > 0 {
        format!("FAIL: {r} regression(s), {a} advisory, {n} note(s)")
    } else {
        format!("PASS: no regression, {a} advisory, {n} note(s)")
    }
}

pub fn markdown(
    base: &Report,
    new: &Report,
    c: &Comparison,
    opts: &CompareOptions,
    limits: &MarkdownLimits,
    full_table: Option<&str>,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## raybench compare: {}\n", verdict(c));
    let _ = writeln!(
        s,
        "base: {} ({}), new: {} ({}). Ratios are to `{}` in the same run; a change is written \
         as a slowdown (time per query or per build, relative to the reference). Timing \
         thresholds: {:.0} % for a structure × workload's geometric mean over the scenes, \
         {:.0} % for one scene{}; significance-tested where both reports carry confidence \
         intervals.\n",
        base.header.environment.git_revision,
        base.header.environment.timestamp,
        new.header.environment.git_revision,
        new.header.environment.timestamp,
        new.run.reference,
        opts.max_slowdown * 100.0,
        opts.max_scene_slowdown * 100.0,
        if opts.timing_advisory {
            ", advisory"
        } else {
            ""
        }
    );
    for severity in [Severity::Regression, Severity::Advisory, Severity::Note] {
        let of: Vec<&Finding> = c
            .findings
            .iter()
            .filter(|f| f.severity == severity)
            .collect();
        let tag = match severity {
            Severity::Regression => "REGRESSION",
            Severity::Advisory => "advisory",
            Severity::Note => "note",
        };
        for f in of.iter().take(limits.max_findings) {
            let _ = writeln!(s, "- **{tag}**: {}", f.what);
        }
        if of.len() > limits.max_findings {
            let _ = writeln!(
                s,
                "- … and {} more {tag} finding(s) (`--format json` lists them all)",
                of.len() - limits.max_findings
            );
        }
    }
    let mut rows: Vec<&Row> = c
        .rows
        .iter()
        .filter(|r| r.changed || !limits.only_changed)
        .collect();
    rows.sort_by(|a, b| b.worst().total_cmp(&a.worst()));
    let shown = rows.len().min(limits.max_rows);
    let _ = writeln!(
        s,
        "\n{} of {} rows{}, worst first{}:\n",
        shown,
        c.rows.len(),
        if limits.only_changed {
            " (changed only)"
        } else {
            ""
        },
        full_table.map_or(String::new(), |p| format!("; every row in `{p}`"))
    );
    table(&mut s, &rows[..shown]);
    if s.len() > MARKDOWN_LIMIT {
        let mut cut = MARKDOWN_LIMIT;
        while !s.is_char_boundary(cut) {
            cut -= 1;
        }
        s.truncate(cut);
        s.push_str(
            "\n\n… cut to fit a pull-request comment; `--full-table FILE` writes every row.\n",
        );
    }
    s
}

/// Every row, unbounded, for `--full-table`.
pub fn full_table(c: &Comparison) -> String {
    let mut s = String::new();
    let rows: Vec<&Row> = c.rows.iter().collect();
    table(&mut s, &rows);
    s
}

fn table(s: &mut String, rows: &[&Row]) {
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
            change_cell(&r.speed),
            change_cell(&r.build),
            r.counters,
            r.mismatches.0,
            r.mismatches.1
        );
    }
}

#[derive(Serialize)]
struct JsonFinding<'a> {
    severity: &'static str,
    at: &'a str,
    what: &'a str,
    /// The structure whose timing ratio the finding is about, for timing findings.
    timing_of: Option<&'a str>,
}

fn severity_name(s: Severity) -> &'static str {
    match s {
        Severity::Regression => "regression",
        Severity::Advisory => "advisory",
        Severity::Note => "note",
    }
}

/// The whole comparison as JSON: the verdict, every finding and every row (only the changed
/// ones with `only_changed`).
pub fn json(c: &Comparison, opts: &CompareOptions, only_changed: bool) -> String {
    let findings: Vec<JsonFinding> = c
        .findings
        .iter()
        .map(|f| JsonFinding {
            severity: severity_name(f.severity),
            at: &f.at,
            what: &f.what,
            timing_of: f.timing_of.as_deref(),
        })
        .collect();
    let rows: Vec<&Row> = c
        .rows
        .iter()
        .filter(|r| r.changed || !only_changed)
        .collect();
    let value = serde_json::json!({
        "verdict": if c.regressions() > 0 { "fail" } else { "pass" },
        "regressions": c.regressions(),
        "max_slowdown": opts.max_slowdown,
        "timing_advisory": opts.timing_advisory,
        "findings": findings,
        "rows": rows,
    });
    serde_json::to_string_pretty(&value).unwrap_or_default() + "\n"
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// JUnit XML: one test case per row (failed by the regressions about it or its scene and
/// structure), and one for the findings about the reports as a whole.
pub fn junit(c: &Comparison) -> String {
    let mut cases = String::new();
    let mut failures = 0;
    let mut claimed = vec![false; c.findings.len()];
    let mut case = |name: &str, class: &str, of: Vec<&Finding>, cases: &mut String| {
        let _ = write!(
            cases,
            "    <testcase classname=\"{}\" name=\"{}\"",
            xml(class),
            xml(name)
        );
        if of.is_empty() {
            cases.push_str("/>\n");
            return;
        }
        failures += 1;
        let text: Vec<&str> = of.iter().map(|f| f.what.as_str()).collect();
        let _ = write!(
            cases,
            ">\n      <failure message=\"{}\">{}</failure>\n    </testcase>\n",
            xml(text[0]),
            xml(&text.join("\n"))
        );
    };
    for r in &c.rows {
        let label = r.label();
        let entry = format!("{} / {}", r.scene, r.structure);
        let mut of = Vec::new();
        for (i, f) in c.findings.iter().enumerate() {
            let about = f.at == label || (f.at == entry && r.workload == first_workload(c, r));
            if f.severity == Severity::Regression && about {
                claimed[i] = true;
                of.push(f);
            }
        }
        case(&r.workload, &entry, of, &mut cases);
    }
    let rest: Vec<&Finding> = c
        .findings
        .iter()
        .zip(&claimed)
        .filter(|(f, done)| f.severity == Severity::Regression && !**done)
        .map(|(f, _)| f)
        .collect();
    case(
        "the reports as a whole",
        "raybench compare",
        rest,
        &mut cases,
    );
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n  <testsuite name=\"raybench \
         compare\" tests=\"{}\" failures=\"{failures}\">\n{cases}  </testsuite>\n</testsuites>\n",
        c.rows.len() + 1
    )
}

/// The first workload row of a scene and structure: where its build-level findings go.
fn first_workload<'a>(c: &'a Comparison, r: &Row) -> &'a str {
    c.rows
        .iter()
        .find(|x| x.scene == r.scene && x.structure == r.structure)
        .map_or("", |x| x.workload.as_str())
}
