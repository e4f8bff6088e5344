//! The page's "Claims" section: each claim of the report, its verdict, the rule and the figures
//! it rests on.

use super::page::escape;
use crate::report::claims::Verdict;
use crate::report::run::Report;
use std::fmt::Write as _;

/// Writes the claims table; nothing when the report decides no claim.
pub(crate) fn claims_section(s: &mut String, report: &Report) {
    if report.claims.is_empty() {
        return;
    }
    s.push_str(
        "<h2 id=\"claims\">Claims</h2>\n<table class=\"claims\"><tr><th class=\"l\">claim</th>\
         <th class=\"l\">verdict</th><th class=\"l\">rule</th><th class=\"l\">figures</th></tr>\n",
    );
    for c in &report.claims {
        let class = match c.verdict {
            Verdict::Holds => "holds",
            Verdict::DoesNotHold => "bad",
            Verdict::NotMeasured => "note",
        };
        let _ = writeln!(
            s,
            "<tr><td class=\"l\">{}</td><td class=\"l {class}\">{}</td><td class=\"l\">{}</td>\
             <td class=\"l\">{}</td></tr>",
            escape(&c.statement),
            c.verdict.text(),
            escape(&c.rule),
            c.figures
                .iter()
                .map(|f| escape(f))
                .collect::<Vec<_>>()
                .join("<br>")
        );
    }
    s.push_str("</table>\n");
}
