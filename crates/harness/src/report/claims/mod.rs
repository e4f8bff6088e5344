//! The claims a report checks: each a sentence from the literature, the rule that decides it
//! on this run's data, the figures the rule read and the verdict. Computed when a run's report
//! is assembled (see `crate::claims`) and stored in `report.json`, so a reader of the JSON
//! sees the same verdicts as the page.

use serde::{Deserialize, Serialize};

/// What this run's data says about a claim.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Holds,
    DoesNotHold,
    /// The run lacks the scenes, structures or workloads the rule needs.
    NotMeasured,
}

impl Verdict {
    pub fn text(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::DoesNotHold => "does not hold",
            Verdict::NotMeasured => "not measured in this run",
        }
    }
}

/// One claim and its verdict on one report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Claim {
    /// Stable short name, also the chart's file name (`charts/claim-<id>.svg`).
    pub id: String,
    /// The claim in one sentence.
    pub statement: String,
    /// The rule that decides it, in words, with its thresholds.
    pub rule: String,
    pub verdict: Verdict,
    /// The figures the rule read, one line each (empty when not measured).
    pub figures: Vec<String>,
    /// Why the claim is not measured, or what the data shows when it does not hold.
    pub note: Option<String>,
}

mod data;
mod grids;
mod pairs;
mod scaling;

use data::Data;

/// What a claim's chart draws, independent of how it is drawn: lines against a numeric x
/// (sizes, ratios), or bars per scene.
#[derive(Clone, Debug)]
pub enum ClaimChart {
    Lines {
        title: String,
        x_desc: String,
        y_desc: String,
        log_x: bool,
        /// (structure or quantity, points (x, y)).
        series: Vec<(String, Vec<(f64, f64)>)>,
        /// Theory curves: (label, points).
        references: Vec<(String, Vec<(f64, f64)>)>,
    },
    Bars {
        title: String,
        y_desc: String,
        /// Scene names.
        groups: Vec<String>,
        /// (name, one value per group).
        series: Vec<(String, Vec<Option<f64>>)>,
        log_y: bool,
    },
}

/// A claim with the chart of the figures it rests on.
#[derive(Clone, Debug)]
pub struct Evaluated {
    pub claim: Claim,
    pub chart: Option<ClaimChart>,
}

/// Every claim, decided on `report`'s data, in the order the page lists them.
pub fn evaluate(report: &Report) -> Vec<Evaluated> {
    let d = Data { report };
    vec![
        scaling::bvh_log_n(d),
        scaling::grid_cube_root(d),
        scaling::bruteforce_linear(d),
        grids::stadium_collapse(d),
        pairs::binned_sah(d),
        pairs::front_to_back(d),
        pairs::kd_early_exit(d),
        grids::best_resolution(d),
    ]
}

/// The claims to show for `report`: those stored in it, or else decided now (a report written
/// before claims were stored).
pub fn of_report(report: &Report) -> Vec<Claim> {
    if report.claims.is_empty() {
        evaluate(report).into_iter().map(|e| e.claim).collect()
    } else {
        report.claims.clone()
    }
}

use crate::report::run::Report;

impl Claim {
    fn new(id: &str, statement: &str, rule: String) -> Claim {
        Claim {
            id: id.into(),
            statement: statement.into(),
            rule,
            verdict: Verdict::NotMeasured,
            figures: Vec::new(),
            note: None,
        }
    }

    /// Not measured, saying what the rule needs.
    fn lacks(mut self, what: &str) -> Evaluated {
        self.verdict = Verdict::NotMeasured;
        self.note = Some(format!("this run lacks {what}"));
        Evaluated {
            claim: self,
            chart: None,
        }
    }

    fn decided(mut self, holds: bool, figures: Vec<String>, chart: ClaimChart) -> Evaluated {
        self.verdict = if holds {
            Verdict::Holds
        } else {
            Verdict::DoesNotHold
        };
        self.figures = figures;
        Evaluated {
            claim: self,
            chart: Some(chart),
        }
    }
}
