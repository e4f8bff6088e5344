//! Claims decided by two structures that differ in one thing, on the scenes where both ran:
//! binned against full-sweep SAH (the same builder with fewer candidate planes), ordered
//! against fixed child order (the same tree), the k-d tree with and without early exit (the
//! same tree).

use super::data::{Data, Measure, number};
use super::{Claim, ClaimChart, Evaluated};
use crate::output::results::geometric_mean;

/// `a / b` of `m` per scene, and its geometric mean.
fn ratios(
    d: Data,
    scenes: &[String],
    (a, b): (&str, &str),
    wl: &str,
    m: Measure,
) -> (Vec<Option<f64>>, Option<f64>) {
    let per: Vec<Option<f64>> = scenes
        .iter()
        .map(|s| {
            let (x, y) = (d.get(s, a, wl, m)?, d.get(s, b, wl, m)?);
            (y > 0.0).then_some(x / y)
        })
        .collect();
    let mean = geometric_mean(per.iter().flatten().copied());
    (per, mean)
}

fn first_workload(d: Data, pair: [&str; 2], workloads: &[&str]) -> Option<String> {
    workloads
        .iter()
        .find(|wl| !d.common_scenes(&pair, wl).is_empty())
        .map(|wl| wl.to_string())
}

pub(super) fn binned_sah(d: Data) -> Evaluated {
    let c = Claim::new(
        "binned-sah",
        "Binned SAH builds a BVH nearly as good as a full sweep over every split position, in a fraction of the time.",
        "bvh-binned (32 bins) against bvh-sweep (every position), geometric means over the \
         scenes where both ran: holds when the SAH cost is within 5 % (ratio ≤ 1.05), the time \
         per random ray (else primary ray) within 10 % (ratio ≤ 1.10) and the build takes half \
         the time or less (ratio ≤ 0.5)"
            .into(),
    );
    let pair = ["bvh-binned", "bvh-sweep"];
    let Some(wl) = first_workload(d, pair, &["random", "primary"]) else {
        return c.lacks("bvh-binned and bvh-sweep on the same scenes");
    };
    let scenes = d.common_scenes(&pair, &wl);
    let per_scene = |f: &dyn Fn(&crate::report::run::ResultEntry) -> Option<f64>| {
        scenes
            .iter()
            .map(|s| {
                let (a, b) = (f(d.result(s, pair[0])?)?, f(d.result(s, pair[1])?)?);
                (b > 0.0 && a > 0.0).then_some(a / b)
            })
            .collect::<Vec<_>>()
    };
    let sah = per_scene(&|r| r.build_stats.sah_cost);
    let build = per_scene(&|r| Some(r.build.median_ms));
    let (time, time_mean) = ratios(d, &scenes, (pair[0], pair[1]), &wl, Measure::NsPerQuery);
    let mean = |v: &[Option<f64>]| geometric_mean(v.iter().flatten().copied());
    let (Some(sah_mean), Some(build_mean), Some(time_mean)) = (mean(&sah), mean(&build), time_mean)
    else {
        return c.lacks("SAH costs, builds and throughputs of both on one scene");
    };
    let figures = vec![format!(
        "bvh-binned / bvh-sweep over {} scenes: SAH cost {}×, time per {wl} ray {}×, build time {}×",
        scenes.len(),
        number(sah_mean),
        number(time_mean),
        number(build_mean)
    )];
    c.decided(
        sah_mean <= 1.05 && time_mean <= 1.10 && build_mean <= 0.5,
        figures,
        ClaimChart::Bars {
            title: "bvh-binned relative to bvh-sweep".into(),
            y_desc: "bvh-binned / bvh-sweep".into(),
            groups: scenes.clone(),
            series: vec![
                ("SAH cost".into(), sah),
                (format!("time per {wl} ray"), time),
                ("build time".into(), build),
            ],
            log_y: true,
        },
    )
}

/// Named values, one per scene.
type Named = Vec<(String, Vec<Option<f64>>)>;

