//! Timing findings: a ratio's change written as a slowdown, the significance test on its
//! interval, and the geometric means over the scenes that gate at `max_slowdown` (see the
//! parent module for the policy).

use super::{CompareOptions, Finding, Severity};
use crate::report::interval::Interval;
use crate::report::run::{Report, throughput_unit};

/// A ratio to the reference with its interval, when it has one.
type Figure = (f64, Option<Interval>);

/// A timing ratio's change between the reports, written one way everywhere: as a slowdown,
/// the relative rise in time per query (or per build) against the reference, positive when the
/// new report is slower.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Change {
    pub base: f64,
    pub new: f64,
    pub slowdown: f64,
    /// The slowdown's range when both ratios have confidence intervals: from the most
    /// favourable ends to the least.
    pub range: Option<(f64, f64)>,
    /// The lower coverage of the two intervals.
    pub level: Option<f64>,
}

/// The least coverage an interval needs to decide significance.
pub const MIN_LEVEL: f64 = 0.9;

impl Change {
    /// `higher_is_better`: a throughput ratio (else a build time ratio).
    pub fn new(
        (base, base_interval): (f64, Option<Interval>),
        (new, new_interval): (f64, Option<Interval>),
        higher_is_better: bool,
    ) -> Change {
        let slow = |b: f64, n: f64| {
            if higher_is_better {
                b / n - 1.0
            } else {
                n / b - 1.0
            }
        };
        let range = base_interval.zip(new_interval).map(|(bi, ni)| {
            if higher_is_better {
                (slow(bi.lo, ni.hi), slow(bi.hi, ni.lo))
            } else {
                (slow(bi.hi, ni.lo), slow(bi.lo, ni.hi))
            }
        });
        Change {
            base,
            new,
            slowdown: slow(base, new),
            range,
            level: base_interval
                .zip(new_interval)
                .map(|(b, n)| b.level.min(n.level)),
        }
    }

    /// "12.5 % slower", "3.0 % faster" or "same".
    pub fn words(&self) -> String {
        words(self.slowdown)
    }
}

fn words(slowdown: f64) -> String {
    if slowdown.abs() < 0.0005 {
        "same".into()
    } else if slowdown > 0.0 {
        format!("{:.1} % slower", slowdown * 100.0)
    } else {
        format!("{:.1} % faster", -slowdown * 100.0)
    }
}

/// Whether a structure's timing ratio is Embree against Embree: an Embree entry that traces ray
/// by ray, as the Embree reference does, differs from it only in Embree's own build settings
/// (quality, robust mode), so no raybench code lies between the two sides of the ratio and a
/// shift is the machine's. Such ratios are reported, never gated. The stream and packet entries
/// stay gated: they batch the rays in raybench's wrapper.
fn embree_against_itself(structure: &str, params: &serde_json::Value, reference: &str) -> bool {
    let embree = |name: &str| name.starts_with("embree-");
    let batched = ["coherent_stream", "coherent_packet16"]
        .iter()
        .any(|k| params.get(k).and_then(serde_json::Value::as_bool) == Some(true));
    embree(structure) && embree(reference) && !batched
}

/// Whose timing ratio a finding is about.
#[derive(Clone, Copy)]
pub(super) struct Subject<'a> {
    pub structure: &'a str,
    /// Embree against Embree ([`embree_against_itself`]): advisory whatever its size.
    pub embree_only: bool,
}

impl<'a> Subject<'a> {
    pub(super) fn new(structure: &'a str, params: &serde_json::Value, reference: &str) -> Self {
        Subject {
            structure,
            embree_only: embree_against_itself(structure, params, reference),
        }
    }
}

