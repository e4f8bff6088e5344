//! `raybench report`: every chart type from a real (small) report, heatmap sizes and value
//! range, the site's pages (a short summary with the answer, the geometric means with their
//! spread and the claims; a page per scene; charts; details with a readable environment),
//! static but for the table-sorting script. The same pages in a browser: `report_browser`.

use crate::common;

use raybench_harness::output::render::sweep::Sweep;
use raybench_harness::output::render::{pictures, render};
use raybench_harness::pipeline::run::run;
use raybench_harness::report::claims::{Claim, Verdict};
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Three sphere sizes (so the scaling chart appears) and a plane (so the report sweeps no
/// parameter and keeps its bar charts), two structures with counters and Embree.
fn report() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        let options = raybench_harness::pipeline::run::RunOptions {
            workloads: raybench_scenes::Workload::ALL[..2].to_vec(),
            rays: 2000,
            ..common::options(&["bruteforce", "bvh-binned", "embree-medium"])
        };
        let scenes = [
            "sphere:triangles=500",
            "sphere:triangles=2000",
            "sphere:triangles=8000",
            "plane:quads=8",
        ]
        .map(|s| SceneRequest::Spec(s.into()));
        run(&options, &scenes).unwrap()
    })
}

/// The report with two claims, as the summary page shows them.
fn with_claims() -> Report {
    let mut r = report().clone();
    let claim = |id: &str, verdict| Claim {
        id: id.into(),
        statement: format!("Claim {id} <with markup> holds"),
        rule: "a rule & its threshold".into(),
        verdict,
        figures: vec!["1.2 against 1.0".into()],
        note: None,
    };
    r.claims = vec![
        claim("first", Verdict::Holds),
        claim("second", Verdict::NotMeasured),
    ];
    r
}

pub(crate) fn rendered() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("raybench-render-{}", std::process::id()));
        render(&with_claims(), &dir).unwrap();
        dir
    })
}

fn page(name: &str) -> String {
    std::fs::read_to_string(rendered().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every page the summary links: (scene, file), from the answer table's first column.
fn scene_pages() -> Vec<(String, String)> {
    let html = page("index.html");
    let answer = &html[html.find("id=\"answer\"").unwrap()..];
    let answer = &answer[..answer.find("</table>").unwrap()];
    answer
        .split("<td class=\"l\"><a href=\"")
        .skip(1)
        .map(|s| {
            let file = &s[..s.find('"').unwrap()];
            let name = &s[s.find('>').unwrap() + 1..s.find("</a>").unwrap()];
            (name.to_string(), file.to_string())
        })
        .collect()
}

/// The text between `start` and the next `end` after it.
fn between<'a>(html: &'a str, start: &str, end: &str) -> &'a str {
    let from = html.find(start).unwrap_or_else(|| panic!("no {start:?}"));
    let rest = &html[from..];
    &rest[..rest.find(end).unwrap_or(rest.len())]
}

#[test]
fn every_chart_type_is_drawn() {
    let dir = rendered().join("charts");
    for (file, title) in [
        ("build-ms.svg", "Build time"),
        ("ratio-build.svg", "Build time / embree-medium"),
        ("mrays-primary.svg", "primary: Mrays/s"),
        ("ratio-random.svg", "random: Mrays/s / embree-medium"),
        ("memory-per-triangle.svg", "Memory per triangle"),
        ("counters-primary.svg", "nodes per ray"),
        ("scaling.svg", "N log N"),
        (
            "break-even-sphere-triangles-2000.svg",
            "build + trace K rays",
        ),
        ("agreement.svg", "within tolerance: "),
    ] {
        let svg = std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(svg.starts_with("<svg"), "{file} is not an SVG");
        assert!(svg.contains(title), "{file} lacks its title {title:?}");
        assert!(
            svg.matches("<rect").count() + svg.matches("<polyline").count() > 3,
            "{file} draws nothing"
        );
    }
}

