//! Each structure's geometric means against the reference per workload (and for build time and
//! memory), each with its spread: the lowest and highest ratio over the scenes. A mean of 1.0
//! over scenes from 0.5 to 2.0 is a different answer from one where every scene is near 1.0,
//! and the range says so in the units of the mean; its ends name their scenes on hover.

use super::page::escape;
use crate::output::results::{geometric_mean, ratio_text, scene_ratios};
use crate::report::run::Report;
use std::fmt::Write as _;

/// A geometric mean over scenes and the scenes with the lowest and the highest ratio.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Spread {
    pub mean: f64,
    pub scenes: usize,
    pub lowest: (f64, String),
    pub highest: (f64, String),
}

impl Spread {
    /// Over the positive finite `(ratio, scene)` pairs (the values the geometric mean keeps).
    pub fn of(values: impl IntoIterator<Item = (f64, String)>) -> Option<Spread> {
        let values: Vec<(f64, String)> = values
            .into_iter()
            .filter(|(v, _)| v.is_finite() && *v > 0.0)
            .collect();
        let mean = geometric_mean(values.iter().map(|(v, _)| *v))?;
        let lowest = values.iter().min_by(|a, b| a.0.total_cmp(&b.0))?.clone();
        let highest = values.iter().max_by(|a, b| a.0.total_cmp(&b.0))?.clone();
        Some(Spread {
            mean,
            scenes: values.len(),
            lowest,
            highest,
        })
    }

    /// "1.19 0.95–1.40": the mean, then the range in small type (the cell sorts by the mean).
    fn cell(&self) -> String {
        let title = format!(
            "geometric mean over {} scene(s); lowest {} on {}, highest {} on {}",
            self.scenes,
            ratio_text(self.lowest.0),
            self.lowest.1,
            ratio_text(self.highest.0),
            self.highest.1
        );
        let range = if self.scenes > 1 {
            format!(
                " <small>{}–{}</small>",
                ratio_text(self.lowest.0),
                ratio_text(self.highest.0)
            )
        } else {
            String::new()
        };
        format!(
            "<td title=\"{}\">{}{range}</td>",
            escape(&title),
            ratio_text(self.mean)
        )
    }
}

fn cell(s: Option<&Spread>) -> String {
    s.map_or("<td>-</td>".into(), Spread::cell)
}

/// One structure's spreads: per workload of the run, then build time and memory.
pub(crate) struct Row {
    pub structure: String,
    pub workloads: Vec<Option<Spread>>,
    pub build: Option<Spread>,
    pub memory: Option<Spread>,
    pub scenes: usize,
}

/// Every structure but the reference, in the run's order.
pub(crate) fn rows(report: &Report) -> Vec<Row> {
    scene_ratios(report)
        .into_iter()
        .map(|r| Row {
            workloads: r.workloads.into_iter().map(Spread::of).collect(),
            build: Spread::of(r.build),
            memory: Spread::of(r.memory),
            structure: r.structure,
            scenes: r.scenes,
        })
        .collect()
}

/// The table of geometric means with their ranges.
pub(crate) fn geomeans_section(s: &mut String, report: &Report) {
    let rows = rows(report);
    if rows.is_empty() {
        return;
    }
    let _ = write!(
        s,
        "<h2 id=\"geomeans\">Geometric means against {}</h2>\n<p class=\"note\">Per structure, \
         the geometric mean of its ratio to the reference over the scenes it ran on, and below \
         it in small type the spread: the lowest and the highest ratio of any one scene (hover \
         a cell for their scenes). Throughput: higher is faster; build time and memory: lower \
         is better. Click a header to sort.</p>\n<table class=\"sortable geomeans\"><thead><tr>\
         <th class=\"l\">structure</th>",
        escape(&report.run.reference)
    );
    for w in &report.run.workloads {
        let _ = write!(s, "<th>{}</th>", escape(w));
    }
    s.push_str("<th>build</th><th>memory</th><th>scenes</th></tr></thead>\n<tbody>\n");
    for r in rows {
        let _ = write!(s, "<tr><td class=\"l\">{}</td>", escape(&r.structure));
        for w in &r.workloads {
            s.push_str(&cell(w.as_ref()));
        }
        let _ = writeln!(
            s,
            "{}{}<td>{}</td></tr>",
            cell(r.build.as_ref()),
            cell(r.memory.as_ref()),
            r.scenes
        );
    }
    s.push_str("</tbody></table>\n");
}

#[cfg(test)]
mod tests {
    use super::Spread;

    #[test]
    fn the_spread_is_the_lowest_and_highest_positive_ratio() {
        let s = Spread::of([
            (0.5, "a".to_string()),
            (2.0, "b".into()),
            (0.0, "zero".into()),
            (f64::NAN, "nan".into()),
        ])
        .unwrap();
        assert!((s.mean - 1.0).abs() < 1e-12);
        assert_eq!(
            (s.scenes, s.lowest.1.as_str(), s.highest.1.as_str()),
            (2, "a", "b")
        );
        assert!(s.cell().contains(">1.00 <small>0.50–2.00</small></td>"));
        assert_eq!(Spread::of([(0.0, "x".to_string())]), None);
    }
}
