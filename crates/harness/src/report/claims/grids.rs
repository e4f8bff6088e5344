//! The uniform grid's two classic weaknesses: it collapses when the detail sits in a tiny
//! part of a huge scene (the teapot in a stadium), and its resolution has a best value, with
//! too few cells and too many both slower.

use super::data::{Data, Measure, number};
use super::{Claim, ClaimChart, Evaluated};
use crate::output::results::geometric_mean;

/// The teapot-in-stadium scenes that differ only in `size_ratio`: (ratio, scene), largest
/// ratio first. Of several such groups (other parameters or views), the one with the most
/// ratios.
fn stadium_ratios(d: Data, structures: &[&str], workload: &str) -> Vec<(f64, String)> {
    let mut groups: Vec<(String, Vec<(f64, String)>)> = Vec::new();
    for scene in d.common_scenes(structures, workload) {
        let Some(params) = scene.strip_prefix("teapot-in-stadium:") else {
            continue;
        };
        let mut ratio = None;
        let mut rest = Vec::new();
        for kv in params.split(',') {
            match kv.split_once('=') {
                Some(("size_ratio", v)) => ratio = v.trim().parse::<f64>().ok(),
                _ => rest.push(kv.to_string()),
            }
        }
        let Some(ratio) = ratio.filter(|r| r.is_finite() && *r > 0.0) else {
            continue;
        };
        rest.sort();
        let key = rest.join(",");
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, g)) => g.push((ratio, scene)),
            None => groups.push((key, vec![(ratio, scene)])),
        }
    }
    let mut best = groups
        .into_iter()
        .map(|(_, g)| g)
        .max_by_key(|g| g.len())
        .unwrap_or_default();
    best.sort_by(|a, b| b.0.total_cmp(&a.0));
    best
}

pub(super) fn stadium_collapse(d: Data) -> Evaluated {
    let c = Claim::new(
        "grid-stadium-collapse",
        "A uniform grid collapses on the teapot in a stadium as the teapot shrinks, while a BVH and a k-d tree do not.",
        "triangle tests per primary ray from the largest to the smallest teapot/stadium size \
         ratio (at least 1000× apart): holds when the grid's (λ = 1) grow 10× or more and 10× \
         more than both bvh8-binned's (else bvh-binned's) and kd-sah's, and end 100× or more \
         above both trees'. (The grid's own growth is capped: once the teapot fits in one cell, \
         a ray into it tests about all of the teapot's triangles.)"
            .into(),
    );
    let wl = "primary";
    let bvh = ["bvh8-binned", "bvh-binned"]
        .into_iter()
        .find(|b| stadium_ratios(d, &["grid", b, "kd-sah"], wl).len() >= 2);
    let Some(bvh) = bvh else {
        return c.lacks(
            "grid, a BVH and kd-sah on primary rays of teapot-in-stadium at 2 or more size_ratio values",
        );
    };
    let structures = ["grid", bvh, "kd-sah"];
    let ratios = stadium_ratios(d, &structures, wl);
    let (first, last) = (&ratios[0], &ratios[ratios.len() - 1]);
    if first.0 / last.0 < 1000.0 {
        return c.lacks("teapot-in-stadium size ratios 1000× apart");
    }
    let growth = |st: &str| -> Option<f64> {
        let a = d.get(&first.1, st, wl, Measure::TriangleTests)?;
        let b = d.get(&last.1, st, wl, Measure::TriangleTests)?;
        (a > 0.0).then_some(b / a)
    };
    let (Some(g), Some(b), Some(k)) = (growth("grid"), growth(bvh), growth("kd-sah")) else {
        return c.lacks("counted triangle tests for grid, the BVH and kd-sah");
    };
    let at_end = |st: &str| d.get(&last.1, st, wl, Measure::TriangleTests);
    let above_trees = match (at_end("grid"), at_end(bvh), at_end("kd-sah")) {
        (Some(g), Some(b), Some(k)) => g >= 100.0 * b.max(k),
        _ => false,
    };
    let holds = g >= 10.0 && g >= 10.0 * b.max(k) && above_trees;
    let mut figures = Vec::new();
    let mut series = Vec::new();
    for st in structures {
        let points: Vec<(f64, f64)> = ratios
            .iter()
            .filter_map(|(r, s)| Some((*r, d.get(s, st, wl, Measure::TriangleTests)?)))
            .collect();
        figures.push(format!(
            "{st} triangle tests per primary ray: {} (×{} from size ratio {} to {})",
            points
                .iter()
                .map(|(r, v)| format!("{r:e}: {}", number(*v)))
                .collect::<Vec<_>>()
                .join(", "),
            number(growth(st).unwrap_or(f64::NAN)),
            first.0,
            last.0
        ));
        series.push((st.to_string(), points));
    }
    c.decided(
        holds,
        figures,
        ClaimChart::Lines {
            title: "Teapot in a stadium: triangle tests per primary ray against the size ratio"
                .into(),
            x_desc: "teapot width / stadium width".into(),
            y_desc: "triangle tests per ray".into(),
            log_x: true,
            series,
            references: Vec::new(),
        },
    )
}

