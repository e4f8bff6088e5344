//! A program's own structures: `Registry::register` refuses what would break a command, and a
//! registered entry is listed, run, timed and checked by the same command handlers as a
//! built-in one (called as `cli::main_with` calls them, without a subprocess).

use crate::common;

use clap::Parser;
use raybench_accel::{Accel, BuildError, BuildStats, Counters, Hit, Memory, PointHit};
use raybench_bvh::{Bvh, BvhParams};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use raybench_harness::cli::list::write_structures;
use raybench_harness::cli::run::RunArgs;
use raybench_harness::cli::verify::VerifyArgs;
use raybench_harness::pipeline::verify::{VerifyOptions, verify_with};
use raybench_harness::registry::RegisterError;
use raybench_harness::report::run::Report;
use raybench_harness::{Registry, cli};
use raybench_scenes::{SceneRequest, Workload};
use std::process::ExitCode;
use std::sync::Arc;

/// The binary BVH with two-triangle leaves: a configuration no built-in entry has, so its
/// parameters in a report can only come from the registration.
fn small_leaves() -> BvhParams {
    BvhParams {
        max_leaf_size: 2,
        ..BvhParams::binned()
    }
}

fn with_mine() -> Registry {
    let mut r = Registry::builtin();
    r.register::<Bvh>(
        "my-bvh",
        "binned SAH binary BVH with two-triangle leaves",
        small_leaves(),
    )
    .unwrap();
    r
}

#[test]
fn a_taken_name_is_refused_naming_it() {
    let mut r = with_mine();
    for name in ["bvh8-binned", "embree-medium", "my-bvh"] {
        let err = r
            .register::<Bvh>(name, "again", BvhParams::default())
            .unwrap_err();
        assert_eq!(err, RegisterError::Duplicate(name.to_string()));
        assert!(err.to_string().contains(&format!("`{name}`")), "{err}");
    }
    assert_eq!(r.names().len(), Registry::builtin().names().len() + 1);
}

#[test]
fn names_the_structures_flag_cannot_carry_are_refused() {
    let mut r = Registry::builtin();
    let err = r
        .register::<Bvh>("", "d", BvhParams::default())
        .unwrap_err();
    assert_eq!(err, RegisterError::EmptyName);
    for name in [
        "a,b",
        "two words",
        "tab\there",
        "-flag",
        ".hidden",
        "a/b",
        "ünï",
        "x\n",
    ] {
        match r.register::<Bvh>(name, "d", BvhParams::default()) {
            Err(RegisterError::BadName { name: n, .. }) => assert_eq!(n, name),
            other => panic!("`{name}` was not refused as a bad name: {other:?}"),
        }
    }
    for name in ["mine", "Mine_2", "v1.2-fast", "8wide"] {
        r.register::<Bvh>(name, "d", BvhParams::default())
            .unwrap_or_else(|e| panic!("`{name}`: {e}"));
    }
}

#[test]
fn descriptions_must_say_something_on_one_line() {
    let mut r = Registry::builtin();
    for (description, want) in [
        ("", RegisterError::EmptyDescription("mine".into())),
        ("  ", RegisterError::EmptyDescription("mine".into())),
        ("two\nlines", RegisterError::BadDescription("mine".into())),
    ] {
        let err = r
            .register::<Bvh>("mine", description, BvhParams::default())
            .unwrap_err();
        assert_eq!(err, want);
    }
    // Nothing refused was added.
    assert_eq!(r.names(), Registry::builtin().names());
}