/// A report of unrelated scenes is no sweep: bars per scene, each group labelled with its
/// scene and naming it in full on hover, the legend right of the plot.
#[test]
fn a_report_without_a_sweep_draws_bars_labelled_by_scene() {
    assert_eq!(Sweep::detect(report()), None);
    let svg = std::fs::read_to_string(rendered().join("charts/mrays-random.svg")).unwrap();
    for scene in ["sphere:triangles=500", "plane:quads=8"] {
        assert!(
            svg.contains(&format!("<title>{scene}</title>{scene}</text>")),
            "{scene} is not a group label with its hover title"
        );
    }
    // A bar per scene and structure (4 × 3), each with a hover rectangle, and one hover
    // rectangle per group.
    let bars = svg
        .lines()
        .filter(|l| l.starts_with("<rect") && l.contains("opacity=\"1\""))
        .count();
    assert_eq!(bars, 1 + 12, "the background and twelve bars");
    assert_eq!(svg.matches("fill-opacity=\"0\"><title>").count(), 4 + 12);
    assert!(svg.contains("<title>bvh-binned, sphere:triangles=2000: "));
}

pub(crate) fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn heatmaps_have_the_image_size_and_span_the_shared_scale() {
    let scene = "sphere:triangles=2000";
    let entries: Vec<_> = report()
        .results
        .iter()
        .filter(|r| r.scene == scene)
        .collect();
    let images: Vec<_> = entries
        .iter()
        .filter_map(|r| r.primary_image.as_ref())
        .collect();
    assert_eq!(images.len(), 3, "every structure has a primary image");
    let max = pictures::shared_max(&images);
    for r in entries {
        let img = r.primary_image.as_ref().unwrap();
        let costs = img.cost_values().unwrap();
        assert_eq!(
            costs.is_some(),
            r.structure != "embree-medium",
            "{}",
            r.structure
        );
        // One render per scene (the reference's hits), at the stored planes' size.
        let (w, h, _) = decode(&rendered().join("images/sphere-triangles-2000--render.png"));
        assert_eq!((w, h), (img.width, img.height));
        let Some(costs) = costs else { continue };
        assert!(costs.iter().all(|&c| c <= max));
        let (w, h, px) = decode(&rendered().join(format!(
            "images/sphere-triangles-2000--{}-cost.png",
            r.structure
        )));
        assert_eq!((w, h), (img.width, img.height));
        let colours: Vec<[u8; 3]> = px.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        assert!(
            colours.iter().all(|c| c[2] >= 30),
            "viridis never has little blue: {:?}",
            &colours[..3]
        );
        if costs.contains(&max) {
            assert!(
                colours.contains(&pictures::viridis(1.0)),
                "the top of the scale appears"
            );
        }
    }
    // Brute force tests every triangle for every ray: its cost is flat and the largest.
    let brute = report()
        .results
        .iter()
        .find(|r| r.scene == scene && r.structure == "bruteforce");
    let brute = brute
        .unwrap()
        .primary_image
        .as_ref()
        .unwrap()
        .cost_values()
        .unwrap()
        .unwrap();
    assert_eq!(*brute.iter().max().unwrap(), max);
}

const PAGES: [&str; 3] = ["index.html", "charts.html", "details.html"];

fn all_pages() -> Vec<String> {
    PAGES
        .iter()
        .map(|p| p.to_string())
        .chain(scene_pages().into_iter().map(|(_, f)| f))
        .collect()
}

/// Static files: the only script is the inline one that sorts tables; every image and page a
/// page links exists.
#[test]
fn the_pages_are_static_and_link_everything_they_show() {
    for name in all_pages() {
        let html = page(&name);
        assert_eq!(html.matches("<script").count(), 1, "{name}");
        let script = between(&html, "<script>", "</script>");
        assert!(script.contains("table.sortable"), "{name}: {script}");
        for (attr, what) in [("src=\"", "file"), ("href=\"", "page")] {
            for link in html.split(attr).skip(1).map(|s| &s[..s.find('"').unwrap()]) {
                let link = link.split('#').next().unwrap();
                if link.is_empty() {
                    continue;
                }
                assert!(!link.contains("://"), "{name} links outside: {link}");
                assert!(
                    rendered().join(link).is_file(),
                    "{name} links a missing {what} {link}"
                );
            }
        }
        for other in PAGES {
            assert!(
                html.contains(&format!("href=\"{other}\"")) || other == name,
                "{name} has no link to {other}"
            );
        }
    }
    assert!(page("details.html").contains(">CPU<"));
    assert!(page("index.html").contains("0 mismatches"));
    let charts = page("charts.html");
    for chart in [
        "charts/build-ms.svg",
        "charts/scaling.svg",
        "charts/agreement.svg",
    ] {
        assert!(charts.contains(chart), "charts.html lacks {chart}");
    }
    assert!(
        !charts.contains("charts/break-even-"),
        "break-even charts belong on their scene's page"
    );
}

