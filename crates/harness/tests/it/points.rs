//! Closest-point workloads through the harness: measured, counted and validated like rays.

use crate::common;

use raybench_harness::Registry;
use raybench_harness::pipeline::check::check_points;
use raybench_harness::pipeline::measure::point_pass;
use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::registry::BuildContext;
use raybench_harness::report::compare::{CompareOptions, Severity, compare};
use raybench_harness::report::run::{Report, WorkloadResult};
use raybench_scenes::SceneRequest;
use raybench_scenes::Workload;
use raybench_scenes::points::PointWorkload;

const STRUCTURES: [&str; 6] = [
    "embree-medium",
    "bvh-binned",
    "kd-sah",
    "grid",
    "octree",
    "bruteforce",
];
const SCENES: [&str; 2] = ["sphere:triangles=2000", "soup:triangles=1500"];

fn point_options(threads: usize) -> RunOptions {
    RunOptions {
        workloads: Workload::POINTS.to_vec(),
        points: 400,
        threads,
        images: false,
        ..common::options(&STRUCTURES)
    }
}

fn run_points(threads: usize) -> Report {
    let scenes: Vec<SceneRequest> = SCENES.map(|s| SceneRequest::Spec(s.into())).to_vec();
    run(&point_options(threads), &scenes).expect("the run succeeds")
}

fn point_results(report: &Report) -> Vec<(&str, &str, &WorkloadResult)> {
    report
        .results
        .iter()
        .flat_map(|r| {
            r.workloads
                .iter()
                .map(move |w| (&*r.scene, &*r.structure, w))
        })
        .collect()
}

#[test]
fn point_workloads_agree_with_embree_count_work_and_do_not_depend_on_threads() {
    let one = run_points(1);
    assert!(one.errors.is_empty(), "{:?}", one.errors);
    assert_eq!(one.run.points, 400);
    assert_eq!(one.results.len(), SCENES.len() * STRUCTURES.len());
    let results = point_results(&one);
    assert_eq!(results.len(), SCENES.len() * STRUCTURES.len() * 2);
    for (scene, structure, w) in &results {
        let v = &w.agreement;
        let label = format!("{structure} on {scene} / {}", w.workload);
        assert!(w.point_query && !w.any_hit, "{label}");
        assert_eq!(w.queries, 400, "{label}");
        assert_eq!(v.queries(), 400, "{label}: every query classified");
        assert_eq!(
            v.counts.mismatch, 0,
            "{label}: {:?}",
            v.first_point_mismatches
        );
        assert_eq!(v.counted_path_differs, 0, "{label}");
        assert_eq!(
            v.counts.both_miss, 0,
            "{label}: infinite radius, always an answer"
        );
        assert!(w.mqueries_per_s.median > 0.0, "{label}");
        assert!(
            w.speedup_vs_reference.is_some(),
            "{label}: a ratio to embree-medium"
        );
        match (structure.starts_with("embree"), &w.counters_per_query) {
            (true, c) => assert!(c.is_none(), "{label}: Embree cannot count"),
            (false, Some(c)) => assert!(c.prim_tests >= 1.0, "{label}: {c:?}"),
            (false, None) => panic!("{label}: no counters"),
        }
    }
    // Brute force tests every triangle for every query; a structure prunes.
    let tests = |structure: &str| {
        results
            .iter()
            .find(|(s, st, w)| *s == SCENES[0] && *st == structure && w.workload == "points-near")
            .and_then(|(_, _, w)| w.counters_per_query)
            .map(|c| c.prim_tests)
            .unwrap()
    };
    let triangles = one
        .results
        .iter()
        .find(|r| r.scene == SCENES[0])
        .unwrap()
        .triangles
        .traced;
    assert_eq!(tests("bruteforce"), triangles as f64);
    assert!(tests("bvh-binned") < 200.0, "{}", tests("bvh-binned"));

    let two = run_points(2);
    for ((s1, st1, a), (s2, st2, b)) in results.iter().zip(point_results(&two)) {
        assert_eq!((s1, st1, &a.workload), (&s2, &st2, &b.workload));
        assert_eq!(
            a.counters_total, b.counters_total,
            "{st1} on {s1}: counters"
        );
        assert_eq!(a.agreement.counts, b.agreement.counts, "{st1} on {s1}");
    }
}

