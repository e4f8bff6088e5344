//! Full-resolution pictures: `raybench run` writes them at `--picture-width` (one render per
//! scene, a heatmap per counting structure on one scale per scene, masks only where a
//! structure disagrees) without changing a timed workload's counters or agreement;
//! `raybench report` copies them with a report, or draws the small planes and says so.

use crate::common::{files_below, invoke, scratch};
use raybench_harness::report::run::Report;
use std::path::Path;

const SCENES: &str = "sphere:triangles=500,plane:quads=4";
const STRUCTURES: &str = "bvh-binned,grid,embree-medium";

fn run(out: &Path, extra: &[&str]) -> Report {
    let out_arg = out.display().to_string();
    let mut args = vec![
        "run",
        "--scenes",
        SCENES,
        "--structures",
        STRUCTURES,
        "--workloads",
        "primary,shadow",
        "--rays",
        "1000",
        "--build-runs",
        "1",
        "--trace-runs",
        "1",
        "--out",
        &out_arg,
    ];
    args.extend_from_slice(extra);
    let (code, _, stderr) = invoke(&args);
    assert_eq!(code, 0, "{stderr}");
    Report::read(&out.join("report.json")).unwrap()
}

fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let info = decoder.read_info().unwrap();
    (info.info().width, info.info().height)
}

fn png_pixels(path: &Path) -> Vec<[u8; 3]> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// The default width is 640: every file is 640 × 480, exactly the files the report lists are
/// in images/, one render per scene, heatmaps for the counting structures only, masks only
/// for disagreeing ones; the scene's maximum cost reaches the top colour in some heatmap.
/// The page shows each at display size, linked to the file, with the scale's numbers.
#[test]
fn a_run_writes_full_size_pictures_one_render_per_scene() {
    let dir = scratch("pictures-default");
    let out = dir.join("run");
    let report = run(&out, &[]);
    assert_eq!(report.pictures.len(), 2, "one picture set per scene");
    let mut listed = Vec::new();
    for set in &report.pictures {
        assert_eq!((set.width, set.height), (640, 480));
        assert_eq!(set.reference, "embree-medium");
        assert!(set.max_cost > 0);
        let names: Vec<_> = set
            .structures
            .iter()
            .map(|s| s.structure.as_str())
            .collect();
        assert_eq!(names, ["bvh-binned", "grid", "embree-medium"]);
        let mut top_colour_seen = false;
        for st in &set.structures {
            let counts = st.structure != "embree-medium";
            assert_eq!(st.heatmap.is_some(), counts, "{}", st.structure);
            let disagrees = st.explained_pixels + st.mismatch_pixels > 0;
            assert_eq!(st.mask.is_some(), disagrees, "{}", st.structure);
            if let Some(h) = &st.heatmap {
                let px = png_pixels(&out.join(h));
                assert_eq!(px.len(), 640 * 480);
                top_colour_seen |= px.contains(&[253, 231, 37]);
            }
        }
        assert!(
            top_colour_seen,
            "{}: no pixel at the top of the shared scale",
            set.scene
        );
        for f in set.files() {
            assert_eq!(png_size(&out.join(f)), (640, 480), "{f}");
            listed.push(f.clone());
        }
    }
    listed.sort();
    let on_disk: Vec<String> = files_below(&out.join("images"))
        .into_iter()
        .map(|f| format!("images/{f}"))
        .collect();
    assert_eq!(on_disk, listed, "images/ holds exactly the listed files");
    assert_eq!(
        on_disk.iter().filter(|f| f.contains("--render-")).count(),
        2
    );

    let html = scene_pages(&out);
    assert_eq!(html.matches("class=\"picture\"").count(), listed.len());
    for f in &listed {
        assert!(
            html.contains(&format!(
                "<a href=\"{f}\"><img class=\"picture\" src=\"{f}\""
            )),
            "{f} is not shown linked to itself"
        );
    }
    assert!(html.contains("width:420px"));
    assert!(html.contains("Not counted (no work counters): embree-medium."));
    for set in &report.pictures {
        let digits = set.max_cost.to_string();
        let mut max = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                max.push(',');
            }
            max.push(c);
        }
        assert!(
            html.contains(&format!(">{max}</text>")),
            "the colour bar prints its maximum {max}"
        );
        assert!(html.contains(">0</text>") && html.contains(">1</text>"));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The picture pass is untimed and separate: a run with `--no-images` has the same counters
