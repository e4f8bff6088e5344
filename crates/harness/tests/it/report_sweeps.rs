//! `raybench report` on sweeps: reports whose scenes differ in one generator parameter are
//! drawn as lines against that parameter, with the swept values as tick labels and scene
//! names, fitted exponents for growing scenes, and one colour per structure. The reports are
//! synthetic (one small real run cloned into made-up scenes and numbers), so the exponent
//! every structure should show is known.

use crate::common;

use raybench_harness::output::render::palette::{self, Palette};
use raybench_harness::output::render::render;
use raybench_harness::output::render::sweep::Sweep;
use raybench_harness::pipeline::run::run;
use raybench_harness::report::run::{Report, ResultEntry};
use raybench_scenes::SceneRequest;
use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::sync::OnceLock;

/// One real result to clone: one scene, one counting structure, two ray workloads.
fn template() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        let options = raybench_harness::pipeline::run::RunOptions {
            workloads: raybench_scenes::Workload::ALL[..2].to_vec(),
            rays: 500,
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

/// What one made-up structure measures at one scene.
struct Measured {
    triangles: u64,
    ns_per_ray: f64,
    tests_per_ray: Option<f64>,
    build_ms: f64,
}

/// A report over `scenes` (name, generator, params) and `structures`, each result from
/// `measure(scene index, structure index)`; every timing has three runs 5 % apart.
fn synthetic(
    scenes: &[(String, &str, serde_json::Value)],
    structures: &[&str],
    measure: impl Fn(usize, usize) -> Measured,
) -> Report {
    let t = template();
    let counting = t
        .results
        .iter()
        .find(|r| r.structure == "bvh-binned")
        .unwrap();
    let mut report = t.clone();
    report.run.structures = structures.iter().map(|s| s.to_string()).collect();
    report.scenes.clear();
    report.results.clear();
    for (i, (name, generator, params)) in scenes.iter().enumerate() {
        let mut record = t.scenes[0].clone();
        record.name = name.clone();
        record.source = serde_json::json!({"procedural": {
            "generator": generator, "params": params, "seed": 7
        }});
        for (s, st) in structures.iter().enumerate() {
            let m = measure(i, s);
            record.triangles.loaded = m.triangles;
            record.triangles.traced = m.triangles;
            let mut r: ResultEntry = counting.clone();
            r.scene = name.clone();
            r.structure = st.to_string();
            r.triangles = record.triangles;
            r.primary_image = None;
            r.build.median_ms = m.build_ms;
            r.build.min_ms = m.build_ms * 0.95;
            r.build.max_ms = m.build_ms * 1.05;
            r.build.runs = 3;
            r.memory_bytes = m.triangles * 40;
            for w in &mut r.workloads {
                let mrays = 1e3 / m.ns_per_ray;
                w.mqueries_per_s.median = mrays;
                w.mqueries_per_s.min = mrays * 0.95;
                w.mqueries_per_s.max = mrays * 1.05;
                w.mqueries_per_s.runs = 3;
                w.speedup_vs_reference = Some(1.0 + s as f64 / 10.0);
                match m.tests_per_ray {
                    Some(tests) => {
                        let c = w.counters_per_query.as_mut().unwrap();
                        c.prim_tests = tests;
                    }
                    None => w.counters_per_query = None,
                }
            }
            report.results.push(r);
        }
        report.scenes.push(record);
    }
    report
}

fn draw(report: &Report, tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raybench-sweep-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    render(report, &dir).unwrap();
    dir
}

fn chart(dir: &std::path::Path, file: &str) -> String {
    std::fs::read_to_string(dir.join("charts").join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// Twelve structures, so that a palette of ten would repeat.
const TWELVE: [&str; 12] = [
    "bruteforce",
    "bvh-binned",
    "bvh4-binned",
    "bvh8-binned",
    "kd-sah",
    "grid",
    "grid2",
    "octree",
    "embree-low",
    "embree-medium",
    "embree-high",
    "embree-robust",
];

const RATIOS: [&str; 5] = ["1e-1", "1e-2", "1e-3", "1e-4", "1e-5"];

/// The stadium sweep: one triangle count, the teapot's size ratio from 1e-1 to 1e-5.
fn stadium() -> &'static (Report, PathBuf) {
    static DRAWN: OnceLock<(Report, PathBuf)> = OnceLock::new();
    DRAWN.get_or_init(|| {
        let scenes: Vec<_> = RATIOS
            .iter()
            .map(|r| {
                let v: f64 = r.parse().unwrap();
                (
                    format!("teapot-in-stadium:size_ratio={r}"),
                    "teapot-in-stadium",
                    serde_json::json!({"size_ratio": v, "stadium_triangles": 20000, "teapot_triangles": 4000}),
                )
            })
            .collect();
        let report = synthetic(&scenes, &TWELVE, |i, s| Measured {
            triangles: 24_000,
            ns_per_ray: 100.0 * (1.0 + s as f64) * (1.0 + i as f64),
            tests_per_ray: (s < 8).then_some(10.0 + i as f64),
            build_ms: 5.0 + s as f64,
        });
        let dir = draw(&report, "stadium");
        (report, dir)
    })
}

#[test]
fn a_size_ratio_sweep_is_detected_with_its_values_in_order() {
    let sweep = Sweep::detect(&stadium().0).expect("a sweep");
    assert_eq!(sweep.key, "size_ratio");
    assert_eq!(sweep.generator, "teapot-in-stadium");
    let labels: Vec<&str> = sweep.points.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "size_ratio=1e-5",
            "size_ratio=1e-4",
            "size_ratio=1e-3",
            "size_ratio=1e-2",
            "size_ratio=1e-1"
        ]
    );
    assert!(sweep.log_x(), "five decades are drawn on a log axis");
    assert!(!sweep.is_size_sweep(), "every scene has the same triangles");
}