/// The summary: the TOC, the answer per scene, the geometric means with their spread, the
/// claims, and a link to every scene's page; no results table, no chart.
#[test]
fn the_summary_opens_with_the_answer_and_the_geometric_means_with_their_spread() {
    let html = page("index.html");
    let toc = between(&html, "On this page:", "</p>");
    for id in ["#answer", "#geomeans", "#claims", "#more"] {
        assert!(toc.contains(id), "the table of contents lacks {id}");
        assert!(
            html.contains(&format!("id=\"{}\"", &id[1..])),
            "no section {id}"
        );
    }
    let answer = html.find("id=\"answer\"").expect("an answer section");
    let geomeans = html.find("id=\"geomeans\"").expect("a geomeans section");
    let claims = html.find("id=\"claims\"").expect("a claims section");
    assert!(answer < geomeans && geomeans < claims);
    assert!(!html.contains("<img"), "the summary draws no chart");
    assert!(!html.contains("class=\"sortable results\""));
    let section = between(&html, "id=\"answer\"", "</table>");
    // One row per scene, each naming the fastest structure of each workload in bold.
    for scene in [
        "sphere:triangles=500",
        "sphere:triangles=8000",
        "plane:quads=8",
    ] {
        let row = section
            .split("<tr>")
            .find(|r| r.contains(&format!(">{scene}<")))
            .unwrap_or_else(|| panic!("no answer row for {scene}"));
        assert_eq!(row.matches("<b>").count(), 2, "{row}");
        assert!(
            ["bvh-binned", "embree-medium", "bruteforce"]
                .iter()
                .any(|s| row.contains(&format!("<b>{s}</b>"))),
            "{row}"
        );
    }
    // The geometric means: every structure but the reference, each cell with its range over
    // the four scenes.
    let means = between(&html, "id=\"geomeans\"", "</table>");
    assert!(means.contains("class=\"sortable geomeans\""));
    assert!(means.contains(">bvh-binned<") && means.contains(">bruteforce<"));
    assert!(!means.contains(">embree-medium</td>"));
    let bvh = means
        .split("<tr>")
        .find(|r| r.contains(">bvh-binned<"))
        .unwrap();
    assert_eq!(bvh.matches("<small>").count(), 2 + 2, "{bvh}");
    assert!(bvh.contains("lowest") && bvh.contains("highest"), "{bvh}");
    // The claims, escaped.
    let claims = between(&html, "id=\"claims\"", "</table>");
    assert!(
        claims.contains("Claim first &lt;with markup&gt; holds"),
        "{claims}"
    );
    assert!(claims.contains("not measured in this run"), "{claims}");
    // A link to every scene's page.
    let linked: Vec<String> = scene_pages().into_iter().map(|(s, _)| s).collect();
    let scenes: Vec<String> = report().scenes.iter().map(|s| s.name.clone()).collect();
    assert_eq!(linked, scenes);
}

/// Each scene's page holds that scene's rows of the results, and only them, its break-even
/// chart and its pictures.
#[test]
fn every_scene_has_a_page_with_its_rows_chart_and_pictures() {
    for (scene, file) in scene_pages() {
        assert!(
            file.starts_with("scene-") && !file.contains('/'),
            "{file}: scene pages sit beside index.html"
        );
        let html = page(&file);
        assert!(
            html.contains(&format!("<h1>raybench report: {scene}</h1>")),
            "{file}"
        );
        let results: Vec<_> = report()
            .results
            .iter()
            .filter(|r| r.scene == scene)
            .collect();
        let table = between(&html, "class=\"sortable results\"", "</table>");
        let rows: Vec<&str> = table.split("<tr>").skip(2).collect();
        assert_eq!(rows.len(), results.len(), "{file}");
        for r in &results {
            let row = rows
                .iter()
                .find(|row| row.starts_with(&format!("<td class=\"l st\">{}</td>", r.structure)))
                .unwrap_or_else(|| panic!("{file} has no row for {}", r.structure));
            assert!(
                row.contains(&format!("<td>{}</td>", r.triangles.traced)),
                "{file}: {row}"
            );
        }
        assert!(html.contains("charts/break-even-"), "{file}");
        assert!(html.contains("images/"), "{file} shows no picture");
        assert!(html.contains("href=\"index.html\""), "{file}");
    }
}

