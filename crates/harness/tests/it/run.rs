//! End-to-end: `run` on small procedural scenes against Embree, the report round-trip, and
//! determinism of rays and counters.

use crate::common::options;
use raybench_harness::pipeline::run::run;
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use raybench_scenes::Workload;
use std::path::PathBuf;

fn scenes() -> Vec<SceneRequest> {
    [
        "sphere:triangles=2000",
        "soup:triangles=1500",
        "plane:quads=24",
    ]
    .map(|s| SceneRequest::Spec(s.into()))
    .to_vec()
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("raybench-test-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn bruteforce_and_every_embree_variant_agree() {
    let structures = [
        "bruteforce",
        "bruteforce-watertight",
        "embree-low",
        "embree-medium",
        "embree-high",
        "embree-robust",
    ];
    let report = run(&options(&structures), &scenes()).expect("run succeeds");
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert_eq!(report.results.len(), 3 * structures.len());
    for r in &report.results {
        assert_eq!(
            r.workloads.len(),
            Workload::RAYS.len(),
            "{} on {}",
            r.structure,
            r.scene
        );
        for w in &r.workloads {
            let v = &w.agreement;
            assert_eq!(
                v.counts.mismatch, 0,
                "{} on {} / {}: {:?}",
                r.structure, r.scene, w.workload, v.first_mismatches
            );
            assert_eq!(
                v.counted_path_differs, 0,
                "{} {} {}",
                r.structure, r.scene, w.workload
            );
            assert_eq!(v.queries() as usize, w.queries);
            assert!(w.mqueries_per_s.median > 0.0 && w.mqueries_per_s.median.is_finite());
            assert_eq!(
                w.counters_per_query.is_some(),
                r.structure.starts_with("bruteforce")
            );
            if r.structure == "embree-medium" {
                assert_eq!(
                    v.counts.exact + v.counts.both_miss,
                    w.queries as u64,
                    "the reference agrees with itself exactly"
                );
            }
        }
        // Every primary ray hits the sphere's default view somewhere or misses cleanly; the
        // workloads must have produced rays.
        assert!(r.workloads.iter().all(|w| w.queries > 0));
    }
    // Ratios exist for everything and are exactly 1 for the reference.
    let reference = report
        .results
        .iter()
        .find(|r| r.structure == "embree-medium")
        .unwrap();
    assert_eq!(reference.build_ratio_to_reference, Some(1.0));
    assert!(
        reference
            .workloads
            .iter()
            .all(|w| w.speedup_vs_reference == Some(1.0))
    );
}

#[test]
fn report_round_trips_through_serde_and_is_written_atomically() {
    let report = run(&options(&["bruteforce", "embree-medium"]), &scenes()[..1]).unwrap();
    let dir = temp_dir("roundtrip");
    let path = report.write_atomic(&dir).unwrap();
    let back = Report::read(&path).expect("the report reads back");
    assert_eq!(
        serde_json::to_string(&report).unwrap(),
        serde_json::to_string(&back).unwrap()
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .collect();
    assert_eq!(
        leftovers,
        vec![std::ffi::OsString::from("report.json")],
        "no temporary file left behind"
    );
    let text = std::fs::read_to_string(&path).unwrap();
    for field in [
        "schema_version",
        "environment",
        "git_revision",
        "mqueries_per_s",
        "counters_per_query",
        "first_mismatches",
    ] {
        assert!(text.contains(field), "report lacks {field}");
    }
    // No separate "no inf/NaN" scan is needed: serde_json writes a non-finite float as null,
    // which cannot deserialize back into the f64/f32 fields, so the round trip above fails.
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn same_seed_gives_identical_rays_and_counters() {
    let a = run(&options(&["bruteforce", "embree-medium"]), &scenes()).unwrap();
    let b = run(&options(&["bruteforce", "embree-medium"]), &scenes()).unwrap();
    let mut threads2 = options(&["bruteforce", "embree-medium"]);
    threads2.threads = 2;
    let c = run(&threads2, &scenes()).unwrap();
    let key = |r: &Report| -> Vec<String> {
        r.results
            .iter()
            .flat_map(|e| {
                e.workloads.iter().map(move |w| {
                    format!(
                        "{} {} {} {} {:?} {:?}",
                        e.scene,
                        e.structure,
                        w.workload,
                        w.queries,
                        w.counters_total,
                        w.agreement.counts
                    )
                })
            })
            .collect()
    };
    assert_eq!(key(&a), key(&b));
    assert_eq!(
        key(&a),
        key(&c),
        "thread count must not change rays, answers or counters"
    );
    let scenes = |r: &Report| {
        let mut v = serde_json::to_value(&r.scenes).unwrap();
        v.as_array_mut()
            .unwrap()
            .iter_mut()
            .for_each(|s| s["load_ms"] = 0.into()); // wall time
        v
    };
    assert_eq!(scenes(&a), scenes(&b));
}

#[test]
fn a_broken_scene_is_an_error_in_the_report_not_a_crash() {
    let missing = SceneRequest::File {
        path: "/nonexistent/nothing.obj".into(),
        optional: false,
    };
    let absent_optional = SceneRequest::File {
        path: "/nonexistent/optional.obj".into(),
        optional: true,
    };
    let bad_spec = SceneRequest::Spec("sphere:triangles=-5".into());
    let good = SceneRequest::Spec("soup:triangles=500".into());
    let report = run(
        &options(&["embree-medium"]),
        &[missing, absent_optional, bad_spec, good],
    )
    .unwrap();
    assert_eq!(report.results.len(), 1, "the good scene still runs");
    assert_eq!(report.errors.len(), 2, "{:?}", report.errors);
    assert!(
        report.errors[0].contains("nothing.obj"),
        "{}",
        report.errors[0]
    );
    assert!(
        report.notes.iter().any(|n| n.contains("optional.obj")),
        "{:?}",
        report.notes
    );
}

#[test]
fn scenes_get_unique_report_names() {
    let requests = [
        "teapot:triangles=500",
        "teapot:triangles=500",
        "teapot:triangles=500,view=default",
    ]
    .map(|s| SceneRequest::Spec(s.into()))
    .to_vec();
    let report = run(&options(&["embree-medium"]), &requests).unwrap();
    let names: Vec<&str> = report.scenes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "teapot:triangles=500",
            "teapot:triangles=500 #2",
            "teapot:triangles=500,view=default"
        ]
    );
    let result_names: Vec<&str> = report.results.iter().map(|r| r.scene.as_str()).collect();
    assert_eq!(
        result_names, names,
        "results carry the same names, so ratios pair up correctly"
    );
}

#[test]
fn unknown_structure_is_a_clear_error() {
    let err = run(&options(&["bvh-nonexistent"]), &scenes())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bvh-nonexistent") && err.contains("embree-medium"),
        "{err}"
    );
}