#[test]
fn sweep_charts_are_lines_against_the_swept_values() {
    let dir = &stadium().1;
    for file in [
        "build-ms.svg",
        "ratio-build.svg",
        "mrays-random.svg",
        "ratio-random.svg",
        "memory-per-triangle.svg",
        "counters-random.svg",
    ] {
        let svg = chart(dir, file);
        assert!(
            svg.contains("against size_ratio"),
            "{file} is not drawn against the parameter"
        );
        for tick in [">1e-5<", ">1e-3<", ">0.1<"] {
            assert!(svg.contains(tick), "{file} lacks the tick label {tick}");
        }
        assert!(
            svg.contains("<title>teapot-in-stadium:size_ratio=1e-3 (24000 triangles)</title>"),
            "{file}: a tick does not name its scene on hover"
        );
        // The background is the only rectangle: no bars.
        assert_eq!(svg.matches("<rect").count(), 1, "{file} draws bars");
        assert!(
            svg.contains("size_ratio of teapot-in-stadium"),
            "{file} has no x axis name"
        );
    }
    // Every structure is one line of five points, with an error bar and two caps at each.
    let svg = chart(dir, "mrays-random.svg");
    let colours = legend_colours(&svg);
    for st in TWELVE {
        let c = colours[st].to_uppercase();
        let bars = svg
            .lines()
            .filter(|l| l.contains(&format!("stroke=\"{c}\" stroke-width=\"1\"")))
            .count();
        assert_eq!(bars, 15, "{st}: error bars of five points");
    }
    // The break-even charts name their scene by its value.
    let be = chart(dir, "break-even-teapot-in-stadium-size-ratio-1e-3.svg");
    assert!(be.contains("size_ratio=1e-3: build + trace K rays"), "{be}");
}

/// (structure, colour) of each legend entry, in the legend's own drawing: a line swatch in the
/// structure's colour, then its name.
fn legend_colours(svg: &str) -> HashMap<String, String> {
    let mut out = HashMap::new();
    let mut last = None;
    for line in svg.lines() {
        if line.starts_with("<line") && line.contains("stroke-width=\"2\"") {
            let at = line.find("stroke=\"").unwrap() + 8;
            last = Some(line[at..at + 7].to_string());
        } else if let Some(text) = line.strip_prefix("<text").and_then(|l| l.split('>').nth(1))
            && let Some(name) = text.strip_suffix("</text")
            && let Some(c) = last.take()
        {
            out.insert(name.to_string(), c);
        }
    }
    out
}

