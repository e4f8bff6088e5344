//! How cost grows with the triangle count N, read along a scene family measured at several
//! sizes: a BVH like log N, a uniform grid like N^1/3, brute force like N. Each is decided by
//! the exponent b of a least-squares fit `∝ N^b` on log–log axes (with its 95 % interval).

use super::data::{Data, Family, Measure, fit, series_text};
use super::{Claim, ClaimChart, Evaluated};

/// The structure (first of `candidates` with a size family) and its workload and family.
fn find<'a>(
    d: Data,
    candidates: &[&'a str],
    workloads: &[&'a str],
    min_span: f64,
) -> Option<(&'a str, &'a str, Family)> {
    candidates.iter().find_map(|&st| {
        workloads
            .iter()
            .find_map(|&wl| Some((st, wl, d.size_family(st, wl, min_span)?)))
    })
}

/// `y0 · f(N) / f(N0)` at each N: a theory curve through the first measured point.
fn theory(points: &[(f64, f64)], f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    let Some(&(n0, y0)) = points.first() else {
        return Vec::new();
    };
    points
        .iter()
        .map(|&(n, _)| (n, y0 * f(n) / f(n0)))
        .collect()
}

fn log_n(n: f64) -> f64 {
    n.max(2.0).log2()
}

/// The lines chart of one measure against N, with log N, N^1/3 and N through its first point.
fn chart(title: String, y_desc: &str, label: &str, points: &[(f64, f64)]) -> ClaimChart {
    ClaimChart::Lines {
        title,
        x_desc: "triangles N".into(),
        y_desc: y_desc.into(),
        log_x: true,
        series: vec![(label.into(), points.to_vec())],
        references: vec![
            ("∝ log N".into(), theory(points, log_n)),
            ("∝ N^1/3".into(), theory(points, f64::cbrt)),
            ("∝ N".into(), theory(points, |n| n)),
        ],
    }
}

/// The exponent line of a figure: "b = 0.11 ± 0.02".
fn exponent(points: &[(f64, f64)]) -> String {
    fit(points).map_or("b: fewer than 3 points".into(), |f| {
        format!("b = {}", f.text())
    })
}

pub(super) fn bvh_log_n(d: Data) -> Evaluated {
    let c = Claim::new(
        "bvh-log-n",
        "A BVH's work per ray grows like log N: refining the same scene tenfold adds only a few nodes to each ray's walk.",
        "the binary BVH's (bvh-binned, else bvh8-binned) nodes visited per primary ray (else \
         random ray), fitted as ∝ N^b over a scene family at 3 or more sizes spanning 16× or \
         more: holds when b ≤ 0.2 (log N over 1k–262k is b ≈ 0.1; N^1/3 would be 0.33)"
            .into(),
    );
    let Some((st, wl, fam)) = find(
        d,
        &["bvh-binned", "bvh8-binned"],
        &["primary", "random"],
        16.0,
    ) else {
        return c.lacks("a BVH measured on one scene family at 3 or more sizes spanning 16×");
    };
    let nodes = d.along(&fam, st, wl, Measure::Nodes);
    let Some(b) = fit(&nodes) else {
        return c.lacks("three sizes with counted nodes");
    };
    let time = d.along(&fam, st, wl, Measure::NsPerQuery);
    let figures = vec![
        format!(
            "{st} nodes per {wl} ray on {}: {}; {}",
            fam.name,
            series_text(&nodes),
            exponent(&nodes)
        ),
        format!(
            "{st} ns per {wl} ray: {}; {}",
            series_text(&time),
            exponent(&time)
        ),
    ];
    let title = format!("{st}: nodes per {wl} ray against N ({})", fam.name);
    c.decided(
        b.exponent <= 0.2,
        figures,
        chart(title, "nodes per ray", st, &nodes),
    )
}

pub(super) fn grid_cube_root(d: Data) -> Evaluated {
    let c = Claim::new(
        "grid-cube-root",
        "A uniform grid's work per ray grows like N^1/3: with a cell per triangle, a ray crosses a cube root of the cells.",
        "the uniform grid's (grid, λ = 1) cells stepped per primary ray (else random ray), \
         fitted as ∝ N^b over a scene family at 3 or more sizes spanning 16× or more: holds when \
         |b − 1/3| ≤ 0.1"
            .into(),
    );
    let Some((st, wl, fam)) = find(d, &["grid"], &["primary", "random"], 16.0) else {
        return c.lacks("the grid measured on one scene family at 3 or more sizes spanning 16×");
    };
    let cells = d.along(&fam, st, wl, Measure::Cells);
    let Some(b) = fit(&cells) else {
        return c.lacks("three sizes with counted cells");
    };
    let tests = d.along(&fam, st, wl, Measure::TriangleTests);
    let time = d.along(&fam, st, wl, Measure::NsPerQuery);
    let figures = vec![
        format!(
            "{st} cells per {wl} ray on {}: {}; {}",
            fam.name,
            series_text(&cells),
            exponent(&cells)
        ),
        format!(
            "triangle tests per ray: {}; {}",
            series_text(&tests),
            exponent(&tests)
        ),
        format!("ns per ray: {}; {}", series_text(&time), exponent(&time)),
    ];
    let title = format!("{st}: cells stepped per {wl} ray against N ({})", fam.name);
    c.decided(
        (b.exponent - 1.0 / 3.0).abs() <= 0.1,
        figures,
        chart(title, "cells per ray", st, &cells),
    )
}

pub(super) fn bruteforce_linear(d: Data) -> Evaluated {
    let c = Claim::new(
        "bruteforce-linear",
        "Brute force costs time in proportion to N: every ray tests every triangle.",
        "bruteforce's time per random ray (else primary ray), fitted as ∝ N^b over a scene \
         family at 3 or more sizes spanning 4× or more (suites run brute force only up to 20,000 \
         triangles): holds when |b − 1| ≤ 0.15"
            .into(),
    );
    let Some((st, wl, fam)) = find(d, &["bruteforce"], &["random", "primary"], 4.0) else {
        return c.lacks("bruteforce measured on one scene family at 3 or more sizes spanning 4×");
    };
    let time = d.along(&fam, st, wl, Measure::NsPerQuery);
    let Some(b) = fit(&time) else {
        return c.lacks("three sizes with a measured throughput");
    };
    let figures = vec![format!(
        "{st} ns per {wl} ray on {}: {}; {}",
        fam.name,
        series_text(&time),
        exponent(&time)
    )];
    let title = format!("{st}: time per {wl} ray against N ({})", fam.name);
    c.decided(
        (b.exponent - 1.0).abs() <= 0.15,
        figures,
        chart(title, "ns per ray", st, &time),
    )
}
