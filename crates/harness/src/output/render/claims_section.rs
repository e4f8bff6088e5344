//! The page's "Claims" section and the claims' charts: each claim of the report in one
//! sentence, its verdict, the rule and the figures it rests on, and a small picture of its
//! chart linking to the full one (`charts/claim-<id>.svg`).

use super::charts::{self, Bars, Series};
use super::lines::{Line, LineChart, Point, Reference, lines_svg};
use super::names::scene_label;
use super::page::escape;
use super::palette::{PALETTE, Palette};
use super::ticks::tick_label;
use super::{H, W};
use crate::report::claims::{self, ClaimChart, Verdict};
use crate::report::run::Report;
use anyhow::Result;
use std::fmt::Write as _;

/// Dash patterns of the theory curves, one per curve.
const DASHES: [(u32, u32); 4] = [(10, 4), (4, 4), (2, 3), (14, 3)];

/// The file of a claim's chart under the output directory.
pub(crate) fn chart_file(id: &str) -> String {
    format!("charts/claim-{}.svg", super::names::slug(id))
}

/// Every claim chart the report's data supports: (file under the output directory, SVG).
pub(crate) fn claim_charts(report: &Report) -> Result<Vec<(String, String)>> {
    let palette = Palette::for_report(report);
    let mut out = Vec::new();
    for e in claims::evaluate(report) {
        let Some(chart) = e.chart else { continue };
        let svg = match chart {
            ClaimChart::Lines {
                title,
                x_desc,
                y_desc,
                log_x,
                series,
                references,
            } => {
                let lines = series
                    .into_iter()
                    .map(|(name, points)| Line {
                        color: palette.color(&name),
                        marker: palette.marker(&name),
                        points: points
                            .iter()
                            .map(|&(x, y)| Point {
                                x,
                                y,
                                range: None,
                                title: format!("{name}: {} at {}", tick_label(y), tick_label(x)),
                            })
                            .collect(),
                        label: name,
                    })
                    .collect();
                let references = references
                    .into_iter()
                    .zip(DASHES.iter().cycle())
                    .map(|((label, points), &dash)| Reference {
                        label,
                        dash,
                        points,
                    })
                    .collect();
                let chart = LineChart {
                    title,
                    x_desc,
                    y_desc,
                    log_x,
                    ticks: Vec::new(),
                    lines,
                    references,
                    marks: Vec::new(),
                };
                if !chart.has_data() {
                    continue;
                }
                lines_svg(&[chart], W, H)?
            }
            ClaimChart::Bars {
                title,
                y_desc,
                groups,
                series,
                log_y,
            } => {
                let chart = Bars {
                    title,
                    y_desc,
                    groups: groups.iter().map(|g| scene_label(None, g)).collect(),
                    group_titles: groups,
                    series: series
                        .into_iter()
                        .enumerate()
                        .map(|(i, (name, values))| Series {
                            // Structures keep their colours; quantities take the palette's.
                            color: if report.results.iter().any(|r| r.structure == name) {
                                palette.color(&name)
                            } else {
                                PALETTE[i % PALETTE.len()]
                            },
                            name,
                            values,
                            ranges: Vec::new(),
                        })
                        .collect(),
                    log_y,
                };
                if !chart.has_data() {
                    continue;
                }
                charts::bars_svg(&chart, W, H)?
            }
        };
        out.push((chart_file(&e.claim.id), svg));
    }
    Ok(out)
}

/// Writes the claims table; nothing when the report decides no claim. `with_charts`: the
/// chart files of [`claim_charts`] that were written.
pub(crate) fn claims_section(s: &mut String, report: &Report, with_charts: &[String]) {
    let claims = claims::of_report(report);
    if claims.is_empty() {
        return;
    }
    let held = claims
        .iter()
        .filter(|c| c.verdict == Verdict::Holds)
        .count();
    let measured = claims
        .iter()
        .filter(|c| c.verdict != Verdict::NotMeasured)
        .count();
    let _ = writeln!(
        s,
        "<h2 id=\"claims\">Claims</h2>\n<p class=\"note\">What the literature says, decided on \
         this run's data by the rule beside each: {held} of {measured} measured claims hold; \
         {} not measured in this run (<code>raybench run --suite claims</code> measures them \
         all).</p>",
        claims.len() - measured
    );
    s.push_str(
        "<table class=\"claims\"><tr><th class=\"l\">claim</th><th class=\"l\">verdict</th>\
         <th class=\"l\">figures</th><th class=\"l\">chart</th></tr>\n",
    );
    for c in &claims {
        let class = match c.verdict {
            Verdict::Holds => "holds",
            Verdict::DoesNotHold => "bad",
            Verdict::NotMeasured => "note",
        };
        let file = chart_file(&c.id);
        let chart = if with_charts.contains(&file) {
            format!(
                "<a href=\"{f}\"><img class=\"thumb\" src=\"{f}\" alt=\"chart of {id}\" \
                 style=\"width:260px\"></a>",
                f = escape(&file),
                id = escape(&c.id)
            )
        } else {
            "-".into()
        };
        let mut figures: Vec<String> = c.figures.iter().map(|f| escape(f)).collect();
        if let Some(n) = &c.note {
            figures.push(format!("<i>{}</i>", escape(n)));
        }
        let _ = writeln!(
            s,
            "<tr id=\"claim-{id}\"><td class=\"l\"><b>{}</b><br><span class=\"note\">rule: {}</span></td>\
             <td class=\"l {class}\">{}</td><td class=\"l\">{}</td><td>{chart}</td></tr>",
            escape(&c.statement),
            escape(&c.rule),
            c.verdict.text(),
            figures.join("<br>"),
            id = escape(&c.id)
        );
    }
    s.push_str("</table>\n");
}
