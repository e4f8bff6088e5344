//! `charts.html` (every chart across the scenes) and `details.html` (every figure of the
//! report as tables: all results, agreement per class, exponents, notes and errors, the
//! environment).

use super::environment::environment;
use super::names::scene_names;
use super::page::{Current, Site, escape, figure, figure_id};
use super::tables::{agreement_table, exponents_table, notes, results_table};
use std::fmt::Write as _;

pub(crate) fn charts_page(site: &Site) -> String {
    let mut s = String::new();
    site.open(&mut s, &format!("{}: charts", site.title), Current::Charts);
    let charts: Vec<_> = site.charts.iter().filter(|c| c.scene.is_none()).collect();
    let _ = writeln!(
        s,
        "<p class=\"note\">One colour per structure in every chart; hover a bar, a point or a \
         label for its value or full name. Bars and points carry the fastest and slowest run \
         as an error bar where the report has them. Each scene's break-even chart is on its \
         page.</p>"
    );
    if charts.is_empty() {
        s.push_str("<p>The report has no figure to chart.</p>\n");
    } else {
        // Twenty-odd charts are many screens: a list of them first, each a link to its figure.
        s.push_str("<p class=\"toc\">On this page: ");
        for (i, c) in charts.iter().enumerate() {
            if i > 0 {
                s.push_str(" · ");
            }
            let _ = write!(
                s,
                "<a href=\"#{}\" title=\"{}\">{}</a>",
                escape(&figure_id(c)),
                escape(&c.caption),
                escape(short(&c.caption))
            );
        }
        s.push_str("</p>\n");
    }
    for c in charts {
        figure(&mut s, c);
    }
    site.close(&mut s);
    s
}

pub(crate) fn details_page(site: &Site) -> String {
    let report = site.report;
    let mut s = String::new();
    site.open(
        &mut s,
        &format!("{}: all results", site.title),
        Current::Details,
    );
    s.push_str(
        "<p class=\"toc\">On this page: <a href=\"#results\">Results</a> · <a \
         href=\"#agreement\">Agreement</a>",
    );
    if site.exponents.is_some() {
        s.push_str(" · <a href=\"#exponents\">Scaling exponents</a>");
    }
    if !report.notes.is_empty() || !report.errors.is_empty() {
        s.push_str(" · <a href=\"#notes\">Notes and errors</a>");
    }
    s.push_str(" · <a href=\"#environment\">Environment</a></p>\n");
    let scenes = scene_names(report);
    s.push_str(
        "<h2 id=\"results\">Results</h2>\n<p class=\"note\">One row per scene × structure: \
         medians, with the ratio to the reference in parentheses; hover a time for the fastest \
         and slowest run. Click a header to sort.</p>\n",
    );
    results_table(&mut s, report, &scenes);
    s.push_str(
        "<h2 id=\"agreement\">Agreement</h2>\n<p class=\"note\">Every query of every scene and \
         workload, by validation class against the reference.</p>\n",
    );
    agreement_table(&mut s, report, &scenes);
    if let Some(e) = site.exponents {
        exponents_table(&mut s, e);
    }
    notes(&mut s, report);
    environment(&mut s, report);
    site.close(&mut s);
    s
}

/// A caption's first clause, for the list of charts: "Throughput on `primary` (median …"
/// → "Throughput on `primary`".
fn short(caption: &str) -> &str {
    let end = [" (", ", ", ": ", " in the same run"]
        .iter()
        .filter_map(|p| caption.find(p))
        .min()
        .unwrap_or(caption.len());
    caption[..end].trim()
}
