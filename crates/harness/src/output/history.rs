//! `raybench history`: run reports from several commits, ordered by time, as one static page
//! (a chart per structure × workload) and a Markdown summary a CI job can post.
//!
//! Each chart follows the geometric mean, over the scenes every report has, of the structure's
//! throughput ratio to the reference, with a band from the geometric means of the interval
//! ends (an approximation of the geometric mean's own interval, wider than it when the scenes'
//! errors are independent) and its deterministic work per query (interior nodes plus triangle
//! tests, geometric mean). A report is marked where the structure's counters changed on any
//! scene compared with the report before it (a change of algorithm, or of settings), and where
//! the ratio moved beyond its interval (the two reports' bands do not overlap).

use crate::report::run::{Report, ResultEntry};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::PathBuf;

/// One report on the time line.
#[derive(Debug)]
pub struct Entry {
    pub path: PathBuf,
    pub report: Report,
}

/// One structure × workload over the reports.
#[derive(Debug)]
pub struct Series {
    pub structure: String,
    pub workload: String,
    /// The scenes the figures average over.
    pub scenes: Vec<String>,
    /// One per report (`None` where the report lacks the series or a scene of it).
    pub points: Vec<Option<Point>>,
    /// What happened at which report (index into the reports).
    pub events: Vec<(usize, String)>,
}

#[derive(Clone, Copy, Debug)]
pub struct Point {
    pub ratio: f64,
    /// Geometric means of the interval ends, when every scene has an interval.
    pub band: Option<(f64, f64)>,
    /// Interior nodes plus triangle tests per query (geometric mean), for structures that count.
    pub work: Option<f64>,
}

/// Orders the reports by timestamp, then revision (a stable order for reports of one second).
pub fn order(mut entries: Vec<Entry>) -> Vec<Entry> {
    entries.sort_by(|a, b| {
        let (x, y) = (&a.report.header.environment, &b.report.header.environment);
        x.timestamp
            .cmp(&y.timestamp)
            .then(x.git_revision.cmp(&y.git_revision))
    });
    entries
}

fn geomean(xs: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for x in xs {
        if !(x > 0.0 && x.is_finite()) {
            return None;
        }
        sum += x.ln();
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).exp())
}

fn find<'a>(r: &'a Report, scene: &str, structure: &str) -> Option<&'a ResultEntry> {
    r.results
        .iter()
        .find(|e| e.scene == scene && e.structure == structure)
}

/// Every structure × workload any report has (the reference's ratios are 1 and left out).
pub fn series(entries: &[Entry]) -> Vec<Series> {
    let mut keys = BTreeSet::new();
    for e in entries {
        for r in e
            .report
            .results
            .iter()
            .filter(|r| r.structure != e.report.run.reference)
        {
            for w in &r.workloads {
                keys.insert((r.structure.clone(), w.workload.clone()));
            }
        }
    }
    keys.into_iter()
        .map(|(structure, workload)| one_series(entries, structure, workload))
        .collect()
}

