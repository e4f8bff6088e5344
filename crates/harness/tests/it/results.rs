//! `raybench results`: the Markdown page of a real (small) report has the headline table with
//! the geometric means the report's figures give, one table per scene, the SAH table and a
//! link to the report; `--report-link` and `--headline-only` do what they say.

use crate::common;

use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::report::run::Report;
use raybench_scenes::{SceneRequest, Workload};
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENES: [&str; 2] = ["soup:triangles=300", "sphere:triangles=300"];

/// A two-scene run of bvh-binned against embree-medium, written as
/// `ROOT/reports/small/report.json`.
fn report_in(root: &Path) -> (Report, PathBuf) {
    report_of(root, &["bvh-binned", "embree-medium"])
}

/// A two-scene run of `structures` (embree-medium the reference), written as
/// `ROOT/reports/small/report.json`.
fn report_of(root: &Path, structures: &[&str]) -> (Report, PathBuf) {
    let options = RunOptions {
        workloads: vec![Workload::Primary, Workload::Random, Workload::PointsNear],
        rays: 1000,
        points: 200,
        images: false,
        ..common::options(structures)
    };
    let requests = SCENES.map(|s| SceneRequest::Spec(s.into()));
    let report = run(&options, &requests).unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let path = report.write_atomic(&root.join("reports/small")).unwrap();
    (report, path)
}

