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
//!   Mrays/s ratio), which cancels most of the machine. A change is written one way everywhere,
//!   as a slowdown: how much longer a query (or the build) takes relative to the reference,
//!   `base / new - 1` for throughput ratios and `new / base - 1` for build ratios. Timing is
//!   gated at two levels. A structure × workload's geometric mean over the scenes both reports
//!   ran fails beyond `max_slowdown`; one scene's figure fails only beyond the looser
//!   `max_scene_slowdown`, because a run shifts single figures as a whole (the placement of a
//!   structure's arrays in memory differs from run to run, and no round inside the run can see
//!   it: three unchanged reruns of the `ci` suite moved single figures by up to 22 % with
//!   narrow intervals, while the geometric means stayed within a few percent). Either way,
//!   when both reports carry confidence intervals for the ratios (per-round samples, see
//!   `report/interval.rs`) a slowdown must be significant: the most favourable end of its
//!   interval still beyond the threshold, with intervals of at least [`MIN_LEVEL`] coverage
//!   (three builds give 75 %: their changes are advisory). Reports without samples fall back
//!   to the medians alone, as a point test. Timing fails unless advisory. A ratio of Embree
//!   against Embree, a single-ray preset against the reference, is always advisory (see
//!   `timing::embree_against_itself`).
//!
//! When every regression is a timing slowdown, [`Comparison::timing_only`] names the
//! structures concerned, so that a script can time them again before failing
//! (`scripts/ci-gate`): a shared machine can slow one structure for one run.
//!
//! Entries in the base that the new report lacks fail too (a structure that stopped building is
//! not "no regression"), unless the comparison is of a subset (`subset`): then they are "not
//! run" notes. Entries only in the new report are listed as new.

mod timing;

pub use timing::{Change, MIN_LEVEL};

use super::run::{Report, ResultEntry, WorkloadResult, is_point_workload, throughput_unit};
use crate::output::compare_table::{Row, row};
use std::collections::BTreeMap;
use timing::{Subject, compare_geomeans, timing_finding};

/// How to judge timing ratios.
#[derive(Clone, Copy, Debug)]
pub struct CompareOptions {
    /// A structure × workload's geometric-mean ratio to the reference worse by more than this
    /// fraction is a slowdown (0.10 = 10 %).
    pub max_slowdown: f64,
    /// The same for one scene's ratio.
    pub max_scene_slowdown: f64,
    /// Print slowdowns but do not fail on them.
    pub timing_advisory: bool,
    /// The new report ran part of the base's scenes, structures or workloads on purpose:
    /// what it lacks is "not run", not a regression.
    pub subset: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            max_slowdown: 0.10,
            max_scene_slowdown: 0.50,
            timing_advisory: false,
            subset: false,
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
    /// What it is about: `scene / structure / workload`, `scene / structure`, or empty for
    /// the reports as a whole.
    pub at: String,
    /// The structure whose timing ratio to the reference this finding is about; `None` for
    /// every other kind of finding.
    pub timing_of: Option<String>,
}

impl Finding {
    fn about(severity: Severity, at: impl Into<String>, what: String) -> Finding {
        Finding {
            severity,
            what,
            at: at.into(),
            timing_of: None,
        }
    }
}

/// The result of a comparison: the rows side by side and the findings (worst first), drawn
/// by [`crate::output::compare_table`].
#[derive(Debug)]
pub struct Comparison {
    pub rows: Vec<Row>,
    pub findings: Vec<Finding>,
}

impl Comparison {
    pub fn regressions(&self) -> usize {
        self.findings
            .iter()
            .filter(|f| f.severity == Severity::Regression)
            .count()
    }