#[test]
fn batch_answers_are_identical_on_one_and_two_threads_and_a_wrong_answer_is_a_mismatch() {
    let scene = raybench_scenes::resolve(SCENES[0], 7).unwrap();
    let mesh = scene.mesh.clone();
    let points = PointWorkload::Near.generate(&mesh, 1000, 7);
    assert_eq!(
        points,
        PointWorkload::Near.generate(&mesh, 1000, 7),
        "seeded"
    );
    let ctx = BuildContext::new(2);
    let grid = Registry::builtin()
        .find("grid")
        .unwrap()
        .build(mesh.clone(), &ctx)
        .unwrap()
        .accel;
    let pass = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut out = vec![None; points.len()];
        pool.install(|| point_pass(grid.as_ref(), &points, f32::INFINITY, threads, &mut out));
        out
    };
    let single = pass(1);
    assert_eq!(single, pass(2));
    assert!(single.iter().all(Option::is_some));
    let embree = Registry::builtin()
        .find("embree-medium")
        .unwrap()
        .build(mesh.clone(), &ctx)
        .unwrap()
        .accel;
    let reference: Vec<_> = points
        .iter()
        .map(|&p| embree.closest_point(p, f32::INFINITY))
        .collect();
    let fine = check_points(
        &mesh,
        &points,
        f32::INFINITY,
        &single,
        &reference,
        "embree-medium",
    );
    assert_eq!(fine.counts.mismatch, 0);
    // Name another triangle, farther away, for query 5: a mismatch, kept with its bits.
    let mut wrong = single.clone();
    let mut hit = wrong[5].unwrap();
    hit.prim = (hit.prim + 1000) % mesh.len() as u32;
    hit.distance *= 1.5;
    wrong[5] = Some(hit);
    let bad = check_points(
        &mesh,
        &points,
        f32::INFINITY,
        &wrong,
        &reference,
        "embree-medium",
    );
    assert_eq!(bad.counts.mismatch, 1);
    let d = &bad.first_point_mismatches[0];
    assert_eq!(d.index, 5);
    assert_eq!(d.point_bits[0], format!("{:#010x}", points[5].x.to_bits()));
    assert_eq!(d.ours.as_ref().unwrap().prim, hit.prim);
}

#[test]
fn an_old_baseline_without_point_workloads_still_gates_the_new_report() {
    let scenes = [SceneRequest::Spec("sphere:triangles=1000".into())];
    let base_opts = RunOptions {
        workloads: vec![Workload::Primary],
        rays: 500,
        points: 200,
        images: false,
        ..common::options(&["bvh-binned", "embree-medium"])
    };
    let new_opts = RunOptions {
        workloads: vec![Workload::Primary, Workload::PointsNear],
        ..base_opts.clone()
    };
    let base = run(&base_opts, &scenes).unwrap();
    let new = run(&new_opts, &scenes).unwrap();
    let opts = CompareOptions {
        timing_advisory: true,
        ..CompareOptions::default()
    };
    let forward = compare(&base, &new, &opts);
    assert_eq!(forward.regressions(), 0, "{:?}", forward.findings);
    assert!(
        forward
            .findings
            .iter()
            .any(|f| f.severity == Severity::Note && f.what.contains("points-near")),
        "{:?}",
        forward.findings
    );
    // Dropping a workload the baseline has is a regression, and so is a different point count.
    assert!(compare(&new, &base, &opts).regressions() > 0);
    let fewer_points = RunOptions {
        points: 100,
        ..new_opts.clone()
    };
    let changed = run(&fewer_points, &scenes).unwrap();
    let c = compare(&new, &changed, &opts);
    assert!(
        c.findings
            .iter()
            .any(|f| f.severity == Severity::Regression && f.what.contains("points")),
        "{:?}",
        c.findings
    );
    // The same settings twice: counters and mismatches identical, the gate passes.
    let again = run(&new_opts, &scenes).unwrap();
    assert_eq!(compare(&new, &again, &opts).regressions(), 0);
}