#[test]
fn twelve_structures_have_twelve_colours_the_same_in_every_chart() {
    let (report, dir) = stadium();
    let palette = Palette::for_report(report);
    let colours: BTreeSet<_> = TWELVE
        .iter()
        .map(|s| palette::hex(palette.color(s)))
        .collect();
    assert_eq!(colours.len(), 12, "two structures share a colour");
    let build = legend_colours(&chart(dir, "build-ms.svg"));
    let mrays = legend_colours(&chart(dir, "mrays-random.svg"));
    let distinct: BTreeSet<&String> = TWELVE.iter().map(|s| &build[*s]).collect();
    assert_eq!(distinct.len(), 12, "the legend repeats a colour: {build:?}");
    for st in TWELVE {
        assert_eq!(build[st], mrays[st], "{st} changes colour between charts");
    }
}

#[test]
fn the_legend_sits_right_of_the_plot() {
    let svg = chart(&stadium().1, "mrays-random.svg");
    // The plot's frame ends before the legend column (230 px of 1100) begins.
    let plot_right = svg
        .lines()
        .filter(|l| l.starts_with("<polyline") && l.contains("stroke=\"#000000\""))
        .flat_map(|l| l.split("points=\"").nth(1).unwrap().split(' '))
        .filter_map(|p| p.split(',').next()?.parse::<f64>().ok())
        .fold(0.0, f64::max);
    let legend_x = svg
        .lines()
        .filter(|l| l.starts_with("<text") && l.contains(">bvh-binned</text>"))
        .map(|l| {
            let at = l.find("x=\"").unwrap() + 3;
            l[at..].split('"').next().unwrap().parse::<f64>().unwrap()
        })
        .next()
        .expect("bvh-binned is in the legend");
    assert!(
        plot_right < 870.0 && legend_x > plot_right,
        "{plot_right} {legend_x}"
    );
}

const SIZES: [u64; 4] = [1000, 10_000, 100_000, 1_000_000];

/// A triangle-count sweep whose structures follow known power laws: time per ray ∝ N^(1/3)
/// with a deterministic wobble of a few per cent, triangle tests ∝ N^(1/3) for the first
/// structure and flat (∝ N^0) for the rest, builds ∝ N.
fn spheres() -> &'static (Report, PathBuf) {
    static DRAWN: OnceLock<(Report, PathBuf)> = OnceLock::new();
    DRAWN.get_or_init(|| {
        let scenes: Vec<_> = SIZES
            .iter()
            .map(|n| {
                (
                    format!("sphere:triangles={n}"),
                    "sphere",
                    serde_json::json!({"radius": 1.0, "triangles": n}),
                )
            })
            .collect();
        let report = synthetic(&scenes, &["grid", "bvh-binned", "embree-medium"], |i, s| {
            let n = SIZES[i] as f64;
            let wobble = 1.0 + 0.03 * ((i * 3 + s) as f64 * 1.7).sin();
            Measured {
                triangles: SIZES[i],
                ns_per_ray: 40.0 * n.powf(1.0 / 3.0) * wobble,
                tests_per_ray: match s {
                    0 => Some(2.0 * n.powf(1.0 / 3.0)),
                    1 => Some(12.0),
                    _ => None,
                },
                build_ms: n / 1e4,
            }
        });
        let dir = draw(&report, "spheres");
        (report, dir)
    })
}

/// Every "grid: b = 0.33 ± 0.04" of `structure` in `svg` as (0.33, 0.04), in drawing order:
/// the legends come panel by panel (build, time per ray, triangle tests per ray). A hover title
/// repeating a cut legend text is not counted.
fn fits(svg: &str, structure: &str) -> Vec<(f64, f64)> {
    svg.match_indices(&format!(">{structure}: b = "))
        .filter(|(at, _)| !svg[..*at].ends_with("<title"))
        .map(|(at, _)| {
            let text = svg[at + 1..].split('<').next().unwrap();
            let (b, hw) = text
                .split_once("b = ")
                .unwrap()
                .1
                .split_once(" ± ")
                .unwrap();
            let hw = hw.split(' ').next().unwrap();
            (b.parse().unwrap(), hw.parse().unwrap())
        })
        .collect()
}

