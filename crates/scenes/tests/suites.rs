mod common;

use common::Fixtures;
use raybench_scenes::input::InputError;
use raybench_scenes::{
    SceneError, Suite, SuiteScene, Workload, generate, list_suites, load_suite, suites_dir,
};

fn repository_suite(name: &str) -> (std::path::PathBuf, Suite) {
    let path = suites_dir().join(name);
    let suite = load_suite(&path).unwrap_or_else(|e| panic!("{e}"));
    (path, suite)
}

#[test]
fn every_suite_parses_and_names_only_valid_specs() {
    let suites = list_suites().unwrap();
    let names: Vec<_> = suites.iter().map(|(_, s)| s.name.as_str()).collect();
    for expected in [
        "ci",
        "default",
        "full",
        "sweep-size",
        "sweep-stadium",
        "sweep-grass",
        "adversarial",
        "race",
        "holdout",
    ] {
        assert!(names.contains(&expected), "{expected} missing: {names:?}");
    }
    for (path, suite) in &suites {
        assert_eq!(
            path.file_stem().unwrap().to_str().unwrap(),
            suite.name,
            "file name = suite name"
        );
        assert!(suite.rays > 0 && !suite.workloads.is_empty() && !suite.structures.is_empty());
        assert!(
            suite.structures.iter().any(|s| s.starts_with("embree-")),
            "{}",
            suite.name
        );
        for scene in &suite.scenes {
            if let SuiteScene::Generated(spec) = scene {
                raybench_scenes::check_spec(spec).unwrap_or_else(|e| panic!("{}: {e}", suite.name));
            }
        }
    }
}

/// The holdout suite checks gains where no constant was tuned: none of its scenes is one of
/// the suites that tuning runs measure, it covers every generator family of the race suite with
/// the race's entries, and its seed is not the default one every tuning run used.
#[test]
fn the_holdout_suite_shares_no_scene_or_seed_with_the_tuning_suites() {
    let (_, holdout) = repository_suite("holdout.json");
    assert!(holdout.seed.is_some_and(|s| s != 1), "{:?}", holdout.seed);
    let generated = |suite: &Suite| -> Vec<String> {
        suite
            .scenes
            .iter()
            .filter_map(|s| match s {
                SuiteScene::Generated(spec) => Some(spec.clone()),
                SuiteScene::File { .. } => None,
            })
            .collect()
    };
    let family = |spec: &str| spec.split(':').next().unwrap().to_owned();
    let held = generated(&holdout);
    assert!(
        held.iter().all(|s| s.contains(':')),
        "every scene sized: {held:?}"
    );
    for tuning in ["default.json", "race.json", "ci.json"] {
        let (_, suite) = repository_suite(tuning);
        assert!(suite.seed.is_none(), "{tuning} runs at the default seed");
        let specs = generated(&suite);
        for spec in &held {
            assert!(!specs.contains(spec), "{spec} is also in {tuning}");
        }
        if tuning == "race.json" {
            for spec in &specs {
                let f = family(spec);
                assert!(held.iter().any(|h| family(h) == f), "no {f} scene held out");
            }
            assert_eq!(holdout.structures, suite.structures, "the race's entries");
            assert_eq!(holdout.workloads, suite.workloads);
        }
    }
}

#[test]
fn small_suites_generate_every_scene_with_its_view() {
    for file in [
        "ci.json",
        "default.json",
        "adversarial.json",
        "sweep-stadium.json",
    ] {
        let (_, suite) = repository_suite(file);
        for scene in &suite.scenes {
            if let SuiteScene::Generated(spec) = scene {
                generate(spec, 0).unwrap_or_else(|e| panic!("{file}: {e}"));
            }
        }
    }
    let (_, ci) = repository_suite("ci.json");
    assert_eq!(
        ci.workloads[..5],
        Workload::RAYS,
        "ci runs every ray workload"
    );
    assert_eq!(ci.workloads[5..], [Workload::PointsNear]);
    assert_eq!(ci.points, Some(2_000), "a ci point workload stays quick");
    for file in ["default.json", "full.json"] {
        let (_, suite) = repository_suite(file);
        assert!(
            Workload::POINTS.iter().all(|w| suite.workloads.contains(w)),
            "{file} runs both point workloads"
        );
        assert_eq!(suite.points, Some(10_000), "{file}");
    }
    // Every family against the reference; brute force, the O(N) oracle, is left to the tests
    // and `verify` (its timing was over half the run's and does not carry between CPUs).
    for family in ["embree-medium", "bvh8-binned", "kd-sah", "grid", "octree"] {
        assert!(
            ci.structures.iter().any(|s| s == family),
            "ci lacks {family}"
        );
    }
    assert!(!ci.structures.iter().any(|s| s.starts_with("bruteforce")));
}

