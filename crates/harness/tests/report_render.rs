//! `raybench report`: every chart type from a real (small) report, heatmap sizes and value
//! range, a static page without scripts, and — where Debian's Chromium is installed — the page
//! and a chart rendered headless to a screenshot that is not blank.

mod common;

use raybench_harness::output::render::sweep::Sweep;
use raybench_harness::output::render::{pictures, render};
use raybench_harness::pipeline::run::run;
use raybench_harness::report::run::Report;
use raybench_scenes::SceneRequest;
use std::path::{Path, PathBuf};
use std::process::Command;
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

fn rendered() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("raybench-render-{}", std::process::id()));
        render(report(), &dir).unwrap();
        dir
    })
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
        ("agreement.svg", "Rays per agreement class"),
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

fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
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
        let path = rendered().join(format!(
            "images/sphere-triangles-2000--{}-render.png",
            r.structure
        ));
        let (w, h, _) = decode(&path);
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

#[test]
fn the_page_is_static_and_links_everything_it_shows() {
    let html = std::fs::read_to_string(rendered().join("index.html")).unwrap();
    assert!(!html.to_lowercase().contains("<script"));
    for needle in [
        "charts/build-ms.svg",
        "charts/scaling.svg",
        "images/legend-viridis.png",
        "cpu_model",
        "0 mismatches",
    ] {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
    for src in html
        .split("src=\"")
        .skip(1)
        .map(|s| &s[..s.find('"').unwrap()])
    {
        assert!(
            rendered().join(src).is_file(),
            "index.html links a missing file {src}"
        );
    }
}

#[test]
fn the_page_opens_with_the_answer_per_scene_and_the_geometric_means() {
    let html = std::fs::read_to_string(rendered().join("index.html")).unwrap();
    let answer = html.find("id=\"answer\"").expect("an answer section");
    let results = html.find("<h2>Results</h2>").expect("a results table");
    assert!(answer < results, "the answer comes before the tables");
    let section = &html[answer..html.find("id=\"summary\"").expect("a summary table")];
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
    // The geometric means: every structure but the reference, with its build ratio.
    let summary = &html[html.find("id=\"summary\"").unwrap()..results];
    assert!(summary.contains(">bvh-binned<") && summary.contains(">bruteforce<"));
    assert!(!summary.contains(">embree-medium</td>"));
}

/// Debian's Chromium, if installed (scripts/test installs it).
fn chromium() -> Option<PathBuf> {
    [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ]
    .into_iter()
    .map(PathBuf::from)
    .find(|p| p.is_file())
}

fn screenshot(browser: &Path, url: &str, out: &Path, size: &str) -> (u32, u32, Vec<u8>) {
    let status = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
        ])
        .arg(format!("--window-size={size}"))
        .arg(format!("--screenshot={}", out.display()))
        .arg(url)
        .output()
        .unwrap();
    assert!(
        out.is_file(),
        "no screenshot of {url}: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    decode(out)
}

fn distinct_colours(px: &[u8], channels: usize) -> usize {
    let mut c: Vec<&[u8]> = px.chunks(channels).map(|p| &p[..3]).collect();
    c.sort_unstable();
    c.dedup();
    c.len()
}

#[test]
fn headless_chromium_renders_the_page_and_a_chart() {
    let Some(browser) = chromium() else {
        eprintln!(
            "NOT RUN: Chromium is not installed (scripts/test installs Debian's `chromium`); the page \
             and charts were checked as files only"
        );
        return;
    };
    let dir = rendered();
    let page = format!("file://{}", dir.join("index.html").display());
    let (w, h, px) = screenshot(&browser, &page, &dir.join("shot-page.png"), "1280,2400");
    assert_eq!((w, h), (1280, 2400));
    let channels = px.len() / (w * h) as usize;
    assert!(
        distinct_colours(&px, channels) > 50,
        "the page screenshot is (nearly) blank"
    );
    let chart = format!("file://{}", dir.join("charts/build-ms.svg").display());
    let (w, h, px) = screenshot(&browser, &chart, &dir.join("shot-chart.png"), "1100,520");
    let channels = px.len() / (w * h) as usize;
    assert!(
        distinct_colours(&px, channels) > 8,
        "the chart screenshot is (nearly) blank"
    );
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