/// and agreement counts for every workload, and no pictures at all.
#[test]
fn pictures_change_no_counter_or_agreement_count() {
    let dir = scratch("pictures-unchanged");
    let with = run(&dir.join("with"), &["--picture-width", "96"]);
    let without = run(&dir.join("without"), &["--no-images"]);
    assert!(without.pictures.is_empty());
    assert!(without.results.iter().all(|r| r.primary_image.is_none()));
    assert!(files_below(&dir.join("without/images")).is_empty());
    assert_eq!(with.results.len(), without.results.len());
    for (a, b) in with.results.iter().zip(&without.results) {
        for (x, y) in a.workloads.iter().zip(&b.workloads) {
            let what = format!("{} {} {}", a.scene, a.structure, x.workload);
            assert_eq!(
                serde_json::to_value(x.counters_total).unwrap(),
                serde_json::to_value(y.counters_total).unwrap(),
                "{what}"
            );
            assert_eq!(
                serde_json::to_value(x.agreement.counts).unwrap(),
                serde_json::to_value(y.agreement.counts).unwrap(),
                "{what}"
            );
            assert_eq!(x.queries, y.queries, "{what}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_picture_width_is_refused_naming_the_flag() {
    let dir = scratch("pictures-bad-width");
    for bad in ["0", "63", "4097", "99999999999", "-5", "wide", ""] {
        let out = dir.join(format!("out-{bad}"));
        let out_arg = out.display().to_string();
        let (code, _, stderr) = invoke(&[
            "run",
            "--scenes",
            "sphere:triangles=100",
            &format!("--picture-width={bad}"),
            "--out",
            &out_arg,
        ]);
        assert_eq!(code, 1, "--picture-width {bad:?}: {stderr}");
        assert!(stderr.contains("--picture-width"), "{bad:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out.join("report.json").exists(), "{bad:?}: work was done");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Drawn elsewhere, a report takes its pictures along; redrawn in place it keeps them; moved
/// without them (or naming files outside images/), the page draws the small planes of
/// report.json and says why.
#[test]
fn a_moved_report_falls_back_to_small_planes_and_says_so() {
    let dir = scratch("pictures-moved");
    let home = dir.join("run");
    let report = run(&home, &["--picture-width", "96"]);
    let listed: Vec<String> = report
        .pictures
        .iter()
        .flat_map(|p| p.files().into_iter().cloned())
        .collect();
    let report_arg = home.join("report.json").display().to_string();

    // Elsewhere, with the files beside the report: copied, shown full size.
    let copy = dir.join("copy");
    let (code, _, stderr) = invoke(&["report", &report_arg, "--out", &copy.display().to_string()]);
    assert_eq!(code, 0, "{stderr}");
    for f in &listed {
        assert_eq!(png_size(&copy.join(f)), (96, 72), "{f}");
    }
    let html = scene_pages(&copy);
    assert!(!html.contains("Small pictures"));
    assert_eq!(html.matches("class=\"picture\"").count(), listed.len());

    // In place: the drawing is replaced, the run's pictures stay.
    let (code, _, stderr) = invoke(&["report", &report_arg]);
    assert_eq!(code, 0, "{stderr}");
    for f in &listed {
        assert_eq!(png_size(&home.join(f)), (96, 72), "{f}");
    }

    // The report alone, moved: small pictures, and the page says so.
    let moved = dir.join("moved");
    std::fs::create_dir_all(&moved).unwrap();
    std::fs::copy(home.join("report.json"), moved.join("report.json")).unwrap();
    let page = dir.join("page");
    let moved_arg = moved.join("report.json").display().to_string();
    let (code, _, stderr) = invoke(&["report", &moved_arg, "--out", &page.display().to_string()]);
    assert_eq!(code, 0, "{stderr}");
    let html = scene_pages(&page);
    assert_eq!(html.matches("<b>Small pictures:</b>").count(), 2, "{html}");
    assert!(html.contains("the full-size files were not found beside the report"));
    assert!(!html.contains("class=\"picture\""));
    assert!(html.contains("class=\"picture-small\""));
    let small = files_below(&page.join("images"));
    assert_eq!(
        small.iter().filter(|f| f.ends_with("--render.png")).count(),
        2,
        "{small:?}"
    );
    for f in &small {
        let (w, h) = png_size(&page.join("images").join(f));
        assert!(w <= 160 && h <= 120, "{f}: {w}×{h}");
    }

    // A report naming a file outside images/ is not followed there.
    let mut hostile = report.clone();
    hostile.pictures[0].render = "images/../report.json".into();
    let evil = dir.join("evil");
    hostile.write_atomic(&evil).unwrap();
    let evil_arg = evil.join("report.json").display().to_string();
    let out = dir.join("evil-page");
    let (code, _, stderr) = invoke(&["report", &evil_arg, "--out", &out.display().to_string()]);
    assert_eq!(code, 0, "{stderr}");
    let html = scene_pages(&out);
    assert!(html.contains("unusable picture file"), "{html}");
    assert!(!out.join("report.json").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// Every scene page of a drawing, one after the other: the pictures live there, not on the
/// summary.
fn scene_pages(dir: &std::path::Path) -> String {
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("scene-") && n.ends_with(".html"))
        .collect();
    names.sort();
    assert!(!names.is_empty(), "no scene page in {}", dir.display());
    names
        .iter()
        .map(|n| std::fs::read_to_string(dir.join(n)).unwrap())
        .collect()
}
