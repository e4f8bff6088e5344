//! `raybench compare BASE.json NEW.json`: what changed between two reports, and whether it is a
//! regression (the Markdown table for CI logs is drawn by [`crate::output::compare_table`]).
//!
//! Three kinds of figure, gated differently:
//! * **correctness** — mismatches (plus counted-path disagreements) per scene × structure ×
//!   workload: any rise fails, on any machine;
//! * **deterministic figures** — counters per query, SAH cost, nodes, leaves, references, depth:
//!   the same seed gives the same numbers on every machine and thread count, so any change
//!   fails (it is a change of algorithm, and the baseline must be regenerated on purpose);
//! * **timing** — only as ratios to the reference measured in the same run (build time ratio,
//!   Mrays/s ratio), which cancels most of the machine; a ratio worse by more than
//!   `max_slowdown` fails unless timing is advisory (CI shares its machine).
//!
//! Entries in the base that the new report lacks fail too (a structure that stopped building is
//! not "no regression"); entries only in the new report are listed as new.

use super::run::{Report, ResultEntry, WorkloadResult, is_point_workload, throughput_unit};
use crate::output::compare_table::{markdown, row};
use std::collections::BTreeMap;

/// How to judge timing ratios.
#[derive(Clone, Copy, Debug)]
pub struct CompareOptions {
    /// A ratio to the reference worse by more than this fraction is a slowdown (0.10 = 10 %).
    pub max_slowdown: f64,
    /// Print slowdowns but do not fail on them.
    pub timing_advisory: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            max_slowdown: 0.10,
            timing_advisory: false,
        }
    }
}

/// What kind of problem a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Fails the comparison.
    Regression,
    /// A slowdown beyond the threshold with timing advisory.
    Advisory,
    /// Worth knowing (different machine, new entries, improvements).
    Note,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub severity: Severity,
    pub what: String,
}

/// The result of a comparison: the Markdown to print and the findings.
#[derive(Debug)]
pub struct Comparison {
    pub markdown: String,
    pub findings: Vec<Finding>,
}

impl Comparison {
    pub fn regressions(&self) -> usize {
        self.findings
            .iter()
            .filter(|f| f.severity == Severity::Regression)
            .count()
    }
}

type Key = (String, String);

fn keyed(report: &Report) -> BTreeMap<Key, &ResultEntry> {
    report
        .results
        .iter()
        .map(|r| ((r.scene.clone(), r.structure.clone()), r))
        .collect()
}

/// Every scene × structure, and scene × structure × workload, a report lists more than once.
/// A real run never makes one (its lists are checked for duplicates), but a report edited or
/// merged by hand can, and keying it would keep one copy and silently drop the other.
pub fn duplicate_entries(report: &Report) -> Vec<String> {
    let mut seen = std::collections::BTreeSet::new();
    let mut twice = Vec::new();
    for r in &report.results {
        if !seen.insert((r.scene.as_str(), r.structure.as_str(), "")) {
            twice.push(format!("{} / {}", r.scene, r.structure));
        }
        for w in &r.workloads {
            if !seen.insert((r.scene.as_str(), r.structure.as_str(), w.workload.as_str())) {
                twice.push(format!("{} / {} / {}", r.scene, r.structure, w.workload));
            }
        }
    }
    twice
}

