//! What `raybench watertight` prints: the cases, then misses per structure and case next to
//! Embree's bar for robust mode.

use crate::report::watertight::{EMBREE_ROBUST_BAR, WatertightReport};
use std::fmt::Write;

/// The table `raybench watertight` prints.
pub fn watertight_table(report: &WatertightReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Rays from outside aimed exactly at interior edges (2 in 3) and vertices (1 in 3), each a \
         segment ending a quarter past the aimed point and confirmed in f64 to cross the mesh: a \
         miss is a crack."
    );
    let _ = writeln!(
        out,
        "Embree's own bar for robust mode is a miss rate <= {EMBREE_ROBUST_BAR:.0e} for random \
         rays from inside its sphere (watertight_triangles); rays aimed at edges are far harder.\n"
    );
    let _ = writeln!(
        out,
        "{:<16} {:<42} {:>9} {:>9} {:>9} {:>8}",
        "case", "mesh", "triangles", "edge", "vertex", "dropped"
    );
    for c in &report.cases {
        let _ = writeln!(
            out,
            "{:<16} {:<42} {:>9} {:>9} {:>9} {:>8}",
            c.case.name,
            format!("{} + {:?}", c.case.spec, c.case.shift),
            c.triangles,
            c.edge_rays,
            c.vertex_rays,
            c.dropped
        );
    }
    let _ = write!(out, "\n{:<22}", "misses / rays");
    for c in &report.cases {
        let _ = write!(out, " {:>15}", c.case.name);
    }
    let _ = writeln!(
        out,
        " {:>15} {:>10} {:>9}  vs 2e-5",
        "at vertices", "miss rate", "upper95"
    );
    for t in &report.totals {
        let _ = write!(out, "{:<22}", t.structure);
        for c in &report.cases {
            let cell = report
                .results
                .iter()
                .find(|r| r.structure == t.structure && r.case == c.case.name)
                .map_or("-".to_string(), |r| format!("{}/{}", r.misses, r.rays));
            let _ = write!(out, " {cell:>15}");
        }
        let _ = writeln!(
            out,
            " {:>15} {:>10.1e} {:>9.1e}  {}",
            format!("{}/{}", t.vertex_misses, t.vertex_rays),
            t.miss_rate,
            t.upper95,
            t.judgement()
        );
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}