fn one_series(entries: &[Entry], structure: String, workload: String) -> Series {
    // The scenes every report that has the series ran it on.
    let has = |r: &Report, scene: &str| {
        find(r, scene, &structure)
            .is_some_and(|e| e.workloads.iter().any(|w| w.workload == workload))
    };
    let mut scenes: Option<BTreeSet<String>> = None;
    for e in entries {
        let here: BTreeSet<String> = e
            .report
            .results
            .iter()
            .filter(|r| has(&e.report, &r.scene) && r.structure == structure)
            .map(|r| r.scene.clone())
            .collect();
        if here.is_empty() {
            continue;
        }
        scenes = Some(match scenes {
            None => here,
            Some(s) => s.intersection(&here).cloned().collect(),
        });
    }
    let scenes: Vec<String> = scenes.unwrap_or_default().into_iter().collect();
    let points: Vec<Option<Point>> = entries
        .iter()
        .map(|e| point(&e.report, &scenes, &structure, &workload))
        .collect();
    let mut events = Vec::new();
    for i in 1..entries.len() {
        let (a, b) = (&entries[i - 1].report, &entries[i].report);
        let changed: Vec<&str> = scenes
            .iter()
            .filter(|s| {
                let c = |r: &Report| {
                    find(r, s, &structure)
                        .and_then(|e| e.workloads.iter().find(|w| w.workload == workload))
                        .and_then(|w| w.counters_total)
                };
                c(a).is_some() && c(b).is_some() && c(a) != c(b)
            })
            .map(String::as_str)
            .collect();
        if !changed.is_empty() {
            let settings = a.run.seed != b.run.seed || a.run.rays != b.run.rays;
            // A few names are enough to find the rest in the reports.
            let mut named = changed[..changed.len().min(3)].join(", ");
            if changed.len() > 3 {
                named.push_str(&format!(", and {} more", changed.len() - 3));
            }
            events.push((
                i,
                format!(
                    "counters changed on {} of {} scenes ({named}){}",
                    changed.len(),
                    scenes.len(),
                    if settings {
                        "; the run settings differ too"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if let (Some(p), Some(q)) = (points[i - 1], points[i])
            && let (Some((pl, ph)), Some((ql, qh))) = (p.band, q.band)
            && (ql > ph || qh < pl)
        {
            events.push((
                i,
                format!(
                    "ratio moved beyond its interval: {:.3} [{pl:.3}, {ph:.3}] -> {:.3} [{ql:.3}, {qh:.3}] ({})",
                    p.ratio,
                    q.ratio,
                    if q.ratio > p.ratio { "faster" } else { "slower" }
                ),
            ));
        }
    }
    Series {
        structure,
        workload,
        scenes,
        points,
        events,
    }
}

fn point(r: &Report, scenes: &[String], structure: &str, workload: &str) -> Option<Point> {
    if scenes.is_empty() {
        return None;
    }
    let ws: Vec<_> = scenes
        .iter()
        .map(|s| {
            find(r, s, structure).and_then(|e| e.workloads.iter().find(|w| w.workload == workload))
        })
        .collect::<Option<Vec<_>>>()?;
    let ratio = geomean(
        ws.iter()
            .map(|w| w.speedup_vs_reference.unwrap_or(f64::NAN)),
    )?;
    let band = ws
        .iter()
        .map(|w| w.speedup_interval.map(|i| (i.lo, i.hi)))
        .collect::<Option<Vec<_>>>()
        .and_then(|b| {
            Some((
                geomean(b.iter().map(|x| x.0))?,
                geomean(b.iter().map(|x| x.1))?,
            ))
        });
    let work = ws
        .iter()
        .map(|w| w.counters_per_query.map(|c| c.nodes + c.prim_tests))
        .collect::<Option<Vec<_>>>()
        .and_then(|v| geomean(v.into_iter()));
    Some(Point { ratio, band, work })
}

fn short(rev: &str) -> &str {
    &rev[..rev.len().min(8)]
}

/// The Markdown summary: the reports in order, then every event, at most `max_events` of them.
pub fn markdown(entries: &[Entry], series: &[Series], max_events: usize) -> String {
    let mut s = String::from("## raybench history\n\n");
    let events: usize = series.iter().map(|x| x.events.len()).sum();
    let _ = writeln!(
        s,
        "{} reports, {} structure × workload series, {events} event(s): counters that changed \
         and ratios that moved beyond their interval.\n",
        entries.len(),
        series.len()
    );
    s.push_str("| # | date | revision | suite | threads | mismatches | file |\n|---:|---|---|---|---:|---:|---|\n");
    for (i, e) in entries.iter().enumerate() {
        let env = &e.report.header.environment;
        let _ = writeln!(
            s,
            "| {} | {} | `{}` | {} | {} | {} | {} |",
            i + 1,
            env.timestamp,
            short(&env.git_revision),
            e.report.run.suite.as_deref().unwrap_or("-"),
            e.report.run.threads,
            e.report.mismatches(),
            e.path.display()
        );
    }
    s.push('\n');
    let mut listed = 0;
    for x in series {
        for (i, what) in &x.events {
            if listed == max_events {
                let _ = writeln!(s, "- … and {} more", events - listed);
                return s;
            }
            let rev = short(&entries[*i].report.header.environment.git_revision);
            let _ = writeln!(
                s,
                "- `{rev}` (#{}) {} / {}: {what}",
                i + 1,
                x.structure,
                x.workload
            );
            listed += 1;
        }
    }
    if events == 0 {
        s.push_str("No counter changed and no ratio moved beyond its interval.\n");
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// One static HTML page: the reports, then a chart per series (ratio line, interval band, red
/// rings at events) with the latest ratio and work per query.
pub fn page(entries: &[Entry], series: &[Series]) -> String {
    let mut s = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>raybench history</title>\
         <style>body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse}\
         td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:middle}\
         .ev{color:#b00;font-size:90%}</style></head><body><h1>raybench history</h1>",
    );
    let _ = write!(
        s,
        "<p>{} reports, oldest first. Each chart: the geometric mean over the scenes every \
         report has of the ratio to the reference (line), its interval band (shaded), red rings \
         where counters changed or the ratio left its interval.</p><ol>",
        entries.len()
    );
    for e in entries {
        let env = &e.report.header.environment;
        let _ = write!(
            s,
            "<li>{} <code>{}</code> {}</li>",
            esc(&env.timestamp),
            esc(short(&env.git_revision)),
            esc(&e.path.display().to_string())
        );
    }
    s.push_str("</ol><table><tr><th>structure</th><th>workload</th><th>ratio over time</th><th>latest</th><th>work / query</th><th>events</th></tr>");
    for x in series {
        let latest = x.points.iter().rev().flatten().next();
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"ev\">{}</td></tr>",
            esc(&x.structure),
            esc(&x.workload),
            chart(x),
            latest.map_or("-".into(), |p| format!("{:.3}", p.ratio)),
            latest
                .and_then(|p| p.work)
                .map_or("-".into(), |w| format!("{w:.2}")),
            x.events
                .iter()
                .map(|(i, what)| format!("#{}: {}", i + 1, esc(what)))
                .collect::<Vec<_>>()
                .join("<br>")
        );
    }
    s.push_str("</table></body></html>\n");
    s
}

/// A 320 × 60 SVG of one series.
fn chart(x: &Series) -> String {
    let (w, h, pad) = (320.0, 60.0, 6.0);
    let vals: Vec<f64> = x
        .points
        .iter()
        .flatten()
        .flat_map(|p| {
            [
                p.ratio,
                p.band.map_or(p.ratio, |b| b.0),
                p.band.map_or(p.ratio, |b| b.1),
            ]
        })
        .collect();
    if vals.is_empty() {
        return "-".into();
    }
    let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = (hi - lo).max(1e-9);
    let n = x.points.len().max(2) as f64 - 1.0;
    let px = |i: usize| pad + (w - 2.0 * pad) * i as f64 / n;
    let py = |v: f64| h - pad - (h - 2.0 * pad) * (v - lo) / span;
    let mut svg =
        format!("<svg width=\"{w}\" height=\"{h}\" xmlns=\"http://www.w3.org/2000/svg\">");
    let banded: Vec<(usize, (f64, f64))> = x
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, p.as_ref()?.band?)))
        .collect();
    if banded.len() > 1 {
        let top: Vec<String> = banded
            .iter()
            .map(|(i, b)| format!("{:.1},{:.1}", px(*i), py(b.1)))
            .collect();
        let bottom: Vec<String> = banded
            .iter()
            .rev()
            .map(|(i, b)| format!("{:.1},{:.1}", px(*i), py(b.0)))
            .collect();
        let _ = write!(
            svg,
            "<polygon points=\"{} {}\" fill=\"#9bd\" fill-opacity=\"0.4\"/>",
            top.join(" "),
            bottom.join(" ")
        );
    }
    let line: Vec<String> = x
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.map(|p| format!("{:.1},{:.1}", px(i), py(p.ratio))))
        .collect();
    let _ = write!(
        svg,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"#246\" stroke-width=\"1.5\"/>",
        line.join(" ")
    );
    for (i, p) in x.points.iter().enumerate() {
        if let Some(p) = p {
            let _ = write!(
                svg,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2\" fill=\"#246\"><title>#{}: {:.3}</title></circle>",
                px(i),
                py(p.ratio),
                i + 1,
                p.ratio
            );
        }
    }
    for (i, _) in &x.events {
        if let Some(p) = x.points[*i] {
            let _ = write!(
                svg,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"5\" fill=\"none\" stroke=\"#b00\" stroke-width=\"1.5\"/>",
                px(*i),
                py(p.ratio)
            );
        }
    }
    let _ = write!(
        svg,
        "<text x=\"{pad}\" y=\"10\" font-size=\"9\" fill=\"#666\">{hi:.3}</text>\
         <text x=\"{pad}\" y=\"{:.0}\" font-size=\"9\" fill=\"#666\">{lo:.3}</text></svg>",
        h - 1.0
    );
    svg
}