#[test]
fn a_triangle_sweep_fits_the_exponent_of_its_power_law() {
    let (report, dir) = spheres();
    let sweep = Sweep::detect(report).unwrap();
    assert_eq!(sweep.key, "triangles");
    assert!(sweep.is_size_sweep());
    let svg = chart(dir, "scaling.svg");
    for panel in [
        "build time against triangles",
        "Time per ray against triangles",
        "Triangle tests per ray against triangles",
    ] {
        assert!(svg.contains(panel), "scaling.svg lacks the panel {panel:?}");
    }
    let grid = fits(&svg, "grid");
    let bvh = fits(&svg, "bvh-binned");
    let embree = fits(&svg, "embree-medium");
    assert_eq!(grid.len(), 3, "{grid:?}");
    assert_eq!(bvh.len(), 3, "{bvh:?}");
    assert_eq!(
        embree.len(),
        2,
        "Embree counts no tests, so it has no tests line: {embree:?}"
    );
    // Builds ∝ N, exactly.
    for f in [grid[0], bvh[0], embree[0]] {
        assert_eq!(f, (1.0, 0.0));
    }
    // Time per ray: N^(1/3) with a ±3 % wobble, every structure.
    for (st, (b, hw)) in [
        ("grid", grid[1]),
        ("bvh-binned", bvh[1]),
        ("embree-medium", embree[1]),
    ] {
        assert!((b - 0.33).abs() < 0.02, "{st}: b = {b}");
        assert!(hw > 0.0 && hw < 0.1, "{st}: ± {hw}");
    }
    // Triangle tests: N^(1/3) exactly for the grid, flat for the BVH.
    assert_eq!(grid[2], (0.33, 0.0));
    assert_eq!(bvh[2], (0.0, 0.0));
    // Theory curves, each with its own dash pattern, labelled with their exponents.
    for label in [
        "∝ log N: b ≈ 0",
        "∝ N^(1/3): b = 0.33",
        "∝ N: b = 1",
        "∝ N log N",
    ] {
        assert!(svg.contains(label), "scaling.svg lacks {label}");
    }
    let dashes: BTreeSet<&str> = svg
        .match_indices("stroke-dasharray=\"")
        .map(|(i, _)| svg[i + 18..].split('"').next().unwrap())
        .collect();
    assert_eq!(dashes.len(), 4, "{dashes:?}");
    // The page tables the same fits.
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("Scaling exponents"));
    assert!(
        html.contains("<td>0.33 ± 0.00</td>"),
        "grid's tests per ray"
    );
    assert!(html.contains("A sweep of <b>triangles</b>"));
}

#[test]
fn triangle_counts_are_short_tick_labels() {
    let dir = &spheres().1;
    for file in ["scaling.svg", "mrays-random.svg", "build-ms.svg"] {
        let svg = chart(dir, file);
        for tick in [">1k<", ">10k<", ">100k<", ">1M<"] {
            assert!(svg.contains(tick), "{file} lacks the tick label {tick}");
        }
        assert!(!svg.contains("1.000k") && !svg.contains("e+"), "{file}");
    }
}

/// Two generators, or two keys changing at once, are not a sweep: those reports keep bars.
#[test]
fn mixed_scenes_are_no_sweep() {
    let params = |r: f64, t: u64| serde_json::json!({"size_ratio": r, "teapot_triangles": t});
    let two_keys: Vec<_> = [(1e-1, 1000), (1e-2, 2000), (1e-3, 3000)]
        .iter()
        .map(|&(r, t)| (format!("s:r={r},t={t}"), "teapot-in-stadium", params(r, t)))
        .collect();
    let report = synthetic(&two_keys, &["bvh-binned"], |_, _| Measured {
        triangles: 100,
        ns_per_ray: 10.0,
        tests_per_ray: Some(3.0),
        build_ms: 1.0,
    });
    assert_eq!(Sweep::detect(&report), None);
    let mut mixed = two_keys.clone();
    mixed[2].1 = "sphere";
    let report = synthetic(&mixed, &["bvh-binned"], |_, _| Measured {
        triangles: 100,
        ns_per_ray: 10.0,
        tests_per_ray: Some(3.0),
        build_ms: 1.0,
    });
    assert_eq!(Sweep::detect(&report), None);
    let dir = draw(&report, "mixed");
    assert!(
        chart(&dir, "build-ms.svg").matches("<rect").count() > 3,
        "bars per scene"
    );
}
