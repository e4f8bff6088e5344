//! `raybench verify` as a library: every structure against three references with brute force
//! on a subsample, disputed rays mapped back to their workload index, the replay command a
//! mismatch prints, and the watertightness figures.

use raybench_accel::Hit;
use raybench_geom::{Ray, Vec3};
use raybench_harness::output::verify_table::verify_table;
use raybench_harness::pipeline::dump::{read_dump, read_index};
use raybench_harness::pipeline::verify::{REFERENCES, VerifyOptions, brute_force_sample, verify};
use raybench_harness::pipeline::watertight::{EMBREE_POSITION, WatertightOptions, watertight};
use raybench_harness::report::agreement::DisputedRay;
use raybench_harness::report::verify::VerifyReport;
use raybench_harness::report::watertight::Case;
use raybench_scenes::SceneRequest;
use raybench_scenes::Workload;
use std::path::PathBuf;
use std::sync::OnceLock;

const SCENES: [&str; 2] = ["sphere:triangles=300", "soup:triangles=300"];
const RAYS: usize = 400;
/// About 100 rays per workload for brute force: small enough that it is subsampled here.
const BUDGET: u64 = 30_000;

fn options(structures: Vec<String>, dump_hits: Option<PathBuf>) -> VerifyOptions {
    VerifyOptions {
        suite: None,
        structures,
        workloads: Workload::RAYS.to_vec(),
        rays: RAYS,
        points: 500,
        threads: 1,
        seed: 3,
        ftz_daz: false,
        progress: false,
        brute_force_budget: BUDGET,
        dump_hits,
    }
}

fn requests() -> Vec<SceneRequest> {
    SCENES.map(|s| SceneRequest::Spec(s.into())).to_vec()
}

/// One verify of every structure, shared by the tests.
fn report() -> &'static VerifyReport {
    static REPORT: OnceLock<VerifyReport> = OnceLock::new();
    REPORT.get_or_init(|| {
        let all = raybench_harness::Registry::builtin().names();
        verify(&options(all, None), &requests()).unwrap()
    })
}

#[test]
fn every_structure_is_checked_against_three_references_with_zero_mismatches() {
    let r = report();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_eq!(r.mismatches(), 0, "{}", verify_table(r));
    let n = raybench_harness::Registry::builtin().names().len();
    assert_eq!(r.settings.structures.len(), n);
    let mut subsampled = 0;
    for scene in &r.scenes {
        for w in &scene.workloads {
            let want = brute_force_sample(w.queries, scene.triangles.traced as usize, BUDGET).len();
            assert_eq!(w.brute_force_queries, want);
            subsampled += usize::from(want < w.queries);
        }
    }
    assert!(
        subsampled >= 6,
        "most workloads are larger than the budget allows"
    );
    assert_eq!(r.results.len(), n * 2 * 5);
    for res in &r.results {
        let scene = r.scenes.iter().find(|s| s.name == res.scene).unwrap();
        let w = scene
            .workloads
            .iter()
            .find(|w| w.workload == res.workload)
            .unwrap();
        let refs: Vec<&str> = res
            .agreements
            .iter()
            .map(|v| v.reference.as_str())
            .collect();
        assert_eq!(refs, REFERENCES);
        let checked: Vec<u64> = res.agreements.iter().map(|v| v.queries()).collect();
        let (all, sample) = (w.queries as u64, w.brute_force_queries as u64);
        let exhaustive = res.structure.starts_with("bruteforce");
        let traced = if exhaustive { sample } else { all };
        assert_eq!(
            res.queries as u64, traced,
            "{} {}",
            res.structure, res.workload
        );
        assert_eq!(res.subsampled, traced < all);
        let want = if exhaustive {
            [sample; 3]
        } else {
            [all, all, sample]
        };
        assert_eq!(checked, want, "{} {}", res.structure, res.workload);
        if res.structure == "embree-medium" {
            let c = &res.agreements[0].counts;
            assert_eq!(
                c.exact + c.both_miss,
                all,
                "the reference agrees with itself"
            );
        }
    }
    assert_eq!(r.totals.len(), n * 3);
    for row in &r.totals {
        let want = format!(
            "0 mismatches in {} rays (95% upper bound 3/n = ",
            row.queries
        );
        assert!(row.agreement.starts_with(&want), "{}", row.agreement);
    }
    let table = verify_table(r);
    assert!(
        table.contains("evenly spaced subsamples on sphere:triangles=300"),
        "{table}"
    );
}