#[test]
fn sweeps_span_what_they_claim() {
    let specs = |file: &str| -> Vec<String> {
        repository_suite(file)
            .1
            .scenes
            .into_iter()
            .filter_map(|s| match s {
                SuiteScene::Generated(spec) => Some(spec),
                SuiteScene::File { .. } => None,
            })
            .collect()
    };
    let size = specs("sweep-size.json");
    assert_eq!(size.first().unwrap(), "teapot:triangles=1024");
    assert_eq!(size.last().unwrap(), "teapot:triangles=4194304");
    let stadium = specs("sweep-stadium.json");
    assert_eq!(
        (stadium[0].as_str(), stadium[4].as_str()),
        (
            "teapot-in-stadium:size_ratio=1e-1",
            "teapot-in-stadium:size_ratio=1e-5"
        )
    );
    assert_eq!(specs("sweep-grass.json").len(), 7);
}

#[test]
fn default_lists_every_shared_scene_as_optional() {
    let (_, suite) = repository_suite("default.json");
    let files: Vec<_> = suite
        .scenes
        .iter()
        .filter_map(|s| match s {
            SuiteScene::File { obj, optional } => {
                assert!(optional, "{obj} must be optional");
                Some(obj.as_str())
            }
            SuiteScene::Generated(_) => None,
        })
        .collect();
    assert_eq!(files.len(), 7, "{files:?}");
    assert!(
        files
            .iter()
            .all(|f| f.starts_with("../../shared/scenes/") && f.ends_with(".obj"))
    );
}

#[test]
fn ci_suite_resolves_with_the_bunny_or_a_note() {
    let (path, suite) = repository_suite("ci.json");
    let requests = suite.requests(&path);
    assert_eq!(requests.len(), suite.scenes.len());
    let loaded: Vec<Option<String>> = requests
        .iter()
        .map(|r| r.load(0).unwrap().map(|s| s.name))
        .collect();
    let generated = suite
        .scenes
        .iter()
        .filter(|s| matches!(s, SuiteScene::Generated(_)))
        .count();
    assert_eq!(
        loaded[..3],
        [
            Some("sphere".into()),
            Some("soup".into()),
            Some("plane".into())
        ]
    );
    assert!(loaded[..generated].iter().all(Option::is_some));
    match &loaded[generated] {
        Some(bunny) => assert_eq!(bunny, "stanford-bunny"),
        None => eprintln!(
            "NOTE: the bunny was not loaded: {} is absent",
            requests[generated].label()
        ),
    }
}

fn manifest(scenes: &str) -> String {
    format!(
        r#"{{"name": "t", "description": "test", "scenes": {scenes},
            "structures": ["bruteforce"], "workloads": ["primary", "shadow"], "rays": 10}}"#
    )
}

#[test]
fn absent_optional_file_is_a_note_but_broken_or_required_files_are_errors() {
    let fx = Fixtures::new("suite");
    fx.write("broken.obj", "v 0 0 0\nf 1 2 3\n");
    let scenes = r#"["plane:quads=2",
        {"obj": "nowhere/x.obj", "optional": true},
        {"obj": "broken.obj", "optional": true},
        {"obj": "missing.obj"}]"#;
    let path = fx.write("t.json", manifest(scenes));
    let suite = load_suite(&path).unwrap();
    let requests = suite.requests(&path);
    assert_eq!(requests.len(), 4);
    assert!(matches!(requests[0].load(0), Ok(Some(_))));
    assert!(requests[1].label().ends_with("nowhere/x.obj"));
    assert!(matches!(requests[1].load(0), Ok(None)));
    assert!(requests[1].check().is_ok());
    let broken = requests[2].load(0).unwrap_err().to_string();
    assert!(
        broken.contains("broken.obj: line 2: vertex index 2 is out of range"),
        "{broken}"
    );
    assert!(matches!(
        requests[3].load(0),
        Err(SceneError::Input(InputError::Missing { .. }))
    ));
    let missing = requests[3].check().unwrap_err().to_string();
    assert!(missing.contains("missing.obj"), "{missing}");
}

#[test]
fn bad_manifests_are_errors_that_name_the_file() {
    let fx = Fixtures::new("badsuite");
    let cases = [
        (
            "unknown_workload.json",
            manifest("[\"sphere\"]").replace("shadow", "glossy"),
            "unknown variant `glossy`",
        ),
        (
            "typo.json",
            manifest("[\"sphere\"]").replace("\"rays\"", "\"ray\""),
            "unknown field `ray`",
        ),
        ("no_scenes.json", manifest("[]"), "lists no scenes"),
        (
            "zero_rays.json",
            manifest("[\"sphere\"]").replace(": 10}", ": 0}"),
            "rays = 0",
        ),
        (
            "zero_points.json",
            manifest("[\"sphere\"]").replace(": 10}", ": 10, \"points\": 0}"),
            "points = 0",
        ),
        (
            "not_json.json",
            "{".to_owned(),
            "not a valid suite manifest",
        ),
    ];
    for (name, text, expected) in cases {
        let path = fx.write(name, text);
        let msg = load_suite(&path).unwrap_err().to_string();
        assert!(
            msg.starts_with(&path.display().to_string()) && msg.contains(expected),
            "{name}: {msg}"
        );
    }
}

#[test]
fn suites_round_trip_through_json() {
    let (_, suite) = repository_suite("ci.json");
    let text = serde_json::to_string_pretty(&suite).unwrap();
    let back: Suite = serde_json::from_str(&text).unwrap();
    assert_eq!(back, suite);
}
