//! `index.html`, the summary: the run, the mismatch count, the answer per scene and workload,
//! each structure's geometric means with their spread, the claims, a sweep's exponents, and
//! where everything else is. It grows by one answer row per scene and nothing else, so it
//! stays a few screens tall for suites of a few dozen scenes: every per-scene figure lives on
//! the scene's own page, every chart on the charts page.

use super::page::{CHARTS_FILE, Current, DETAILS_FILE, Site};
use super::tables::{exponents_table, sweep_note};
use std::fmt::Write as _;

pub(crate) fn summary_page(site: &Site) -> String {
    let report = site.report;
    let mut s = String::new();
    site.open(&mut s, &site.title, Current::Summary);
    let mismatches = report.mismatches();
    let checked: u64 = report
        .results
        .iter()
        .flat_map(|r| &r.workloads)
        .map(|w| w.agreement.queries())
        .sum();
    let _ = write!(
        s,
        "<p class=\"{}\">{} mismatches in {} checked rays.",
        if mismatches > 0 { "bad" } else { "note" },
        super::ticks::thousands(mismatches),
        super::ticks::thousands(checked)
    );
    if !report.errors.is_empty() {
        let _ = write!(
            s,
            " <span class=\"bad\">{} error(s): see <a href=\"{DETAILS_FILE}#notes\">notes and \
             errors</a>.</span>",
            report.errors.len()
        );
    }
    s.push_str("</p>\n");
    toc(&mut s, site);
    if let Some(sweep) = site.sweep {
        sweep_note(&mut s, sweep);
    }
    let link = |scene: &str| site.scene_file(scene).map(str::to_string);
    super::answer::answer_section(&mut s, report, &link);
    super::geomeans::geomeans_section(&mut s, report);
    super::claims_section::claims_section(&mut s, report, site.claim_charts);
    if let Some(e) = site.exponents {
        exponents_table(&mut s, e);
    }
    more(&mut s, site);
    site.close(&mut s);
    s
}

/// The sections of this page.
fn toc(s: &mut String, site: &Site) {
    let mut sections = vec![
        ("answer", "The answer"),
        ("geomeans", "Geometric means and their spread"),
    ];
    if !crate::report::claims::of_report(site.report).is_empty() {
        sections.push(("claims", "Claims"));
    }
    if site.exponents.is_some() {
        sections.push(("exponents", "Scaling exponents"));
    }
    sections.push(("more", "Scenes, charts and details"));
    s.push_str("<p class=\"toc\">On this page: ");
    for (i, (id, text)) in sections.iter().enumerate() {
        if i > 0 {
            s.push_str(" · ");
        }
        let _ = write!(s, "<a href=\"#{id}\">{text}</a>");
    }
    s.push_str("</p>\n");
}

/// Where the rest of the report is.
fn more(s: &mut String, site: &Site) {
    let cross_scene = site.charts.iter().filter(|c| c.scene.is_none()).count();
    let _ = writeln!(
        s,
        "<h2 id=\"more\">Scenes, charts and details</h2>\n<ul>\n<li>Each scene's page (its \
         name in the answer table and at the top lead to it): its rows of the results, its \
         break-even chart and its pictures.</li>\n<li><a href=\"{CHARTS_FILE}\">Charts</a>: \
         {cross_scene} chart(s) across the scenes (build time, throughput, ratios, memory, work \
         per query, agreement).</li>\n<li><a href=\"{DETAILS_FILE}\">All results, agreement, \
         environment</a>: every scene × structure, the validation classes, notes and errors, \
         the machine and the settings.</li>\n</ul>"
    );
}
