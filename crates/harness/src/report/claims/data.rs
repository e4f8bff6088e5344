//! What the claims read from a report: one structure's figures on one scene and workload, the
//! scene families that come in several sizes, and the sentences that quote them.

use crate::output::render::fit::{PowerFit, fit_power};
use crate::output::render::ticks::tick_label;
use crate::report::run::{CountersPerQuery, Report, ResultEntry};

/// A report as the claims query it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Data<'a> {
    pub report: &'a Report,
}

/// Which number of a result a claim reads.
#[derive(Clone, Copy, Debug)]
pub(super) enum Measure {
    /// Interior nodes + leaves per query (counted pass).
    Nodes,
    Leaves,
    TriangleTests,
    Cells,
    /// Nanoseconds per query, from the median throughput.
    NsPerQuery,
}

impl Measure {
    fn of_counters(self, c: &CountersPerQuery) -> Option<f64> {
        Some(match self {
            Measure::Nodes => c.nodes + c.leaves,
            Measure::Leaves => c.leaves,
            Measure::TriangleTests => c.prim_tests,
            Measure::Cells => c.cells,
            Measure::NsPerQuery => return None,
        })
    }
}

/// A scene family (one generator or file) at several sizes: `(scene, triangles traced)`,
/// smallest first.
#[derive(Clone, Debug)]
pub(super) struct Family {
    pub name: String,
    pub scenes: Vec<(String, f64)>,
}

/// The generator (or file) a scene comes from: `teapot:triangles=4000` → `teapot`.
pub(super) fn family_of(scene: &str) -> &str {
    scene.split(':').next().unwrap_or(scene)
}

impl<'a> Data<'a> {
    pub fn result(&self, scene: &str, structure: &str) -> Option<&'a ResultEntry> {
        self.report
            .results
            .iter()
            .find(|r| r.scene == scene && r.structure == structure)
    }

    /// `measure` of `structure` on `scene` and `workload`; `None` when not run or not
    /// counted (or a throughput of 0).
    pub fn get(&self, scene: &str, structure: &str, workload: &str, m: Measure) -> Option<f64> {
        let w = self
            .result(scene, structure)?
            .workloads
            .iter()
            .find(|w| w.workload == workload)?;
        match m {
            Measure::NsPerQuery => {
                let t = w.mqueries_per_s.median;
                (t.is_finite() && t > 0.0).then(|| 1e3 / t)
            }
            _ => m.of_counters(w.counters_per_query.as_ref()?),
        }
    }

    /// Scenes in report order on which every one of `structures` ran `workload`.
    pub fn common_scenes(&self, structures: &[&str], workload: &str) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for r in &self.report.results {
            if out.contains(&r.scene) {
                continue;
            }
            let all = structures.iter().all(|st| {
                self.result(&r.scene, st)
                    .is_some_and(|e| e.workloads.iter().any(|w| w.workload == workload))
            });
            if all {
                out.push(r.scene.clone());
            }
        }
        out
    }

    /// The family with the most distinct sizes on which `structure` ran `workload`: three
    /// sizes or more, the largest at least `min_span` times the smallest. Scaling is read
    /// along one kind of geometry only.
    pub fn size_family(&self, structure: &str, workload: &str, min_span: f64) -> Option<Family> {
        let mut best: Option<Family> = None;
        for scene in self.common_scenes(&[structure], workload) {
            let name = family_of(&scene);
            if best.as_ref().is_some_and(|b| b.name == name) {
                continue;
            }
            let mut scenes: Vec<(String, f64)> = Vec::new();
            for s in self.common_scenes(&[structure], workload) {
                let n = self.result(&s, structure).map_or(0, |r| r.triangles.traced) as f64;
                if family_of(&s) == name && n > 0.0 && !scenes.iter().any(|(_, m)| *m == n) {
                    scenes.push((s, n));
                }
            }
            scenes.sort_by(|a, b| a.1.total_cmp(&b.1));
            let span = scenes.last().map_or(0.0, |l| l.1) / scenes.first().map_or(1.0, |f| f.1);
            if scenes.len() >= 3
                && span >= min_span
                && best.as_ref().is_none_or(|b| scenes.len() > b.scenes.len())
            {
                best = Some(Family {
                    name: name.to_string(),
                    scenes,
                });
            }
        }
        best
    }

    /// `measure` of `structure` along a family, `(N, value)` for the sizes that have it.
    pub fn along(
        &self,
        family: &Family,
        structure: &str,
        workload: &str,
        m: Measure,
    ) -> Vec<(f64, f64)> {
        family
            .scenes
            .iter()
            .filter_map(|(s, n)| Some((*n, self.get(s, structure, workload, m)?)))
            .collect()
    }
}

/// The fit of `points` as `∝ N^b`, when three or more are usable.
pub(super) fn fit(points: &[(f64, f64)]) -> Option<PowerFit> {
    fit_power(points)
}

/// "1k: 12.3, 4k: 14.1, …".
pub(super) fn series_text(points: &[(f64, f64)]) -> String {
    points
        .iter()
        .map(|(n, v)| format!("{}: {}", tick_label(*n), number(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A figure with three significant digits, without exponent notation below a million.
pub(super) fn number(v: f64) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    let a = v.abs();
    if a >= 1e6 {
        tick_label(v)
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}
