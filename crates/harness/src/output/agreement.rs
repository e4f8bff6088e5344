//! How agreement is stated, wherever raybench states it (the run summary, the verify table):
//! "0 mismatches in n rays (95% upper bound 3/n = …)", never "100 %", always with the counts of
//! every validation class next to it (docs/validation.md, Comparison policy, item 5).

use raybench_accel::classify::VerdictCounts;

/// "0 mismatches in n rays (95% upper bound 3/n = 2.4e-5)", or "k mismatches in n rays".
///
/// With no mismatch among n independent rays, 3/n is the 95 % upper confidence bound on the
/// mismatch rate (the rule of three); it is capped at 1 for n < 3.
pub fn agreement_sentence(counts: &VerdictCounts) -> String {
    agreement_sentence_of(counts, "rays")
}

/// [`agreement_sentence`] counting `what` ("rays", or "queries" for closest points).
pub fn agreement_sentence_of(counts: &VerdictCounts, what: &str) -> String {
    let n = counts.total();
    match counts.mismatch {
        0 if n == 0 => format!("0 mismatches in 0 {what} (nothing was checked)"),
        0 => format!(
            "0 mismatches in {n} {what} (95% upper bound 3/n = {:.1e})",
            (3.0 / n as f64).min(1.0)
        ),
        1 => format!("1 mismatch in {n} {what}"),
        k => format!("{k} mismatches in {n} {what}"),
    }
}

/// Every class with its count, in the order of the validation classes.
pub fn class_counts(c: &VerdictCounts) -> String {
    format!(
        "both_miss {}, exact {}, within_tolerance {}, tie {}, boundary {}, edge_ambiguous {}, mismatch {}",
        c.both_miss, c.exact, c.within_tolerance, c.tie, c.boundary, c.edge_ambiguous, c.mismatch
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sentences_state_the_bound_or_the_count() {
        let mut c = VerdictCounts {
            exact: 99_990,
            both_miss: 10,
            ..Default::default()
        };
        assert_eq!(
            agreement_sentence(&c),
            "0 mismatches in 100000 rays (95% upper bound 3/n = 3.0e-5)"
        );
        c.mismatch = 2;
        assert_eq!(agreement_sentence(&c), "2 mismatches in 100002 rays");
        assert_eq!(
            agreement_sentence(&VerdictCounts {
                exact: 1,
                ..Default::default()
            }),
            "0 mismatches in 1 rays (95% upper bound 3/n = 1.0e0)"
        );
        assert_eq!(
            class_counts(&c),
            "both_miss 10, exact 99990, within_tolerance 0, tie 0, boundary 0, edge_ambiguous 0, mismatch 2"
        );
    }
}
