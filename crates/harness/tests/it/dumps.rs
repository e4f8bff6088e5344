//! `--dump-hits` read back against the report and a re-trace, and determinism: the same run with
//! 1 thread twice and with 2 threads gives byte-identical dumps (every ray, every hit) and
//! identical counters, for every registered structure.

use crate::common;

use raybench_harness::Registry;
use raybench_harness::pipeline::dump::{read_dump, read_index};
use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::registry::BuildContext;
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("raybench-dumps-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn requests(specs: &[&str]) -> Vec<SceneRequest> {
    specs
        .iter()
        .map(|s| SceneRequest::Spec(s.to_string()))
        .collect()
}

fn run_with_dumps(opts: RunOptions, specs: &[&str], dir: &Path) -> Report {
    let opts = RunOptions {
        dump_hits: Some(dir.to_path_buf()),
        images: false,
        ..opts
    };
    let report = run(&opts, &requests(specs)).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    report
}

#[test]
fn a_dump_matches_the_report_and_a_re_trace() {
    let dir = scratch("retrace");
    let spec = "sphere:triangles=500";
    let structures = ["bvh-binned", "grid", "embree-medium", "bruteforce"];
    let opts = RunOptions {
        rays: 600,
        ..common::options(&structures)
    };
    let report = run_with_dumps(opts.clone(), &[spec], &dir);
    let index = read_index(&dir).unwrap();
    let expected: usize = report.results.iter().map(|r| r.workloads.len()).sum();
    assert_eq!(index.files.len(), expected);
    let mesh = raybench_scenes::resolve(spec, opts.seed).unwrap().mesh;
    let mut workload_rays: BTreeMap<String, Vec<[u32; 8]>> = BTreeMap::new();
    for e in &index.files {
        let result = report
            .results
            .iter()
            .find(|r| r.structure == e.structure)
            .unwrap();
        let w = result
            .workloads
            .iter()
            .find(|w| w.workload == e.workload)
            .unwrap();
        let dump = read_dump(&dir.join(&e.file)).unwrap();
        assert_eq!(
            (dump.records.len(), dump.any_hit),
            (w.queries, w.any_hit),
            "{}",
            e.file
        );
        let bits: Vec<[u32; 8]> = dump.records.iter().map(|r| r.ray_bits).collect();
        // Every structure traced the very same rays.
        let first = workload_rays
            .entry(e.workload.clone())
            .or_insert_with(|| bits.clone());
        assert_eq!(*first, bits, "{}", e.file);
        let accel = Registry::builtin()
            .find(&e.structure)
            .unwrap()
            .build(mesh.clone(), &BuildContext::new(1))
            .unwrap()
            .accel;
        for record in dump.records.iter().step_by(37) {
            let ray = record.ray();
            if dump.any_hit {
                assert_eq!(accel.occluded(&ray), record.occluded, "{}", e.file);
            } else {
                assert_eq!(
                    accel.intersect(&ray),
                    record.hit,
                    "{} ray {}",
                    e.file,
                    record.ray_index
                );
            }
        }
    }
    assert!(workload_rays.len() == 5, "{:?}", workload_rays.keys());
    std::fs::remove_dir_all(dir).unwrap();
}

/// (file → bytes) of every dump in `dir`.
fn dump_bytes(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    read_index(dir)
        .unwrap()
        .files
        .into_iter()
        .map(|e| {
            let bytes = std::fs::read(dir.join(&e.file)).unwrap();
            (e.file, bytes)
        })
        .collect()
}

/// Counters of every scene × structure × workload.
fn counters(r: &Report) -> Vec<String> {
    r.results
        .iter()
        .flat_map(|e| {
            e.workloads.iter().map(move |w| {
                format!(
                    "{} {} {} {:?}",
                    e.scene, e.structure, w.workload, w.counters_total
                )
            })
        })
        .collect()
}

#[test]
fn hits_and_counters_are_identical_across_repeats_and_thread_counts() {
    let specs = [
        "sphere:triangles=400",
        "soup:triangles=300",
        "coplanar:triangles=200",
    ];
    let all: Vec<String> = Registry::builtin().names();
    let names: Vec<&str> = all.iter().map(String::as_str).collect();
    let one = RunOptions {
        rays: 300,
        ..common::options(&names)
    };
    let two = RunOptions {
        threads: 2,
        ..one.clone()
    };
    let dirs = [scratch("det-a"), scratch("det-b"), scratch("det-c")];
    let a = run_with_dumps(one.clone(), &specs, &dirs[0]);
    let b = run_with_dumps(one, &specs, &dirs[1]);
    let c = run_with_dumps(two, &specs, &dirs[2]);
    assert_eq!(a.results.len(), all.len() * specs.len());
    let (da, db, dc) = (
        dump_bytes(&dirs[0]),
        dump_bytes(&dirs[1]),
        dump_bytes(&dirs[2]),
    );
    assert_eq!(da.len(), all.len() * specs.len() * 5);
    for (file, bytes) in &da {
        assert!(
            db[file] == *bytes,
            "{file} differs between two 1-thread runs"
        );
        assert!(dc[file] == *bytes, "{file} differs between 1 and 2 threads");
    }
    assert_eq!(counters(&a), counters(&b));
    assert_eq!(
        counters(&a),
        counters(&c),
        "thread count must not change counters"
    );
    for d in dirs {
        std::fs::remove_dir_all(d).unwrap();
    }
}