    /// When there are regressions and every one is a timing slowdown: the structures they
    /// concern (sorted, each once). `None` when there is no regression or any is of another
    /// kind (mismatches, counters, missing entries, settings), which no second run can clear.
    pub fn timing_only(&self) -> Option<Vec<String>> {
        let regressions: Vec<&Finding> = self
            .findings
            .iter()
            .filter(|f| f.severity == Severity::Regression)
            .collect();
        if regressions.is_empty() {
            return None;
        }
        let names: Option<std::collections::BTreeSet<String>> =
            regressions.iter().map(|f| f.timing_of.clone()).collect();
        names.map(|n| n.into_iter().collect())
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
            findings.push(Finding::about(
                Severity::Regression,
                twice.clone(),
                format!(
                    "the {which} report lists {twice} more than once: a report with duplicate \
                     entries cannot be compared (one copy would hide the other)"
                ),
            ));
        }
    }
    let comparable = environment_warnings(base, new, opts, &mut findings);
    // Ratios to the reference do not carry between CPUs (docs/usage.md, `compare`).
    let cross_cpu;
    let opts = if other_cpu(base, new) && !opts.timing_advisory {
        findings.push(Finding::about(
            Severity::Note,
            "",
            format!(
                "timing slowdowns are advisory: the base was timed on `{}`, the new report on \
                 `{}`, and a ratio to the reference does not carry between CPUs; correctness \
                 and deterministic figures are gated as always. A baseline made on this CPU \
                 (scripts/update-baseline) gates timing here",
                machine(&base.header.environment),
                machine(&new.header.environment)
            ),
        ));
        cross_cpu = CompareOptions {
            timing_advisory: true,
            ..*opts
        };
        &cross_cpu
    } else {
        opts
    };
    for e in &new.errors {
        findings.push(Finding::about(
            Severity::Regression,
            "",
            format!("the new report has an error: {e}"),
        ));
    }
    // Shadow, diffuse and Whitted rays are generated from the reference's hits: with another
    // Embree build or ISA they may differ by an ulp, and so may the counters they produce.
    let same_embree = base.header.environment.embree.version
        == new.header.environment.embree.version
        && base.header.environment.embree.isa == new.header.environment.embree.isa;
    let (b, n) = (keyed(base), keyed(new));
    let mut rows = Vec::new();
    let mut not_run = 0usize;
    // What the base has and the new report lacks: "not run" with `--subset`, else a regression.
    let mut missing = |at: &str, what: &str, findings: &mut Vec<Finding>| {
        if opts.subset {
            not_run += 1;
        } else {
            findings.push(Finding::about(
                Severity::Regression,
                at,
                format!("{at}: {what}"),
            ));
        }
    };
    for (key, be) in &b {
        let at = format!("{} / {}", key.0, key.1);
        let Some(ne) = n.get(key) else {
            missing(
                &at,
                "in the base, missing from the new report",
                &mut findings,
            );
            continue;
        };
        if comparable {
            compare_build_stats(be, ne, &mut findings);
        }
        compare_build_time(be, ne, opts, &mut findings);
        for bw in &be.workloads {
            let label = format!("{at} / {}", bw.workload);
            let Some(nw) = ne.workloads.iter().find(|w| w.workload == bw.workload) else {
                missing(
                    &label,
                    "workload missing from the new report",
                    &mut findings,
                );
                continue;
            };
            // The reference's own ratio is always 1: not judged.
            let subject = (key.1 != new.run.reference)
                .then(|| Subject::new(&key.1, &be.params, &new.run.reference));
            // Query points, like primary and random rays, depend on the scene and seed only.
            let independent_rays =
                matches!(bw.workload.as_str(), "primary" | "random") || bw.point_query;
            let gate_counters = comparable && (same_embree || independent_rays);
            compare_workload(&label, bw, nw, gate_counters, subject, opts, &mut findings);
            rows.push(row(be, ne, bw, nw, comparable, opts));
        }
    }
    compare_geomeans(base, new, opts, &mut findings);
    if not_run > 0 {
        findings.push(Finding::about(
            Severity::Note,
            "",
            format!(
                "{not_run} entries or workloads of the base were not run in the new report \
                 (compared as a subset)"
            ),
        ));
    }
    for key in n.keys().filter(|k| !b.contains_key(*k)) {
        let at = format!("{} / {}", key.0, key.1);
        findings.push(Finding::about(
            Severity::Note,
            at.clone(),
            format!("{at}: new in this report (no baseline)"),
        ));
    }
    findings.sort_by_key(|f| f.severity);
    Comparison { rows, findings }
}

/// Whether the two reports were timed on different CPUs: another model name, or another set of
/// SIMD features. One model name (`AMD EPYC`) covers CPUs with and without AVX-512, and the
/// kernels picked at run time differ between them (the packet walks need AVX-512, Embree picks
/// its AVX2 or AVX-512 kernels), so a ratio to the reference does not carry from one to the
/// other.
pub fn other_cpu(base: &Report, new: &Report) -> bool {
    let (b, n) = (&base.header.environment, &new.header.environment);
    b.cpu_model != n.cpu_model || b.cpu_flags != n.cpu_flags
}

