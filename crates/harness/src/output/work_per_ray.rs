//! The results page's "Work per ray" table: for every structure that counts its work, per ray
//! workload, the geometric mean over the scenes of the nodes it visits, the triangles it tests
//! and the bytes those visits read.
//!
//! Incoherent rays are bound by memory latency more than by arithmetic, so what a change to a
//! tree's shape or node format does shows up first in how many bytes a ray pulls in. The bytes
//! are an estimate from the counters and the structure's own memory figures: nodes visited ×
//! the mean bytes of an interior node (`memory.nodes` over interior nodes) plus triangles
//! tested × the mean bytes per stored triangle reference (`memory.primitives` over `refs`,
//! padding of partly filled SIMD blocks included). It counts every visit as a fetch, as if
//! nothing stayed in cache, so it compares layouts; it does not predict cache misses.

use super::render::names::structure_names;
use super::results::geometric_mean;
use super::summary::sig;
use crate::report::run::{Report, ResultEntry, is_point_workload};
use std::fmt::Write;

/// Nodes, triangle tests and estimated bytes per ray of one result on one workload.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorkPerRay {
    pub nodes: f64,
    pub prim_tests: f64,
    /// `None` where the structure reports no interior nodes or no stored triangles (grids
    /// step through cells; their bytes per cell are not a node's).
    pub bytes: Option<f64>,
}

/// The work per ray of `r` on `workload`, when the structure counted it.
pub fn work_per_ray(r: &ResultEntry, workload: &str) -> Option<WorkPerRay> {
    let w = r.workloads.iter().find(|w| w.workload == workload)?;
    let c = w.counters_per_query.as_ref()?;
    let interior = r.build_stats.nodes.saturating_sub(r.build_stats.leaves);
    let node_bytes =
        (interior > 0 && r.memory.nodes > 0).then(|| r.memory.nodes as f64 / interior as f64);
    let prim_bytes = (r.build_stats.refs > 0 && r.memory.primitives > 0)
        .then(|| r.memory.primitives as f64 / r.build_stats.refs as f64);
    let bytes = match (node_bytes, prim_bytes) {
        (Some(n), Some(p)) if c.cells == 0.0 => Some(c.nodes * n + c.prim_tests * p),
        _ => None,
    };
    Some(WorkPerRay {
        nodes: c.nodes,
        prim_tests: c.prim_tests,
        bytes,
    })
}

/// Appends the table (nothing when no structure of the run counted its work).
pub fn work_section(s: &mut String, report: &Report) {
    let workloads: Vec<&String> = report
        .run
        .workloads
        .iter()
        .filter(|w| !is_point_workload(w))
        .collect();
    let rows: Vec<(String, Vec<Option<WorkPerRay>>)> = structure_names(report)
        .into_iter()
        .map(|st| {
            let cells = workloads
                .iter()
                .map(|wl| {
                    let per_scene: Vec<WorkPerRay> = report
                        .results
                        .iter()
                        .filter(|r| r.structure == st)
                        .filter_map(|r| work_per_ray(r, wl))
                        .collect();
                    mean_work(&per_scene)
                })
                .collect();
            (st, cells)
        })
        .filter(|(_, cells): &(String, Vec<Option<WorkPerRay>>)| cells.iter().any(Option::is_some))
        .collect();
    if rows.is_empty() {
        return;
    }
    s.push_str(
        "\n## Work per ray\n\nGeometric mean over the scenes of the interior nodes visited, the \
         triangles tested and the bytes those visits read per ray (nodes × mean node bytes + \
         tests × mean bytes per stored triangle, every visit counted as a fetch; see \
         docs/report-format.md), as `nodes · tests · bytes`.\n\n| structure |",
    );
    for w in &workloads {
        let _ = write!(s, " {w} |");
    }
    s.push_str("\n|---|");
    s.push_str(&"---:|".repeat(workloads.len()));
    s.push('\n');
    for (st, cells) in rows {
        let _ = write!(s, "| {st} |");
        for c in cells {
            let text = c.map_or("-".to_string(), |c| {
                format!(
                    "{} · {} · {}",
                    sig(c.nodes),
                    sig(c.prim_tests),
                    c.bytes.map_or("-".to_string(), bytes_text)
                )
            });
            let _ = write!(s, " {text} |");
        }
        s.push('\n');
    }
}

/// Geometric means of each figure over the scenes (a zero leaves its scene out of that figure).
fn mean_work(per_scene: &[WorkPerRay]) -> Option<WorkPerRay> {
    if per_scene.is_empty() {
        return None;
    }
    let or_zero = |v: Option<f64>| v.unwrap_or(0.0);
    let bytes: Vec<f64> = per_scene.iter().filter_map(|w| w.bytes).collect();
    Some(WorkPerRay {
        nodes: or_zero(geometric_mean(per_scene.iter().map(|w| w.nodes))),
        prim_tests: or_zero(geometric_mean(per_scene.iter().map(|w| w.prim_tests))),
        bytes: (bytes.len() == per_scene.len())
            .then(|| geometric_mean(bytes))
            .flatten(),
    })
}

/// Bytes with a k or M suffix, three significant digits.
fn bytes_text(b: f64) -> String {
    if b >= 1e6 {
        format!("{}M", sig(b / 1e6))
    } else if b >= 1e3 {
        format!("{}k", sig(b / 1e3))
    } else {
        sig(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_with_a_suffix() {
        assert_eq!(bytes_text(512.0), "512");
        assert_eq!(bytes_text(6_650.0), "6.65k");
        assert_eq!(bytes_text(2_500_000.0), "2.50M");
    }

    #[test]
    fn a_mean_needs_every_scene_for_bytes() {
        let a = WorkPerRay {
            nodes: 2.0,
            prim_tests: 8.0,
            bytes: Some(100.0),
        };
        let b = WorkPerRay {
            nodes: 8.0,
            prim_tests: 2.0,
            bytes: None,
        };
        let m = mean_work(&[a, b]).unwrap();
        assert!((m.nodes - 4.0).abs() < 1e-12 && (m.prim_tests - 4.0).abs() < 1e-12);
        assert_eq!(
            m.bytes, None,
            "a scene without bytes leaves the mean without them"
        );
        let m = mean_work(&[a, a]).unwrap();
        assert!((m.bytes.unwrap() - 100.0).abs() < 1e-9);
    }
}