pub fn compare(base: &Report, new: &Report, opts: &CompareOptions) -> Comparison {
    let mut findings = Vec::new();
    for (which, report) in [("base", base), ("new", new)] {
        for twice in duplicate_entries(report) {
            findings.push(Finding {
                severity: Severity::Regression,
                what: format!(
                    "the {which} report lists {twice} more than once: a report with duplicate \
                     entries cannot be compared (one copy would hide the other)"
                ),
            });
        }
    }
    let comparable = environment_warnings(base, new, &mut findings);
    for e in &new.errors {
        findings.push(Finding {
            severity: Severity::Regression,
            what: format!("the new report has an error: {e}"),
        });
    }
    // Shadow, diffuse and Whitted rays are generated from the reference's hits: with another
    // Embree build or ISA they may differ by an ulp, and so may the counters they produce.
    let same_embree = base.header.environment.embree.version
        == new.header.environment.embree.version
        && base.header.environment.embree.isa == new.header.environment.embree.isa;
    let (b, n) = (keyed(base), keyed(new));
    let mut rows = Vec::new();
    for (key, be) in &b {
        let Some(ne) = n.get(key) else {
            findings.push(Finding {
                severity: Severity::Regression,
                what: format!(
                    "{} / {}: in the base, missing from the new report",
                    key.0, key.1
                ),
            });
            continue;
        };
        if comparable {
            compare_build_stats(be, ne, &mut findings);
        }
        compare_build_time(be, ne, opts, &mut findings);
        for bw in &be.workloads {
            let Some(nw) = ne.workloads.iter().find(|w| w.workload == bw.workload) else {
                findings.push(Finding {
                    severity: Severity::Regression,
                    what: format!(
                        "{} / {} / {}: workload missing from the new report",
                        key.0, key.1, bw.workload
                    ),
                });
                continue;
            };
            let label = format!("{} / {} / {}", key.0, key.1, bw.workload);
            let is_reference = key.1 == new.run.reference;
            // Query points, like primary and random rays, depend on the scene and seed only.
            let independent_rays =
                matches!(bw.workload.as_str(), "primary" | "random") || bw.point_query;
            let gate_counters = comparable && (same_embree || independent_rays);
            compare_workload(
                &label,
                bw,
                nw,
                gate_counters,
                is_reference,
                opts,
                &mut findings,
            );
            rows.push(row(be, ne, bw, nw, comparable));
        }
    }
    for key in n.keys().filter(|k| !b.contains_key(*k)) {
        findings.push(Finding {
            severity: Severity::Note,
            what: format!("{} / {}: new in this report (no baseline)", key.0, key.1),
        });
    }
    findings.sort_by_key(|f| f.severity);
    let markdown = markdown(base, new, &rows, &findings, opts);
    Comparison { markdown, findings }
}

/// Warns about different machines and settings; returns whether deterministic figures are
/// comparable (same seed, rays, workloads, suite and reference).
fn environment_warnings(base: &Report, new: &Report, findings: &mut Vec<Finding>) -> bool {
    let (be, ne) = (&base.header.environment, &new.header.environment);
    let machine = [
        ("CPU", be.cpu_model.clone(), ne.cpu_model.clone()),
        ("cores", be.cores.to_string(), ne.cores.to_string()),
        ("threads", be.threads.to_string(), ne.threads.to_string()),
        (
            "Embree",
            be.embree.version.clone(),
            ne.embree.version.clone(),
        ),
        ("Embree ISA", be.embree.isa.clone(), ne.embree.isa.clone()),
        ("rustc", be.rustc.clone(), ne.rustc.clone()),
        ("profile", be.profile.clone(), ne.profile.clone()),
        ("MXCSR", be.mxcsr.clone(), ne.mxcsr.clone()),
    ];
    for (what, b, n) in machine {
        if b != n {
            findings.push(Finding {
                severity: Severity::Note,
                what: format!(
                    "WARNING: different environments ({what}: base `{b}`, new `{n}`): timing ratios \
                     are less comparable"
                ),
            });
        }
    }
    let (br, nr) = (&base.run, &new.run);
    let mut settings = vec![
        ("seed", br.seed.to_string(), nr.seed.to_string()),
        ("rays", br.rays.to_string(), nr.rays.to_string()),
        ("reference", br.reference.clone(), nr.reference.clone()),
    ];
    // A base without point workloads says nothing about the point count.
    if ran_points(base) {
        settings.push(("points", br.points.to_string(), nr.points.to_string()));
    }
    let mut comparable = workloads_comparable(&br.workloads, &nr.workloads, findings);
    for (what, b, n) in settings {
        if b != n {
            comparable = false;
            findings.push(Finding {
                severity: Severity::Regression,
                what: format!(
                    "different run settings ({what}: base `{b}`, new `{n}`): deterministic figures \
                     cannot be compared; regenerate the baseline with the same settings"
                ),
            });
        }
    }
    comparable
}

fn ran_points(report: &Report) -> bool {
    report.run.workloads.iter().any(|w| is_point_workload(w))
}

/// A workload the base ran and the new report lacks makes the figures incomparable (as any
/// other changed setting); workloads only the new report has are new, not a regression (so a
/// baseline from before point workloads still gates the ray workloads it has).
fn workloads_comparable(base: &[String], new: &[String], findings: &mut Vec<Finding>) -> bool {
    let dropped: Vec<&str> = base
        .iter()
        .filter(|w| !new.contains(w))
        .map(String::as_str)
        .collect();
    let added: Vec<&str> = new
        .iter()
        .filter(|w| !base.contains(w))
        .map(String::as_str)
        .collect();
    if !added.is_empty() {
        findings.push(Finding {
            severity: Severity::Note,
            what: format!("new workloads (no baseline): {}", added.join(",")),
        });
    }
    if dropped.is_empty() {
        return true;
    }
    findings.push(Finding {
        severity: Severity::Regression,
        what: format!(
            "different run settings (workloads: base `{}`, new `{}`): deterministic figures \
             cannot be compared; regenerate the baseline with the same settings",
            base.join(","),
            new.join(",")
        ),
    });
    false
}

