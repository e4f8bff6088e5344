//! The claims a report decides (`report::claims`): on synthetic reports whose numbers follow
//! the textbook laws every claim holds; breaking one law turns exactly that claim to "does not
//! hold"; a report without the structures a rule needs says "not measured"; and a real run
//! stores its claims in report.json and shows them on the page.

use crate::common;

use raybench_harness::pipeline::run::run;
use raybench_harness::report::claims::{Verdict, evaluate};
use raybench_harness::report::run::{Report, ResultEntry};
use raybench_scenes::SceneRequest;
use std::sync::OnceLock;

/// One real result (a counting structure on primary and random rays) to clone.
fn template() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        let options = raybench_harness::pipeline::run::RunOptions {
            workloads: raybench_scenes::Workload::ALL[..2].to_vec(),
            rays: 300,
            images: false,
            ..common::options(&["bvh-binned", "embree-medium"])
        };
        run(
            &options,
            &[SceneRequest::Spec("sphere:triangles=200".into())],
        )
        .unwrap()
    })
}

/// What one structure measures on one scene (per ray, on both workloads).
#[derive(Clone, Copy, Debug)]
struct M {
    ns: f64,
    nodes: f64,
    leaves: f64,
    tests: f64,
    cells: f64,
    build_ms: f64,
    sah: f64,
}

const STRUCTURES: [&str; 11] = [
    "embree-medium",
    "bruteforce",
    "bvh-sweep",
    "bvh-binned",
    "bvh-binned-unordered",
    "bvh8-binned",
    "kd-sah",
    "kd-sah-exhaustive",
    "grid-coarse",
    "grid",
    "grid-fine",
];

/// The claims suite's scenes: (name, triangles, stadium size ratio).
fn scenes() -> Vec<(String, f64, Option<f64>)> {
    let mut v: Vec<_> = [1024.0, 4096.0, 16384.0, 65536.0, 262144.0]
        .into_iter()
        .map(|n| (format!("teapot:triangles={n}"), n, None))
        .collect();
    for r in ["1e-1", "1e-2", "1e-3", "1e-4"] {
        v.push((
            format!("teapot-in-stadium:size_ratio={r}"),
            220_000.0,
            Some(r.parse().unwrap()),
        ));
    }
    v
}

/// Textbook numbers: trees like log N, the grid like N^1/3 and collapsing as the teapot
/// shrinks, brute force like N, binned SAH as good as the sweep at a tenth of the build,
/// ordered and early-exit walks half the work, λ = 1 the best grid.
fn textbook(st: &str, n: f64, ratio: Option<f64>) -> M {
    let log = n.log2();
    let cube = n.cbrt();
    let base = M {
        ns: 10.0 * log,
        nodes: 2.0 * log,
        leaves: log / 2.0,
        tests: 8.0,
        cells: 0.0,
        build_ms: n / 1e4,
        sah: 50.0,
    };
    let grid_tests = match ratio {
        // 10 tests at the largest ratio, 10,000 at the smallest.
        Some(r) => 10.0 * (0.1 / r),
        None => 2.0 * cube,
    };
    match st {
        "bruteforce" => M {
            ns: n,
            tests: n,
            ..base
        },
        "bvh-sweep" => M {
            build_ms: base.build_ms * 10.0,
            ..base
        },
        "bvh-binned-unordered" | "kd-sah-exhaustive" => M {
            nodes: base.nodes * 2.0,
            leaves: base.leaves * 3.0,
            ..base
        },
        "grid" | "grid-coarse" | "grid-fine" => {
            let slower = if st == "grid" { 1.0 } else { 1.5 };
            M {
                ns: 20.0 * cube * slower,
                nodes: 0.0,
                leaves: 0.0,
                tests: grid_tests,
                cells: cube,
                ..base
            }
        }
        _ => base,
    }
}

fn synthetic(model: impl Fn(&str, f64, Option<f64>) -> M) -> Report {
    let t = template();
    let proto = t
        .results
        .iter()
        .find(|r| r.structure == "bvh-binned")
        .unwrap();
    let mut report = t.clone();
    report.run.structures = STRUCTURES.iter().map(|s| s.to_string()).collect();
    report.results.clear();
    report.claims.clear();
    for (scene, n, ratio) in scenes() {
        for st in STRUCTURES {
            let m = model(st, n, ratio);
            let mut r: ResultEntry = proto.clone();
            r.scene = scene.clone();
            r.structure = st.into();
            r.triangles.loaded = n as u64;
            r.triangles.traced = n as u64;
            r.build.median_ms = m.build_ms;
            r.build_stats.sah_cost = Some(m.sah);
            for w in &mut r.workloads {
                w.mqueries_per_s.median = 1e3 / m.ns;
                let c = w.counters_per_query.as_mut().unwrap();
                c.nodes = m.nodes - m.leaves;
                c.leaves = m.leaves;
                c.prim_tests = m.tests;
                c.cells = m.cells;
            }
            report.results.push(r);
        }
    }
    report
}