pub(super) fn timing_finding(
    at: &str,
    what: &str,
    change: &Change,
    threshold: f64,
    subject: Subject,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    if change.slowdown <= opts.max_slowdown.min(threshold) {
        return;
    }
    let (b, n) = (change.base, change.new);
    let limit = format!("threshold {:.0} %", threshold * 100.0);
    let (severity, why) = match (change.range, change.level) {
        _ if change.slowdown <= threshold => (
            Severity::Advisory,
            format!("within the {limit} for a single scene; gated by the geometric mean"),
        ),
        (Some((lo, hi)), Some(level)) if level < MIN_LEVEL => (
            Severity::Advisory,
            format!(
                "not tested: its intervals cover {:.1} %, below the {:.0} % a test needs \
                 (more rounds); the change may be {} to {}",
                level * 100.0,
                MIN_LEVEL * 100.0,
                words(lo),
                words(hi)
            ),
        ),
        (Some((lo, hi)), _) if lo <= threshold => (
            Severity::Advisory,
            format!(
                "not significant: the interval of the change, {} to {}, reaches the {limit}",
                words(lo),
                words(hi)
            ),
        ),
        (Some((lo, hi)), _) => (
            regression_or_advisory(opts),
            format!(
                "significant: the interval of the change, {} to {}, is beyond the {limit}",
                words(lo),
                words(hi)
            ),
        ),
        (None, _) => (
            regression_or_advisory(opts),
            format!("{limit}; no confidence intervals in these reports: a point test"),
        ),
    };
    let (severity, why) = if subject.embree_only && severity == Severity::Regression {
        (
            Severity::Advisory,
            format!("{why}; Embree against Embree, not gated: no raybench code differs"),
        )
    } else {
        (severity, why)
    };
    findings.push(Finding {
        severity,
        at: at.to_string(),
        what: format!("{at}: {what} {b:.3} -> {n:.3}: {} ({why})", change.words()),
        timing_of: Some(subject.structure.to_string()),
    });
}

/// Every structure × workload's geometric mean over the scenes both reports ran it on (two or
/// more), gated at `max_slowdown`; the interval is the geometric means of the scenes' interval
/// ends, wider than the mean's own when the scenes' errors are independent (conservative).
pub(super) fn compare_geomeans(
    base: &Report,
    new: &Report,
    opts: &CompareOptions,
    findings: &mut Vec<Finding>,
) {
    let mut keys = std::collections::BTreeSet::new();
    for r in base
        .results
        .iter()
        .filter(|r| r.structure != base.run.reference)
    {
        for w in &r.workloads {
            keys.insert((r.structure.clone(), w.workload.clone()));
        }
        keys.insert((r.structure.clone(), String::new()));
    }
    for (structure, workload) in keys {
        // (ratio, interval) per scene, base then new; `workload` empty: the build.
        let figure = |r: &Report, scene: &str| -> Option<(f64, Option<Interval>)> {
            let e = r
                .results
                .iter()
                .find(|e| e.scene == scene && e.structure == structure)?;
            if workload.is_empty() {
                return Some((e.build_ratio_to_reference?, e.build_ratio_interval));
            }
            let w = e.workloads.iter().find(|w| w.workload == workload)?;
            Some((w.speedup_vs_reference?, w.speedup_interval))
        };
        let pairs: Vec<_> = base
            .results
            .iter()
            .filter(|e| e.structure == structure)
            .filter_map(|e| Some((figure(base, &e.scene)?, figure(new, &e.scene)?)))
            .filter(|((b, _), (n, _))| *b > 0.0 && *n > 0.0)
            .collect();
        if pairs.len() < 2 {
            continue;
        }
        let mean = |side: &dyn Fn(&(Figure, Figure)) -> Figure| {
            let figures: Vec<(f64, Option<Interval>)> = pairs.iter().map(side).collect();
            let gm = |xs: &mut dyn Iterator<Item = f64>| {
                let (sum, k) = xs.fold((0.0, 0), |(s, k), x| (s + x.ln(), k + 1));
                (sum / k as f64).exp()
            };
            let ratio = gm(&mut figures.iter().map(|f| f.0));
            let intervals: Option<Vec<Interval>> = figures.iter().map(|f| f.1).collect();
            let interval = intervals
                .filter(|v| v.iter().all(|i| i.lo > 0.0))
                .map(|v| Interval {
                    lo: gm(&mut v.iter().map(|i| i.lo)),
                    hi: gm(&mut v.iter().map(|i| i.hi)),
                    level: v.iter().map(|i| i.level).fold(1.0, f64::min),
                });
            (ratio, interval)
        };
        let b = mean(&|p| p.0);
        let n = mean(&|p| p.1);
        let build = workload.is_empty();
        let change = Change::new(b, n, !build);
        let at = format!(
            "{structure} / {} (geometric mean over {} scenes)",
            if build { "build" } else { &workload },
            pairs.len()
        );
        let what = if build {
            "build time ratio".to_string()
        } else {
            format!("{} ratio", throughput_unit(&workload))
        };
        let params = base
            .results
            .iter()
            .find(|e| e.structure == structure)
            .map_or(&serde_json::Value::Null, |e| &e.params);
        let subject = Subject::new(&structure, params, &base.run.reference);
        timing_finding(
            &at,
            &what,
            &change,
            opts.max_slowdown,
            subject,
            opts,
            findings,
        );
    }
}

fn regression_or_advisory(opts: &CompareOptions) -> Severity {
    if opts.timing_advisory {
        Severity::Advisory
    } else {
        Severity::Regression
    }
}