fn compare_build_stats(b: &ResultEntry, n: &ResultEntry, findings: &mut Vec<Finding>) {
    let (bs, ns) = (&b.build_stats, &n.build_stats);
    let figures: [(&str, Option<f64>, Option<f64>); 5] = [
        ("nodes", Some(bs.nodes as f64), Some(ns.nodes as f64)),
        ("leaves", Some(bs.leaves as f64), Some(ns.leaves as f64)),
        ("refs", Some(bs.refs as f64), Some(ns.refs as f64)),
        (
            "max_depth",
            Some(bs.max_depth as f64),
            Some(ns.max_depth as f64),
        ),
        ("sah_cost", bs.sah_cost, ns.sah_cost),
    ];
    for (what, x, y) in figures {
        if x != y {
            findings.push(Finding {
                severity: Severity::Regression,
                what: format!(
                    "{} / {}: {what} changed from {} to {} (deterministic)",
                    b.scene,
                    b.structure,
                    show(x),
                    show(y)
                ),
            });
        }
    }
}

fn show(x: Option<f64>) -> String {
    x.map_or("-".into(), |v| format!("{v}"))
}

fn compare_build_time(
    b: &ResultEntry,
    n: &ResultEntry,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    // Lower is better: new / base - 1 is the slowdown.
    if let (Some(x), Some(y)) = (b.build_ratio_to_reference, n.build_ratio_to_reference)
        && b.structure != reference_name(b)
        && x > 0.0
    {
        timing_finding(
            &format!("{} / {}: build time ratio", b.scene, b.structure),
            x,
            y,
            y / x - 1.0,
            opts,
            findings,
        );
    }
}

fn reference_name(e: &ResultEntry) -> String {
    e.workloads
        .first()
        .map(|w| w.agreement.reference.clone())
        .unwrap_or_default()
}

fn compare_workload(
    label: &str,
    b: &WorkloadResult,
    n: &WorkloadResult,
    gate_counters: bool,
    is_reference: bool,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    let bad = |w: &WorkloadResult| w.agreement.counts.mismatch + w.agreement.counted_path_differs;
    if bad(n) > bad(b) {
        findings.push(Finding {
            severity: Severity::Regression,
            what: format!("{label}: mismatches rose from {} to {}", bad(b), bad(n)),
        });
    }
    if gate_counters && b.counters_total != n.counters_total {
        findings.push(Finding {
            severity: Severity::Regression,
            what: format!(
                "{label}: counters changed (deterministic): {} -> {}",
                counters_text(b),
                counters_text(n)
            ),
        });
    }
    // Higher is better: base / new - 1 is the slowdown.
    if let (Some(x), Some(y)) = (b.speedup_vs_reference, n.speedup_vs_reference)
        && !is_reference
    {
        timing_finding(
            &format!("{label}: {} ratio", throughput_unit(&b.workload)),
            x,
            y,
            x / y - 1.0,
            opts,
            findings,
        );
    }
}

fn counters_text(w: &WorkloadResult) -> String {
    match &w.counters_per_query {
        None => "none".into(),
        Some(c) => format!(
            "nodes {:.3}, leaves {:.3}, prim tests {:.3}, cells {:.3}, mailbox skips {:.3}, jumps {:.3} per {}",
            c.nodes,
            c.leaves,
            c.prim_tests,
            c.cells,
            c.mailbox_skips,
            c.jumps,
            if w.point_query { "query" } else { "ray" }
        ),
    }
}

fn timing_finding(
    label: &str,
    base: f64,
    new: f64,
    slowdown: f64,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    if slowdown > opts.max_slowdown {
        findings.push(Finding {
            severity: if opts.timing_advisory {
                Severity::Advisory
            } else {
                Severity::Regression
            },
            what: format!(
                "{label} {base:.3} -> {new:.3}: {:.1} % slower (threshold {:.0} %)",
                slowdown * 100.0,
                opts.max_slowdown * 100.0
            ),
        });
    }
}