/// A CPU as the cross-CPU note names it: the model, with its SIMD features.
fn machine(e: &crate::env::Environment) -> String {
    if e.cpu_flags.is_empty() {
        e.cpu_model.clone()
    } else {
        format!("{} ({})", e.cpu_model, e.cpu_flags.join(" "))
    }
}

/// Warns about different machines and settings; returns whether deterministic figures are
/// comparable (same seed, rays, workloads, suite and reference).
fn environment_warnings(
    base: &Report,
    new: &Report,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) -> bool {
    let (be, ne) = (&base.header.environment, &new.header.environment);
    let machine = [
        ("CPU", be.cpu_model.clone(), ne.cpu_model.clone()),
        (
            "SIMD features",
            be.cpu_flags.join(" "),
            ne.cpu_flags.join(" "),
        ),
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
    // Huge pages only where both reports say: older reports lack the field.
    let pages = match (&be.transparent_hugepages, &ne.transparent_hugepages) {
        (Some(b), Some(n)) => Some(("transparent huge pages", b.clone(), n.clone())),
        _ => None,
    };
    for (what, b, n) in machine.into_iter().chain(pages) {
        if b != n {
            findings.push(Finding::about(
                Severity::Note,
                String::new(),
                format!(
                    "WARNING: different environments ({what}: base `{b}`, new `{n}`): timing \
                     ratios are less comparable"
                ),
            ));
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
    let mut comparable = workloads_comparable(&br.workloads, &nr.workloads, opts, findings);
    for (what, b, n) in settings {
        if b != n {
            comparable = false;
            findings.push(Finding::about(
                Severity::Regression,
                String::new(),
                format!(
                    "different run settings ({what}: base `{b}`, new `{n}`): deterministic figures \
                     cannot be compared; regenerate the baseline with the same settings"
                ),
            ));
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
fn workloads_comparable(
    base: &[String],
    new: &[String],
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) -> bool {
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
        findings.push(Finding::about(
            Severity::Note,
            String::new(),
            format!("new workloads (no baseline): {}", added.join(",")),
        ));
    }
    // A subset runs fewer workloads on purpose; the ones it ran still compare.
    if dropped.is_empty() || opts.subset {
        return true;
    }
    findings.push(Finding::about(
        Severity::Regression,
        String::new(),
        format!(
            "different run settings (workloads: base `{}`, new `{}`): deterministic figures \
             cannot be compared; regenerate the baseline with the same settings",
            base.join(","),
            new.join(",")
        ),
    ));
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
            findings.push(Finding::about(
                Severity::Regression,
                format!("{} / {}", b.scene, b.structure),
                format!(
                    "{} / {}: {what} changed from {} to {} (deterministic)",
                    b.scene,
                    b.structure,
                    show(x),
                    show(y)
                ),
            ));
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
    if let (Some(x), Some(y)) = (b.build_ratio_to_reference, n.build_ratio_to_reference)
        && b.structure != reference_name(b)
        && x > 0.0
    {
        let at = format!("{} / {}", b.scene, b.structure);
        let change = Change::new(
            (x, b.build_ratio_interval),
            (y, n.build_ratio_interval),
            false,
        );
        timing_finding(
            &at,
            "build time ratio",
            &change,
            opts.max_scene_slowdown,
            Subject::new(&b.structure, &b.params, &reference_name(b)),
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
    subject: Option<Subject>,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    let bad = |w: &WorkloadResult| w.agreement.counts.mismatch + w.agreement.counted_path_differs;
    if bad(n) > bad(b) {
        findings.push(Finding::about(
            Severity::Regression,
            label.to_string(),
            format!("{label}: mismatches rose from {} to {}", bad(b), bad(n)),
        ));
    }
    if gate_counters && b.counters_total != n.counters_total {
        findings.push(Finding::about(
            Severity::Regression,
            label.to_string(),
            format!(
                "{label}: counters changed (deterministic): {} -> {}",
                counters_text(b),
                counters_text(n)
            ),
        ));
    }
    if let (Some(x), Some(y)) = (b.speedup_vs_reference, n.speedup_vs_reference)
        && let Some(subject) = subject
        && y > 0.0
    {
        let change = Change::new((x, b.speedup_interval), (y, n.speedup_interval), true);
        let what = format!("{} ratio", throughput_unit(&b.workload));
        timing_finding(
            label,
            &what,
            &change,
            opts.max_scene_slowdown,
            subject,
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