fn verdicts(report: &Report) -> Vec<(String, Verdict)> {
    evaluate(report)
        .into_iter()
        .map(|e| (e.claim.id, e.claim.verdict))
        .collect()
}

#[test]
fn every_claim_holds_on_textbook_numbers() {
    let all = evaluate(&synthetic(textbook));
    assert_eq!(all.len(), 8);
    for e in &all {
        assert_eq!(e.claim.verdict, Verdict::Holds, "{:#?}", e.claim);
        assert!(
            !e.claim.figures.is_empty() && e.chart.is_some(),
            "{}",
            e.claim.id
        );
    }
    let grid = all.iter().find(|e| e.claim.id == "grid-cube-root").unwrap();
    assert!(
        grid.claim.figures[0].contains("b = 0.33 ± 0.00"),
        "{:?}",
        grid.claim.figures
    );
}

/// Breaking one law turns that claim, and only that one, to "does not hold".
#[test]
fn breaking_a_law_breaks_exactly_its_claim() {
    type Break = fn(&str, f64, Option<f64>, M) -> M;
    let cases: [(&str, Break); 8] = [
        ("bvh-log-n", |st, n, _, m| match st {
            "bvh-binned" => M {
                nodes: n.cbrt(),
                leaves: 0.1,
                ..m
            },
            _ => m,
        }),
        ("grid-cube-root", |st, n, _, m| match st {
            "grid" => M {
                cells: n.log2(),
                ..m
            },
            _ => m,
        }),
        ("bruteforce-linear", |st, n, _, m| match st {
            "bruteforce" => M { ns: n.sqrt(), ..m },
            _ => m,
        }),
        ("grid-stadium-collapse", |st, _, ratio, m| {
            match (st, ratio) {
                ("bvh8-binned", Some(r)) => M {
                    tests: 8.0 * 0.1 / r,
                    ..m
                },
                _ => m,
            }
        }),
        ("binned-sah", |st, _, _, m| match st {
            "bvh-binned" => M {
                sah: m.sah * 1.2,
                ..m
            },
            _ => m,
        }),
        ("front-to-back", |st, _, _, m| match st {
            "bvh-binned-unordered" => M {
                nodes: m.nodes * 0.5,
                leaves: m.leaves / 3.0,
                ..m
            },
            _ => m,
        }),
        ("kd-early-exit", |st, _, _, m| match st {
            "kd-sah-exhaustive" => M {
                leaves: m.leaves / 3.0 * 1.1,
                ..m
            },
            _ => m,
        }),
        ("grid-best-resolution", |st, _, _, m| match st {
            "grid-fine" => M {
                ns: m.ns / 1.5 * 0.9,
                ..m
            },
            _ => m,
        }),
    ];
    for (id, broken) in cases {
        let report = synthetic(|st, n, r| broken(st, n, r, textbook(st, n, r)));
        for (claim, verdict) in verdicts(&report) {
            let want = if claim == id {
                Verdict::DoesNotHold
            } else {
                Verdict::Holds
            };
            assert_eq!(verdict, want, "{claim} with {id} broken");
        }
    }
}

#[test]
fn a_run_without_the_structures_says_not_measured() {
    for e in evaluate(template()) {
        assert_eq!(e.claim.verdict, Verdict::NotMeasured, "{}", e.claim.id);
        assert!(e.claim.note.as_deref().is_some_and(|n| n.contains("lacks")));
        assert!(e.chart.is_none());
    }
}

/// A real run keeps its claims in report.json and shows them at the top of the page: three
/// teapot sizes decide the BVH's log N claim on this run's own counters.
#[test]
fn a_run_stores_its_claims_and_the_page_shows_them() {
    let dir = std::env::temp_dir().join(format!("raybench-claims-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (code, out, err) = common::invoke(&[
        "run",
        "--scenes",
        "teapot:triangles=256,teapot:triangles=1024,teapot:triangles=4096,teapot:triangles=16384",
        "--structures",
        "bvh-binned",
        "--workloads",
        "primary",
        "--rays",
        "2000",
        "--build-runs",
        "1",
        "--trace-runs",
        "1",
        "--no-images",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let report = Report::read(&dir.join("report.json")).unwrap();
    assert_eq!(report.claims.len(), 8);
    let log_n = report.claims.iter().find(|c| c.id == "bvh-log-n").unwrap();
    assert_ne!(log_n.verdict, Verdict::NotMeasured, "{log_n:#?}");
    assert!(log_n.figures[0].contains("teapot"), "{:?}", log_n.figures);
    let json = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(
        json.contains("\"not_measured\""),
        "verdicts are stored by name"
    );
    let page = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(page.contains("id=\"claims\""), "a Claims section");
    assert!(page.contains("charts/claim-bvh-log-n.svg"));
    assert!(dir.join("charts/claim-bvh-log-n.svg").is_file());
    assert!(page.contains("not measured in this run"));
    std::fs::remove_dir_all(&dir).ok();
}
