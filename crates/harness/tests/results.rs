//! `raybench results`: the Markdown page of a real (small) report has the headline table with
//! the geometric means the report's figures give, one table per scene, the SAH table and a
//! link to the report; `--report-link` and `--headline-only` do what they say.

mod common;

use raybench_harness::pipeline::run::{RunOptions, run};
use raybench_harness::report::run::Report;
use raybench_scenes::{SceneRequest, Workload};
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENES: [&str; 2] = ["soup:triangles=300", "sphere:triangles=300"];

/// A two-scene run of bvh-binned against embree-medium, written as
/// `ROOT/reports/small/report.json`.
fn report_in(root: &Path) -> (Report, PathBuf) {
    let options = RunOptions {
        workloads: vec![Workload::Primary, Workload::Random, Workload::PointsNear],
        rays: 1000,
        points: 200,
        images: false,
        ..common::options(&["bvh-binned", "embree-medium"])
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
    std::fs::remove_dir_all(&root).unwrap();
}