#[test]
fn list_shows_registered_entries_under_their_own_heading_last() {
    let text = |r: &Registry| {
        let mut out = Vec::new();
        write_structures(r, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    };
    let (stock, mine) = (text(&Registry::builtin()), text(&with_mine()));
    assert!(!stock.contains("Registered by this program"), "{stock}");
    let added = mine
        .strip_prefix(stock.as_str())
        .expect("built-in part unchanged");
    assert_eq!(
        added,
        "\nRegistered by this program:\n  my-bvh                   binned SAH binary BVH with two-triangle leaves\n"
    );
}

#[test]
fn selection_keeps_registry_order_and_refuses_unknown_names() {
    let r = with_mine();
    let names: Vec<String> = ["my-bvh", "bruteforce"].map(String::from).to_vec();
    let picked: Vec<&str> = r.select(&names).unwrap().iter().map(|e| e.name).collect();
    assert_eq!(picked, ["bruteforce", "my-bvh"]);
    let err = Registry::builtin().find("my-bvh").unwrap_err().to_string();
    assert!(err.contains("unknown structure 'my-bvh'"), "{err}");
}

#[derive(Parser)]
struct Run {
    #[command(flatten)]
    args: RunArgs,
}

#[derive(Parser)]
struct Verify {
    #[command(flatten)]
    args: VerifyArgs,
}

#[test]
fn run_times_and_checks_a_registered_entry_and_reports_its_params() {
    let dir = common::scratch("registry-run");
    let argv = [
        "run",
        "--scenes",
        "sphere:triangles=2000",
        "--structures",
        "my-bvh,bvh-binned",
        "--workloads",
        "primary,shadow",
        "--rays",
        "2000",
        "--build-runs",
        "1",
        "--trace-runs",
        "1",
        "--no-images",
        "--out",
    ];
    let args = Run::parse_from(argv.iter().copied().chain([dir.to_str().unwrap()])).args;
    let code = cli::run::run(&with_mine(), args).unwrap();
    assert_eq!(code, ExitCode::SUCCESS);
    let report = Report::read(&dir.join("report.json")).unwrap();
    assert_eq!(report.mismatches(), 0);
    let mine = report
        .results
        .iter()
        .find(|e| e.structure == "my-bvh")
        .expect("my-bvh in the report");
    assert_eq!(mine.params["max_leaf_size"], 2, "{}", mine.params);
    let binned = report.results.iter().find(|e| e.structure == "bvh-binned");
    assert_ne!(mine.params, binned.unwrap().params);
    assert_eq!(mine.workloads.len(), 2);
    // The stock registry does not know it: the same arguments are refused.
    let args = Run::parse_from(argv.iter().copied().chain([dir.to_str().unwrap()])).args;
    let err = cli::run::run(&Registry::builtin(), args).unwrap_err();
    assert!(
        err.to_string().contains("unknown structure 'my-bvh'"),
        "{err}"
    );
}

#[test]
fn verify_defaults_to_every_entry_but_the_peers_including_registered_ones() {
    let dir = common::scratch("registry-verify");
    let args = Verify::parse_from([
        "verify",
        "--scenes",
        "soup:triangles=300",
        "--workloads",
        "random",
        "--rays",
        "200",
        "--force",
        "--out",
        dir.to_str().unwrap(),
    ])
    .args;
    let code = cli::verify::run(&with_mine(), args).unwrap();
    assert_eq!(code, ExitCode::SUCCESS);
    let text = std::fs::read_to_string(dir.join("verify.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let structures = json["settings"]["structures"].as_array().unwrap();
    let registry = with_mine();
    let own = registry.entries().iter().filter(|e| !e.peer).count();
    assert_eq!(structures.len(), own);
    assert!(
        structures
            .iter()
            .all(|s| !s.as_str().unwrap().starts_with("peer-"))
    );
    assert_eq!(structures.last().unwrap(), "my-bvh");
}

/// A registered structure that never sees anything: verify must call it wrong.
#[derive(Debug)]
struct Blind;

impl Accel for Blind {
    type Params = ();
    fn build(_: Arc<TriangleMesh>, _: &()) -> Result<Blind, BuildError> {
        Ok(Blind)
    }
    fn name(&self) -> &str {
        "blind"
    }
    fn intersect(&self, _: &Ray) -> Option<Hit> {
        None
    }
    fn occluded(&self, _: &Ray) -> bool {
        false
    }
    fn intersect_counted(&self, _: &Ray, _: &mut Counters) -> Option<Hit> {
        None
    }
    fn occluded_counted(&self, _: &Ray, _: &mut Counters) -> bool {
        false
    }
    fn closest_point(&self, _: Vec3, _: f32) -> Option<PointHit> {
        None
    }
    fn closest_point_counted(&self, _: Vec3, _: f32, _: &mut Counters) -> Option<PointHit> {
        None
    }
    fn build_stats(&self) -> BuildStats {
        BuildStats::default()
    }
    fn memory(&self) -> Memory {
        Memory::default()
    }
}

#[test]
fn a_wrong_registered_structure_is_a_mismatch() {
    let mut r = Registry::builtin();
    r.register::<Blind>("blind", "answers nothing", ()).unwrap();
    let opts = VerifyOptions {
        suite: None,
        structures: vec!["blind".into()],
        workloads: vec![Workload::Random],
        rays: 300,
        points: 1,
        threads: 1,
        seed: 5,
        ftz_daz: false,
        progress: false,
        brute_force_budget: 1_000_000,
        dump_hits: None,
    };
    let scenes = [SceneRequest::Spec("sphere:triangles=500".into())];
    let report = verify_with(&r, &opts, &scenes).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    assert!(
        report.mismatches() > 0,
        "a structure that never hits passed"
    );
}
