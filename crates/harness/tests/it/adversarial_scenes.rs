//! End to end on the adversarial scenes: brute force (both triangle tests) and every Embree
//! preset, every workload, checked against the reference. Each structure must build and agree
//! (0 mismatches), or the report must carry an error naming the scene; never a panic.

use crate::common;

use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use raybench_scenes::generators;

const STRUCTURES: [&str; 6] = [
    "bruteforce",
    "bruteforce-watertight",
    "embree-low",
    "embree-medium",
    "embree-high",
    "embree-robust",
];

/// Small sizes of every adversarial scene, with the named views that exist for a reason.
const SCENES: [&str; 12] = [
    "one-centroid:triangles=500",
    "coplanar:triangles=2000",
    "coplanar:triangles=2000,view=grazing",
    "offset:triangles=2000",
    "offset:triangles=2000,offset=0",
    // At 1e7 a radius-1 sphere is a few f32 ulps across, inside the validator's positional
    // tolerance (64 ε × 5.8e6 ≈ 44 units): disagreements there are all excused as `boundary`.
    // The radius-1000 sphere is what checks that regime.
    "offset:triangles=2000,offset=1e7",
    "offset:triangles=2000,offset=1e7,radius=1000",
    "offset:triangles=2000,offset=150000,view=inside",
    "zero-area-mixed:triangles=2000",
    "zero-area-mixed:triangles=300,degenerate_fraction=1",
    "single-triangle",
    "single-triangle:size=1e-5",
];

/// The other adversarial generators (duplicates, fans, huge beside tiny, deep nesting), in a
/// test of their own to keep each test's run short.
const MORE_SCENES: [&str; 5] = [
    "identical:triangles=300",
    "identical:triangles=256,size=0",
    "fan:triangles=2000",
    "huge-and-small:triangles=2000",
    "deep",
];

fn options() -> RunOptions {
    RunOptions {
        rays: 2_000,
        threads: 2,
        seed: 11,
        ..common::options(&STRUCTURES)
    }
}

fn run_one(spec: &str) -> Report {
    run(&options(), &[SceneRequest::Spec(spec.into())])
        .unwrap_or_else(|e| panic!("{spec}: the run itself failed: {e:#}"))
}

/// Every structure built and agrees with the reference on every workload it traced, or the
/// report names the scene in an error. Returns the problems found (empty: all good).
fn problems(spec: &str, report: &Report) -> Vec<String> {
    let name = spec.split(':').next().unwrap();
    let mut out = Vec::new();
    for e in &report.errors {
        if !e.contains(name) {
            out.push(format!("{spec}: error that does not name the scene: {e}"));
        }
    }
    for s in STRUCTURES {
        let built = report.results.iter().any(|r| r.structure == s);
        let explained = report.errors.iter().any(|e| e.contains(name));
        if !built && !explained {
            out.push(format!("{spec}: {s} has neither a result nor an error"));
        }
    }
    for r in &report.results {
        for w in &r.workloads {
            let v = &w.agreement;
            if v.counts.mismatch != 0 {
                out.push(format!(
                    "{spec}: {} / {}: {} mismatches in {} rays; first: {:?}",
                    r.structure, w.workload, v.counts.mismatch, w.queries, v.first_mismatches
                ));
            }
            if v.counted_path_differs != 0 {
                out.push(format!(
                    "{spec}: {} / {}: counted path differs on {} rays",
                    r.structure, w.workload, v.counted_path_differs
                ));
            }
            if v.queries() as usize != w.queries {
                out.push(format!(
                    "{spec}: {} / {}: {} rays classified of {}",
                    r.structure,
                    w.workload,
                    v.queries(),
                    w.queries
                ));
            }
            if !(w.mqueries_per_s.median.is_finite() && w.mqueries_per_s.median >= 0.0) {
                out.push(format!(
                    "{spec}: {} / {}: throughput {}",
                    r.structure, w.workload, w.mqueries_per_s.median
                ));
            }
        }
    }
    out
}

fn check_all(specs: &[&str]) {
    let mut all = Vec::new();
    for spec in specs {
        let report = run_one(spec);
        for r in &report.results {
            let summary: Vec<String> = r
                .workloads
                .iter()
                .map(|w| format!("{} {:?}", w.workload, w.agreement.counts))
                .collect();
            eprintln!("{spec} {}: {}", r.structure, summary.join("; "));
        }
        for e in &report.errors {
            eprintln!("{spec}: error: {e}");
        }
        all.extend(problems(spec, &report));
    }
    assert!(all.is_empty(), "{}", all.join("\n"));
}

#[test]
fn adversarial_scenes_build_and_agree_with_embree() {
    check_all(&SCENES);
}

#[test]
fn more_adversarial_scenes_build_and_agree_with_embree() {
    let known: Vec<&str> = generators().iter().map(|g| g.name).collect();
    for spec in MORE_SCENES {
        let name = spec.split(':').next().unwrap();
        assert!(
            known.contains(&name),
            "{name} is not a registered generator"
        );
    }
    check_all(&MORE_SCENES);
}

/// The empty scene: the run succeeds and every structure builds. Primary and random rays are
/// made (from the view, and from [-1, 1]³ since the box is empty) and all miss everywhere; with
/// no primary hit there are no shadow or diffuse rays, and the harness skips empty workloads,
/// so each result has exactly the primary and random workloads.
#[test]
fn empty_scene_builds_everywhere_and_every_ray_misses() {
    let report = run_one("empty");
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert_eq!(report.results.len(), STRUCTURES.len());
    let record = &report.scenes[0];
    assert_eq!(record.triangles.traced, 0);
    let rays_of = |name: &str| {
        record
            .workloads
            .iter()
            .find(|w| w.workload == name)
            .map(|w| w.queries)
    };
    assert!(rays_of("primary").unwrap() > 0 && rays_of("random") == Some(2_000));
    assert_eq!((rays_of("shadow"), rays_of("diffuse")), (Some(0), Some(0)));
    for r in &report.results {
        let names: Vec<&str> = r.workloads.iter().map(|w| w.workload.as_str()).collect();
        assert_eq!(names, ["primary", "random"], "{}", r.structure);
        for w in &r.workloads {
            let c = &w.agreement.counts;
            assert_eq!(c.mismatch, 0, "{} / {}", r.structure, w.workload);
            assert_eq!(
                c.both_miss, w.queries as u64,
                "{} / {}: every ray misses ({c:?})",
                r.structure, w.workload
            );
        }
    }
}