fn raybench(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "raybench {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// exp(mean(ln x)) over the scenes, in the report's order.
fn geometric_mean(values: &[f64]) -> f64 {
    (values.iter().map(|v| v.ln()).sum::<f64>() / values.len() as f64).exp()
}

/// The headline row of bvh-binned, computed here from the report's figures.
fn expected_row(report: &Report) -> String {
    let ours: Vec<_> = report
        .results
        .iter()
        .filter(|r| r.structure == "bvh-binned")
        .collect();
    assert_eq!(ours.len(), SCENES.len());
    let mut cells = Vec::new();
    for wl in ["primary", "random", "points-near"] {
        let ratios: Vec<f64> = ours
            .iter()
            .map(|r| {
                let w = r.workloads.iter().find(|w| w.workload == wl).unwrap();
                w.speedup_vs_reference.unwrap()
            })
            .collect();
        cells.push(format!("{:.2}", geometric_mean(&ratios)));
    }
    let builds: Vec<f64> = ours
        .iter()
        .map(|r| r.build_ratio_to_reference.unwrap())
        .collect();
    cells.push(format!("{:.2}", geometric_mean(&builds)));
    let memory: Vec<f64> = ours
        .iter()
        .map(|r| {
            let base = report
                .results
                .iter()
                .find(|b| b.scene == r.scene && b.structure == "embree-medium")
                .unwrap();
            r.memory_bytes as f64 / base.memory_bytes as f64
        })
        .collect();
    cells.push(format!("{:.2}", geometric_mean(&memory)));
    format!("| bvh-binned | {} |", cells.join(" | "))
}

#[test]
fn the_page_has_the_headline_scene_and_sah_tables_and_links_the_report() {
    let root = std::env::temp_dir().join(format!("raybench-results-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (report, path) = report_in(&root);
    let page_path = root.join("docs/results/small.md");
    let printed = raybench(&[
        "results",
        path.to_str().unwrap(),
        "--out",
        page_path.to_str().unwrap(),
    ]);
    assert!(printed.contains("small.md"), "{printed}");
    let page = std::fs::read_to_string(&page_path).unwrap();
    let link = "../../reports/small/report.json";
    assert!(page.contains(&format!("[{link}]({link})")), "{page}");
    let revision: String = report
        .header
        .environment
        .git_revision
        .chars()
        .take(10)
        .collect();
    assert!(page.starts_with(&format!(
        "# Results of {} (revision {revision})",
        &report.header.environment.timestamp[..10]
    )));
    // The CPU's SIMD features and Embree's kernels: one model name can cover CPUs with and
    // without AVX-512.
    let env = &report.header.environment;
    if !env.cpu_flags.is_empty() {
        let machine = format!(
            "on {} ({} cores; {}; Embree's {} kernels)",
            env.cpu_model,
            env.cores,
            env.cpu_flags.join(" "),
            env.embree.isa
        );
        assert!(page.contains(&machine), "{machine}\n{page}");
    }

    let headline = &page[page.find("## Headline").unwrap()..page.find("## Scenes").unwrap()];
    assert!(
        headline.contains(
            "| structure | primary | random | points-near | build | memory |\n\
             |---|---:|---:|---:|---:|---:|\n"
        ),
        "{headline}"
    );
    let row = expected_row(&report);
    assert!(headline.contains(&format!("{row}\n")), "{row}\n{headline}");
    assert!(
        !headline.contains("| embree-medium |"),
        "the reference has no row"
    );
    let comparisons: u64 = report
        .results
        .iter()
        .flat_map(|r| &r.workloads)
        .map(|w| w.agreement.counts.total())
        .sum();
    assert!(
        headline.contains(&format!("0 mismatches in {comparisons} comparisons")),
        "{headline}"
    );

    for scene in SCENES {
        assert!(page.contains(&format!("\n### {scene}\n")), "{scene}");
    }
    assert!(page.contains("| structure | build ms | memory MB | primary Mrays/s | random Mrays/s | points-near Mqueries/s |"));
    let sah = report
        .results
        .iter()
        .find(|r| r.scene == SCENES[0] && r.structure == "bvh-binned")
        .and_then(|r| r.build_stats.sah_cost)
        .unwrap();
    assert!(page.contains("| scene | bvh-binned |"), "{page}");
    assert!(
        page.contains(&format!("| {} | {sah:.2} |", SCENES[0])),
        "{page}"
    );

    let linked = root.join("linked.md");
    raybench(&[
        "results",
        path.to_str().unwrap(),
        "--out",
        linked.to_str().unwrap(),
        "--report-link",
        "https://example.org/small/report.json",
    ]);
    let linked = std::fs::read_to_string(linked).unwrap();
    assert!(linked.contains("(https://example.org/small/report.json)"));

    let only = raybench(&["results", path.to_str().unwrap(), "--headline-only"]);
    assert!(only.starts_with("| structure | primary |"), "{only}");
    assert!(
        only.contains(&row) && only.contains("0 mismatches in"),
        "{only}"
    );
    assert!(
        !only.contains("## ") && !only.contains("report.json"),
        "{only}"
    );

    // The headline again against another structure of the run: the reference gets a row, the
    // ratio of the two medians per scene, so embree-medium's is the reciprocal of bvh-binned's.
    let page = raybench(&[
        "results",
        path.to_str().unwrap(),
        "--also-against",
        "bvh-binned",
    ]);
    let against =
        &page[page.find("## Against `bvh-binned`").unwrap()..page.find("## Scenes").unwrap()];
    let inverse: Vec<f64> = ["primary", "random", "points-near"]
        .iter()
        .map(|wl| {
            let ratios: Vec<f64> = report
                .results
                .iter()
                .filter(|r| r.structure == "bvh-binned")
                .map(|r| {
                    let w = r.workloads.iter().find(|w| &w.workload == wl).unwrap();
                    1.0 / w.speedup_vs_reference.unwrap()
                })
                .collect();
            geometric_mean(&ratios)
        })
        .collect();
    let row = format!(
        "| embree-medium | {:.2} | {:.2} | {:.2} |",
        inverse[0], inverse[1], inverse[2]
    );
    assert!(against.contains(&row), "{row}\n{against}");
    assert!(!against.contains("| bvh-binned |"), "{against}");

    // Work per ray: bvh-binned counts its work, Embree does not.
    let work = &page[page.find("## Work per ray").unwrap()..];
    let counted = report
        .results
        .iter()
        .find(|r| r.scene == SCENES[0] && r.structure == "bvh-binned")
        .unwrap();
    let w = raybench_harness::output::work_per_ray::work_per_ray(counted, "random").unwrap();
    let c = counted.workloads[1].counters_per_query.as_ref().unwrap();
    assert_eq!((w.nodes, w.prim_tests), (c.nodes, c.prim_tests));
    let node_bytes = counted.memory.nodes as f64
        / (counted.build_stats.nodes - counted.build_stats.leaves) as f64;
    assert!(
        (node_bytes - 64.0).abs() < 1e-9,
        "binary nodes are 64 bytes: {node_bytes}"
    );
    assert!(w.bytes.unwrap() > c.nodes * 64.0, "{w:?}");
    assert!(work.contains("| structure | primary | random |"), "{work}");
    assert!(work.contains("| bvh-binned | "), "{work}");
    assert!(!work.contains("| embree-medium |"), "{work}");

    let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args([
            "results",
            path.to_str().unwrap(),
            "--also-against",
            "kd-sah",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--also-against kd-sah"),
        "{err}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// `--also-against a+b`: every other structure's ratios are to the faster of the two on each
/// scene and workload (the shorter build, the smaller memory), the two have no row, and a
/// group with an empty, repeated or absent name is refused, naming the flag's value.
#[test]
fn a_group_is_raced_as_the_faster_of_its_structures_on_each_scene() {
    let root = std::env::temp_dir().join(format!("raybench-results-group-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (report, path) = report_of(&root, &["bvh-binned", "bvh-median", "embree-medium"]);
    let page = raybench(&[
        "results",
        path.to_str().unwrap(),
        "--also-against",
        "bvh-median+embree-medium",
    ]);
    let title = "## Against the faster of `bvh-median` and `embree-medium`";
    let against = &page[page.find(title).expect(&page)..page.find("## Scenes").unwrap()];
    let on = |structure: &str, scene: &str| {
        report
            .results
            .iter()
            .find(|r| r.structure == structure && r.scene == scene)
            .unwrap()
    };
    let mut cells = Vec::new();
    for wl in ["primary", "random", "points-near"] {
        let rate = |structure: &str, scene: &str| {
            let r = on(structure, scene);
            r.workloads
                .iter()
                .find(|w| w.workload == wl)
                .unwrap()
                .mqueries_per_s
                .median
        };
        let ratios: Vec<f64> = SCENES
            .iter()
            .map(|scene| {
                let best = rate("bvh-median", scene).max(rate("embree-medium", scene));
                rate("bvh-binned", scene) / best
            })
            .collect();
        cells.push(format!("{:.2}", geometric_mean(&ratios)));
    }
    let build: Vec<f64> = SCENES
        .iter()
        .map(|scene| {
            let ms = |s: &str| on(s, scene).build.median_ms;
            ms("bvh-binned") / ms("bvh-median").min(ms("embree-medium"))
        })
        .collect();
    let memory: Vec<f64> = SCENES
        .iter()
        .map(|scene| {
            let bytes = |s: &str| on(s, scene).memory_bytes as f64;
            bytes("bvh-binned") / bytes("bvh-median").min(bytes("embree-medium"))
        })
        .collect();
    cells.push(format!("{:.2}", geometric_mean(&build)));
    cells.push(format!("{:.2}", geometric_mean(&memory)));
    let row = format!("| bvh-binned | {} |", cells.join(" | "));
    assert!(against.contains(&row), "{row}\n{against}");
    assert!(!against.contains("| bvh-median |"), "{against}");
    assert!(!against.contains("| embree-medium |"), "{against}");

    for (value, says) in [
        ("bvh-median+", "an empty structure name"),
        ("bvh-median+bvh-median", "'bvh-median' is named twice"),
        ("bvh-median+kd-sah", "has no results of 'kd-sah'"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
            .args(["results", path.to_str().unwrap(), "--also-against", value])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{value}: accepted");
        assert!(
            err.contains(&format!("--also-against {value}")) && err.contains(says),
            "{value}: {err}"
        );
    }
    std::fs::remove_dir_all(&root).unwrap();
}