/// Per scene `m` of both structures, the ratio's geometric mean, and whether `a` is below
/// `b` on every scene.
fn compare(
    d: Data,
    scenes: &[String],
    (a, b): (&str, &str),
    wl: &str,
    m: Measure,
) -> (Named, Option<f64>, bool) {
    let of =
        |st: &str| -> Vec<Option<f64>> { scenes.iter().map(|s| d.get(s, st, wl, m)).collect() };
    let (va, vb) = (of(a), of(b));
    let below = va
        .iter()
        .zip(&vb)
        .all(|(x, y)| matches!((x, y), (Some(x), Some(y)) if x <= y));
    let (_, mean) = ratios(d, scenes, (a, b), wl, m);
    (vec![(a.into(), va), (b.into(), vb)], mean, below)
}

pub(super) fn front_to_back(d: Data) -> Evaluated {
    let c = Claim::new(
        "front-to-back",
        "Visiting the nearer child first saves node visits: a hit found early culls the subtrees behind it.",
        "nodes visited (interior + leaves) per primary ray, bvh-binned (nearer child first) \
         against bvh-binned-unordered (the same tree in a fixed child order), on the scenes \
         where both ran: holds when ordered visits no more on any scene and 10 % fewer or more \
         in geometric mean"
            .into(),
    );
    let pair = ["bvh-binned", "bvh-binned-unordered"];
    let wl = "primary";
    let scenes = d.common_scenes(&pair, wl);
    let (series, mean, below) = compare(d, &scenes, (pair[0], pair[1]), wl, Measure::Nodes);
    let Some(mean) = mean else {
        return c.lacks("bvh-binned and bvh-binned-unordered counted on primary rays");
    };
    let (_, time_mean) = ratios(d, &scenes, (pair[0], pair[1]), wl, Measure::NsPerQuery);
    let figures = vec![
        format!(
            "ordered / unordered nodes per primary ray over {} scenes: {}× (geometric mean); \
             ordered visits no more on every scene: {}",
            scenes.len(),
            number(mean),
            if below { "yes" } else { "no" }
        ),
        format!(
            "ordered / unordered time per primary ray: {}×",
            time_mean.map_or("-".into(), number)
        ),
    ];
    c.decided(
        below && mean <= 0.9,
        figures,
        ClaimChart::Bars {
            title: "Nodes per primary ray: nearer child first against fixed order".into(),
            y_desc: "nodes per ray".into(),
            groups: scenes,
            series,
            log_y: true,
        },
    )
}

pub(super) fn kd_early_exit(d: Data) -> Evaluated {
    let c = Claim::new(
        "kd-early-exit",
        "A k-d tree stops at the first hit: its cells do not overlap, so the cells behind a hit are never visited.",
        "leaves visited per primary ray, kd-sah against kd-sah-exhaustive (the same tree walked \
         to the end of every ray), on the scenes where both ran: holds when kd-sah visits no \
         more on any scene and 20 % fewer or more in geometric mean"
            .into(),
    );
    let pair = ["kd-sah", "kd-sah-exhaustive"];
    let wl = "primary";
    let scenes = d.common_scenes(&pair, wl);
    let (series, mean, below) = compare(d, &scenes, (pair[0], pair[1]), wl, Measure::Leaves);
    let Some(mean) = mean else {
        return c.lacks("kd-sah and kd-sah-exhaustive counted on primary rays");
    };
    let (_, tests) = ratios(d, &scenes, (pair[0], pair[1]), wl, Measure::TriangleTests);
    let figures = vec![format!(
        "kd-sah / kd-sah-exhaustive over {} scenes (geometric means): leaves per primary ray {}×, \
         triangle tests {}×; no more leaves on every scene: {}",
        scenes.len(),
        number(mean),
        tests.map_or("-".into(), number),
        if below { "yes" } else { "no" }
    )];
    c.decided(
        below && mean <= 0.8,
        figures,
        ClaimChart::Bars {
            title: "Leaves per primary ray: k-d tree with and without early exit".into(),
            y_desc: "leaves per ray".into(),
            groups: scenes,
            series,
            log_y: true,
        },
    )
}