pub(super) fn best_resolution(d: Data) -> Evaluated {
    let c = Claim::new(
        "grid-best-resolution",
        "A uniform grid has a best resolution: too few cells and too many are both slower.",
        "time per random ray (else primary ray) of the grid at λ = 1/8, 1 and 8 cells per \
         triangle (grid-coarse, grid, grid-fine), geometric mean over the scene family measured \
         at 3 or more sizes (evenly detailed scenes; the teapot in a stadium is the claim \
         above), else over every scene where all three ran: holds when λ = 1/8 and λ = 8 are \
         both 1.1× slower than λ = 1 or more"
            .into(),
    );
    let structures = ["grid-coarse", "grid", "grid-fine"];
    let Some(wl) = ["random", "primary"]
        .into_iter()
        .find(|wl| !d.common_scenes(&structures, wl).is_empty())
    else {
        return c.lacks("grid-coarse, grid and grid-fine on the same scenes");
    };
    let scenes = match d.size_family("grid", wl, 1.0) {
        Some(fam) => fam
            .scenes
            .into_iter()
            .map(|(s, _)| s)
            .filter(|s| {
                structures
                    .iter()
                    .all(|st| d.get(s, st, wl, Measure::NsPerQuery).is_some())
            })
            .collect(),
        None => d.common_scenes(&structures, wl),
    };
    let time = |st: &str| -> Vec<Option<f64>> {
        scenes
            .iter()
            .map(|s| d.get(s, st, wl, Measure::NsPerQuery))
            .collect()
    };
    let slower = |st: &str| -> Option<f64> {
        let ratios: Vec<f64> = time(st)
            .iter()
            .zip(time("grid"))
            .filter_map(|(a, b)| Some(a.as_ref()? / b?))
            .collect();
        geometric_mean(ratios)
    };
    let (Some(coarse), Some(fine)) = (slower("grid-coarse"), slower("grid-fine")) else {
        return c.lacks("throughputs of the three grids on one scene");
    };
    let figures = vec![format!(
        "time per {wl} ray relative to λ = 1, geometric mean over {} scenes: λ = 1/8 {}×, λ = 8 {}×",
        scenes.len(),
        number(coarse),
        number(fine)
    )];
    c.decided(
        coarse >= 1.1 && fine >= 1.1,
        figures,
        ClaimChart::Bars {
            title: format!("Uniform grid at three resolutions: ns per {wl} ray"),
            y_desc: "ns per ray".into(),
            groups: scenes.clone(),
            series: structures
                .iter()
                .map(|st| (st.to_string(), time(st)))
                .collect(),
            log_y: true,
        },
    )
}