#[test]
fn dumps_hold_every_traced_ray_with_its_workload_index() {
    let dir = std::env::temp_dir().join(format!("raybench-verify-dumps-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let structures = ["bruteforce", "grid", "embree-robust"]
        .map(String::from)
        .to_vec();
    let r = &verify(&options(structures, Some(dir.clone())), &requests()).unwrap();
    let index = read_index(&dir).unwrap();
    assert_eq!(index.files.len(), r.results.len());
    for e in &index.files {
        let res = r
            .results
            .iter()
            .find(|x| x.scene == e.scene && x.structure == e.structure && x.workload == e.workload)
            .unwrap();
        let dump = read_dump(&dir.join(&e.file)).unwrap();
        assert_eq!(dump.records.len(), res.queries, "{}", e.file);
        assert_eq!(dump.any_hit, res.any_hit);
        let indices: Vec<usize> = dump.records.iter().map(|x| x.ray_index as usize).collect();
        let scene = r.scenes.iter().find(|s| s.name == e.scene).unwrap();
        let w = scene
            .workloads
            .iter()
            .find(|w| w.workload == e.workload)
            .unwrap();
        let want = if res.subsampled {
            brute_force_sample(w.queries, scene.triangles.traced as usize, BUDGET)
        } else {
            (0..w.queries).collect()
        };
        assert_eq!(indices, want, "{}", e.file);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Injects one mismatch: the exit status becomes 2 and the table prints a replay command that
/// the binary runs as printed.
#[test]
fn a_mismatch_prints_a_replay_command_that_replays() {
    let mut r = report().clone();
    let ray = Ray::infinite(Vec3::new(0.1, 0.2, 3.0), Vec3::new(0.0, 0.0, -1.0));
    let hit = Hit {
        t: 2.0,
        prim: 1,
        u: 0.25,
        v: 0.25,
    };
    let res = r
        .results
        .iter_mut()
        .find(|x| x.structure == "grid" && x.scene == SCENES[0])
        .unwrap();
    let v = &mut res.agreements[1];
    v.counts.mismatch += 1;
    v.first_mismatches
        .push(DisputedRay::new(7, "mismatch", &ray, Some(hit), None));
    assert_eq!(r.mismatches(), 1);
    assert_eq!(
        raybench_harness::cli::exit_status(r.mismatches(), 0),
        std::process::ExitCode::from(2)
    );
    let table = verify_table(&r);
    assert!(table.contains("replay the first 1 with:"), "{table}");
    let command = table
        .lines()
        .find(|l| l.starts_with("raybench replay "))
        .unwrap_or_else(|| panic!("no replay line in\n{table}"));
    assert!(
        command.contains("--structure grid,embree-robust"),
        "{command}"
    );
    assert!(command.contains("--seed 3"), "{command}");
    let args: Vec<&str> = command.split_whitespace().skip(1).collect();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args(&args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{command}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("origin (0.1, 0.2, 3)") && stdout.contains("grid "),
        "{stdout}"
    );
}

#[test]
fn verify_json_round_trips_and_is_written_atomically() {
    let dir = std::env::temp_dir().join(format!("raybench-verify-json-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let path = report().write_atomic(&dir).unwrap();
    let back = VerifyReport::read(&path).unwrap();
    assert_eq!(
        serde_json::to_string(report()).unwrap(),
        serde_json::to_string(&back).unwrap()
    );
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["verify.json"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Rays aimed at the edges and vertices of a sphere at Embree's far position: the watertight
/// test (Woop–Benthin–Wald) and Embree's robust mode find no crack; Möller–Trumbore does, which
/// shows the rays really graze edges (a set of easy rays would let this test pass vacuously).
#[test]
fn far_from_the_origin_watertight_tests_find_no_crack_and_moller_does() {
    let opts = WatertightOptions {
        cases: vec![Case {
            name: "sphere@embree".into(),
            spec: "offset:triangles=2000,radius=2,offset=0".into(),
            shift: EMBREE_POSITION,
        }],
        structures: ["bruteforce", "bruteforce-watertight", "embree-robust"]
            .map(String::from)
            .to_vec(),
        rays: 3_000,
        seed: 1,
        threads: 1,
        brute_force_budget: u64::MAX,
    };
    let r = watertight(&opts).unwrap();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    let misses = |s: &str| r.results.iter().find(|m| m.structure == s).unwrap();
    assert!(misses("bruteforce").rays > 2_500);
    assert_eq!(misses("bruteforce-watertight").misses, 0);
    assert_eq!(misses("embree-robust").misses, 0);
    assert!(misses("bruteforce").misses > 0, "{:?}", r.results);
}

/// A verify.json of schema version 1 (fields named after rays, `validations`) reads through the
/// old names into the same report.
#[test]
fn a_schema_1_verify_json_reads_through_the_old_names() {
    let mut old = serde_json::to_value(report()).unwrap();
    old["schema_version"] = 1.into();
    let rename = |object: &mut serde_json::Value| {
        let map = object.as_object_mut().unwrap();
        for (new, was) in [
            ("queries", "rays"),
            ("brute_force_queries", "brute_force_rays"),
            ("agreements", "validations"),
        ] {
            if let Some(v) = map.remove(new) {
                map.insert(was.to_string(), v);
            }
        }
    };
    for scene in old["scenes"].as_array_mut().unwrap() {
        scene["workloads"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .for_each(rename);
    }
    old["results"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .for_each(rename);
    old["totals"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .for_each(rename);
    let dir = std::env::temp_dir().join(format!("raybench-verify-v1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("verify.json");
    std::fs::write(&path, serde_json::to_vec_pretty(&old).unwrap()).unwrap();
    assert!(
        std::fs::read_to_string(&path)
            .unwrap()
            .contains("\"validations\"")
    );
    let mut read = VerifyReport::read(&path).expect("a schema-1 verify.json reads");
    assert_eq!(read.header.schema_version, 1);
    read.header.schema_version = report().header.schema_version;
    assert_eq!(
        serde_json::to_string(&read).unwrap(),
        serde_json::to_string(report()).unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}
