//! The pages of `raybench report` rendered by headless Chromium where Debian's package is
//! installed (scripts/test installs it): not blank, the summary a few screens tall, the claims
//! and the summary table in the rendered document, the scene pages' pictures at full size.

use crate::common;
use crate::report_render::{decode, rendered};
use raybench_harness::output::render::render;
use raybench_harness::pipeline::run::run;
use raybench_scenes::SceneRequest;
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// What a browser makes of a page at 1280 pixels wide: the document as rendered, its height
/// and the natural width of each `img.picture`. A copy of the page, beside it so its links
/// resolve, gets a script that writes both into an element once everything has loaded.
struct Measured {
    dom: String,
    height: u32,
    picture_widths: Vec<u32>,
}

fn measure(browser: &Path, page: &Path) -> Measured {
    let html = std::fs::read_to_string(page).unwrap();
    let probe = "<script>window.addEventListener('load', function () {\
        var h = document.documentElement.scrollHeight;\
        var w = Array.from(document.querySelectorAll('img.picture')).map(function (i) { return i.naturalWidth; });\
        var e = document.createElement('pre'); e.id = 'raybench-measured';\
        e.textContent = 'height=' + h + ';pictures=' + w.join(',') + ';';\
        document.body.appendChild(e); });</script></body>";
    assert!(html.contains("</body>"), "{}", page.display());
    let copy = page.with_file_name(format!(
        ".measure-{}",
        page.file_name().unwrap().to_string_lossy()
    ));
    std::fs::write(&copy, html.replace("</body>", probe)).unwrap();
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--window-size=1280,1080",
            "--virtual-time-budget=3000",
            "--dump-dom",
        ])
        .arg(format!("file://{}", copy.display()))
        .output()
        .unwrap();
    std::fs::remove_file(&copy).ok();
    let dom = String::from_utf8_lossy(&out.stdout).into_owned();
    let measured = dom
        .split("id=\"raybench-measured\">")
        .nth(1)
        .and_then(|s| s.split('<').next())
        .unwrap_or_else(|| {
            panic!(
                "{} was not measured: {}",
                page.display(),
                String::from_utf8_lossy(&out.stderr)
            )
        })
        .to_string();
    let field = |name: &str| {
        measured
            .split(&format!("{name}="))
            .nth(1)
            .and_then(|s| s.split(';').next())
            .unwrap_or_default()
            .to_string()
    };
    Measured {
        height: field("height").parse().unwrap(),
        picture_widths: field("pictures")
            .split(',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect(),
        dom,
    }
}

/// Screens of 1080 pixels the summary may take at 1280 pixels wide.
const SUMMARY_SCREENS: u32 = 4;

/// In a browser the summary shows the claims and the summary table and stays a few screens
/// tall; the scene pages show their pictures at full size (at least 640 pixels wide).
#[test]
fn headless_chromium_finds_a_short_summary_and_full_size_pictures() {
    let Some(browser) = chromium() else {
        eprintln!("NOT RUN: Chromium is not installed; the pages were checked as files only");
        return;
    };
    let dir = rendered();
    let summary = measure(&browser, &dir.join("index.html"));
    assert!(summary.dom.contains("id=\"claims\""), "no claims section");
    assert!(
        summary.dom.contains("<table class=\"claims\">"),
        "no claims table"
    );
    assert!(
        summary.dom.contains("class=\"sortable geomeans\""),
        "no summary table"
    );
    // The sorting script ran: every header of a sortable table can be focused.
    assert!(summary.dom.contains("title=\"sort by this column\""));
    eprintln!("the summary is {} pixels tall", summary.height);
    assert!(
        summary.height <= SUMMARY_SCREENS * 1080,
        "the summary is {} pixels tall, more than {SUMMARY_SCREENS} screens",
        summary.height
    );
    // The pictures at full size come from a run that drew them (the report above keeps only
    // its small planes): one scene, a counting structure and Embree, 640 pixels wide.
    let dir = std::env::temp_dir().join(format!("raybench-render-full-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let options = raybench_harness::pipeline::run::RunOptions {
        workloads: vec![raybench_scenes::Workload::Primary],
        rays: 2000,
        picture_dir: Some(dir.clone()),
        picture_width: 640,
        ..common::options(&["bvh-binned", "embree-medium"])
    };
    let full = run(
        &options,
        &[SceneRequest::Spec("sphere:triangles=2000".into())],
    )
    .unwrap();
    render(&full, &dir).unwrap();
    let scene = dir.join("scene-sphere-triangles-2000.html");
    let widths = measure(&browser, &scene).picture_widths;
    assert!(!widths.is_empty(), "no img.picture on {}", scene.display());
    assert!(
        widths.iter().all(|&w| w >= 640),
        "pictures narrower than 640 pixels: {widths:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
