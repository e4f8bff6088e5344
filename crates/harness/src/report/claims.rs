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
