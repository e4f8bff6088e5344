//! What every page of a report's site shares: the head with its style, the navigation (the
//! summary, the charts, the details and every scene's page), the run line, the small sorting
//! script at the end, and HTML escaping.
//!
//! The site is static files: `index.html` (the summary), `scene-<slug>.html` per scene,
//! `charts.html` and `details.html`, all at the top of the output directory so that every page
//! links its pictures as `images/…` and its charts as `charts/…`.

use super::names::{scene_names, scene_slugs};
use super::scaling::Exponents;
use super::sweep::Sweep;
use super::{ChartFile, ScenePictures};
use crate::report::run::Report;
use std::fmt::Write as _;

pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:24px;color:#222;max-width:1300px}\
table{border-collapse:collapse;margin:12px 0;font-size:13px}\
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}\
th{background:#f0f0f0}td.l,th.l{text-align:left}\
table.sortable th{cursor:pointer}th[aria-sort=ascending]::after{content:\" ▲\"}\
th[aria-sort=descending]::after{content:\" ▼\"}\
td small{color:#555}table.geomeans small,td.st{white-space:nowrap}\
figure{margin:18px 0}figcaption{font-size:13px;color:#444}\
img.chart{max-width:100%;border:1px solid #ddd}\
img.px{image-rendering:pixelated;width:240px;border:1px solid #ddd}\
nav{font-size:14px;line-height:1.6;background:#f6f6f6;padding:6px 10px;border:1px solid #ddd}\
nav b{color:#000}td.group{background:#fafafa;font-weight:bold}\
.bad{color:#c00;font-weight:bold}.holds{color:#070;font-weight:bold}.note{color:#555;font-size:13px}";

/// Sorts any `<table class="sortable">` by a clicked header (again: the other way). A cell
/// sorts by the number its text starts with ("1.23 (0.91×)" by 1.23), else by its text; an
/// empty cell or "-" sorts last either way, ties keep their order. Without script the tables
/// read the same, in the report's order.
const SORT_SCRIPT: &str = r#"<script>
document.querySelectorAll("table.sortable").forEach(function (t) {
  t.querySelectorAll("thead th").forEach(function (th, i) {
    th.tabIndex = 0;
    th.title = "sort by this column";
    th.onkeydown = function (e) { if (e.key === "Enter") th.onclick(); };
    th.onclick = function () {
      var up = th.getAttribute("aria-sort") !== "ascending";
      t.querySelectorAll("thead th").forEach(function (h) { h.removeAttribute("aria-sort"); });
      th.setAttribute("aria-sort", up ? "ascending" : "descending");
      var key = function (r) {
        var s = r.cells[i] ? r.cells[i].textContent.trim() : "";
        if (s === "" || s === "-" || s === "–") return null;
        var n = parseFloat(s);
        return isNaN(n) ? s.toLowerCase() : n;
      };
      var body = t.tBodies[0];
      var rows = Array.from(body.rows).map(function (r, k) { return [key(r), k, r]; });
      rows.sort(function (a, b) {
        if (a[0] === null || b[0] === null) return (a[0] === null) - (b[0] === null) || a[1] - b[1];
        var d = typeof a[0] !== typeof b[0] ? (typeof a[0] === "number" ? -1 : 1)
          : a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : 0;
        return (up ? d : -d) || a[1] - b[1];
      });
      rows.forEach(function (r) { body.appendChild(r[2]); });
    };
  });
});
</script>
"#;

/// One page of the site, for the navigation to mark.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Current<'a> {
    Summary,
    Charts,
    Details,
    Scene(&'a str),
}

/// Everything the pages are made from.
pub(crate) struct Site<'a> {
    pub report: &'a Report,
    pub title: String,
    /// Every scene in the report's order, with the file of its page.
    pub scenes: Vec<(String, String)>,
    pub charts: &'a [ChartFile],
    pub pictures: &'a [ScenePictures],
    /// The parameter the report sweeps, if any.
    pub sweep: Option<&'a Sweep>,
    /// Fitted exponents against N, when the scenes grow.
    pub exponents: Option<&'a Exponents>,
    /// The claim charts written (see [`super::claims_section`]).
    pub claim_charts: &'a [String],
}

pub(crate) const SUMMARY_FILE: &str = "index.html";
pub(crate) const CHARTS_FILE: &str = "charts.html";
pub(crate) const DETAILS_FILE: &str = "details.html";

impl<'a> Site<'a> {
    pub fn new(
        report: &'a Report,
        charts: &'a [ChartFile],
        pictures: &'a [ScenePictures],
        sweep: Option<&'a Sweep>,
        exponents: Option<&'a Exponents>,
        claim_charts: &'a [String],
    ) -> Site<'a> {
        let slugs = scene_slugs(report);
        let scenes = scene_names(report)
            .into_iter()
            .map(|name| {
                let file = scene_file(&slugs[&name]);
                (name, file)
            })
            .collect();
        Site {
            report,
            title: match &report.run.suite {
                Some(suite) => format!("raybench: suite {suite}"),
                None => "raybench report".to_string(),
            },
            scenes,
            charts,
            pictures,
            sweep,
            exponents,
            claim_charts,
        }
    }

    /// The page file of `scene`.
    pub fn scene_file(&self, scene: &str) -> Option<&str> {
        self.scenes
            .iter()
            .find(|(name, _)| name == scene)
            .map(|(_, file)| file.as_str())
    }

    /// The document's head, the page's heading, the run line and the navigation.
    pub fn open(&self, s: &mut String, heading: &str, current: Current) {
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width\"><title>{}</title>\
             <style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
            escape(heading),
            escape(heading)
        );
        self.run_line(s);
        self.nav(s, current);
    }

    /// The sorting script and the end of the document.
    pub fn close(&self, s: &mut String) {
        s.push_str(SORT_SCRIPT);
        s.push_str("</body></html>\n");
    }

    fn run_line(&self, s: &mut String) {
        let report = self.report;
        let env = &report.header.environment;
        let _ = writeln!(
            s,
            "<p class=\"note\">{} at revision {}, {} thread(s), seed {}, {} rays per workload; \
             every answer checked against <b>{}</b>.</p>",
            escape(&env.timestamp),
            escape(&env.git_revision),
            report.run.threads,
            report.run.seed,
            report.run.rays,
            escape(&report.run.reference)
        );
    }

    /// Links to every page of the site; the current one in bold instead of a link.
    fn nav(&self, s: &mut String, current: Current) {
        let link = |s: &mut String, here: bool, file: &str, text: &str| {
            if here {
                let _ = write!(s, "<b>{}</b>", escape(text));
            } else {
                let _ = write!(s, "<a href=\"{}\">{}</a>", escape(file), escape(text));
            }
        };
        s.push_str("<nav>");
        link(s, current == Current::Summary, SUMMARY_FILE, "Summary");
        s.push_str(" · ");
        link(s, current == Current::Charts, CHARTS_FILE, "Charts");
        s.push_str(" · ");
        link(
            s,
            current == Current::Details,
            DETAILS_FILE,
            "All results, agreement, environment",
        );
        s.push_str("<br>Scenes: ");
        for (i, (name, file)) in self.scenes.iter().enumerate() {
            if i > 0 {
                s.push_str(" · ");
            }
            link(s, current == Current::Scene(name), file, name);
        }
        s.push_str("</nav>\n");
    }
}

/// The page of the scene with slug `slug`.
pub(crate) fn scene_file(slug: &str) -> String {
    format!("scene-{slug}.html")
}

/// A figure of one chart, as every page shows it, with the chart's file stem as its id.
pub(crate) fn figure(s: &mut String, c: &ChartFile) {
    let _ = writeln!(
        s,
        "<figure id=\"{}\"><img class=\"chart\" src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption>\
         </figure>",
        escape(&figure_id(c)),
        escape(&c.file),
        escape(&c.caption),
        escape(&c.caption)
    );
}

/// `charts/build-ms.svg` → `build-ms`.
pub(crate) fn figure_id(c: &ChartFile) -> String {
    let name = c.file.rsplit('/').next().unwrap_or(&c.file);
    name.strip_suffix(".svg").unwrap_or(name).to_string()
}