/// Tables of figures sort; the environment is a table of labelled values, not JSON.
#[test]
fn tables_sort_and_the_environment_reads_as_a_table() {
    let details = page("details.html");
    for class in ["sortable results", "sortable agreement"] {
        assert!(
            details.contains(&format!("<table class=\"{class}\"><thead>")),
            "{class}"
        );
    }
    let env = between(&details, "<table class=\"environment\">", "</table>");
    for c in ['{', '}', '['] {
        assert!(!env.contains(c), "raw JSON in the environment table: {env}");
    }
    for label in [
        ">Machine<",
        ">CPU<",
        ">Embree<",
        ">Run settings<",
        ">units in the last place<",
    ] {
        assert!(env.contains(label), "the environment lacks {label}");
    }
    let structures = report().run.structures.join(", ");
    assert!(env.contains(&structures), "lists are joined: {structures}");
}

/// The validation chart shows every class, each on its own linear scale: classes far smaller
/// than the largest still get bars.
#[test]
fn the_agreement_chart_draws_every_class() {
    let svg = std::fs::read_to_string(rendered().join("charts/agreement.svg")).unwrap();
    for class in [
        "both miss",
        "exact",
        "within tolerance",
        "tie",
        "boundary",
        "edge ambiguous",
        "mismatch",
    ] {
        // plotters writes a caption's text on a line of its own.
        assert!(
            svg.contains(&format!("\n{class}: ")),
            "no panel for {class}"
        );
    }
    let with_bars = [
        "both miss",
        "exact",
        "within tolerance",
        "tie",
        "edge ambiguous",
    ]
    .iter()
    .filter(|c| svg.contains(&format!("<title>{c}, ")))
    .count();
    assert!(with_bars >= 2, "only the largest class has bars");
}

/// The break-even chart marks where the fastest tracer starts to win, with its ray count.
#[test]
fn the_break_even_chart_marks_its_crossing_with_a_ray_count() {
    let marked = scene_pages()
        .iter()
        .filter_map(|(_, file)| {
            let html = page(file);
            let src = between(&html, "charts/break-even-", "\"").to_string();
            std::fs::read_to_string(rendered().join(src)).ok()
        })
        .filter(|svg| svg.contains("<title>From ") && svg.contains(" rays</text>"))
        .count();
    assert!(marked > 0, "no break-even chart marks its crossing");
}

/// Any finite value a report may hold is drawn: speedups of 5e-324 and 1.7e308, build times of
/// 1e-300 ms and throughputs at both ends of f64 once hung the chart axes (an infinite log
/// axis has no last tick). The report goes through JSON first, as `raybench report` reads it.
#[test]
fn extreme_finite_values_are_drawn() {
    let mut extreme = report().clone();
    let ends = [5e-324, 1.7e308, 1e-300, f64::MAX, f64::MIN_POSITIVE];
    for (i, r) in extreme.results.iter_mut().enumerate() {
        let v = ends[i % ends.len()];
        r.build.median_ms = v;
        r.build_ratio_to_reference = Some(ends[(i + 1) % ends.len()]);
        r.memory_bytes = u64::MAX;
        for (k, w) in r.workloads.iter_mut().enumerate() {
            w.mqueries_per_s.median = ends[(i + k) % ends.len()];
            w.speedup_vs_reference = Some(ends[(i + k + 2) % ends.len()]);
        }
    }
    let dir = std::env::temp_dir().join(format!("raybench-extreme-{}", std::process::id()));
    let path = extreme.write_atomic(&dir).unwrap();
    let back = Report::read(&path).unwrap();
    let drawn = render(&back, &dir).unwrap();
    assert!(drawn.index.exists() && !drawn.charts.is_empty());
    std::fs::remove_dir_all(&dir).ok();
}
