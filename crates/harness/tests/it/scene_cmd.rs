//! `raybench scene list | export | preview`, as a user runs them, and the preview renderer.

use raybench_geom::TriangleMesh;
use raybench_harness::output::preview::{background, render_preview};
use raybench_scenes::{Scene, Vec3, View};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn raybench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args(args)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A fresh, empty directory for one test.
fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raybench-scene-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every entry of `dir`, hidden ones (temporary files) included, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn scene_list_names_the_basic_generators_and_their_views() {
    let out = raybench(&["scene", "list"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    for name in ["sphere", "soup", "plane"] {
        // The generator's line, then (after its parameters) a views line that is not an error.
        let at = stdout
            .lines()
            .position(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("`scene list` lacks {name}:\n{stdout}"));
        let views = stdout
            .lines()
            .skip(at + 1)
            .find(|l| l.trim_start().starts_with("views:"))
            .unwrap();
        assert!(views.contains("views: default"), "{name}: {views}");
    }
    assert!(stdout.contains("radius: sphere radius"), "{stdout}");
    assert!(stdout.contains("PATH.obj"), "{stdout}");
    assert!(stdout.contains("Real scenes"), "{stdout}");
}

/// Positions as bits, so -0 and 0 differ and the comparison is exact.
fn bits(m: &TriangleMesh) -> Vec<[u32; 3]> {
    m.positions()
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn triangle_bits(m: &TriangleMesh) -> Vec<[[u32; 3]; 3]> {
    m.triangles()
        .map(|t| [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits)))
        .collect()
}

/// Exports `name` through the binary and loads the file back; checks it against the scene
/// made in this process. Returns (generated, loaded).
fn export_round_trip(tag: &str, name: &str, triangles: &str, seed: &str) -> (Scene, Scene) {
    let dir = temp_dir(tag);
    let file = dir.join("x.obj");
    let out = raybench(&[
        "scene",
        "export",
        name,
        "--triangles",
        triangles,
        "--seed",
        seed,
        "--out",
        s(&file),
    ]);
    assert!(
        out.status.success(),
        "{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    assert_eq!(entries(&dir), ["x.obj"], "no temporary file left behind");
    let header = std::fs::read_to_string(&file).unwrap(); // the whole file
    let spec = format!("{name}:triangles={triangles}");
    assert!(
        header.contains(&format!("# spec: {spec}"))
            && header.contains(&format!("# seed: {seed}"))
            && header.contains(&format!("raybench {}", env!("CARGO_PKG_VERSION"))),
        "header: {}",
        &header[..300.min(header.len())]
    );
    let loaded = raybench_scenes::load_obj(&file).unwrap();
    let generated = raybench_scenes::resolve(&spec, seed.parse().unwrap()).unwrap();
    // What the file promises: exactly the generated mesh in first-use vertex order...
    let expected = raybench_scenes::in_file_order(&generated.mesh);
    assert_eq!(bits(&loaded.mesh), bits(&expected), "{name}: positions");
    assert_eq!(loaded.mesh.indices(), expected.indices(), "{name}: indices");
    // ...so every primitive keeps its id and its exact vertices.
    assert_eq!(
        triangle_bits(&loaded.mesh),
        triangle_bits(&generated.mesh),
        "{name}: triangles"
    );
    assert!(loaded.loader_notes.is_empty(), "{:?}", loaded.loader_notes);
    // The file's own numbering is the loaded one (vertex i of the file is vertex i after
    // loading), so tools that keep file order see the same ids raybench traces.
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first() {
            Some(&"v") => v.push([1, 2, 3].map(|i| words[i].parse::<f32>().unwrap().to_bits())),
            Some(&"f") => f.push([1, 2, 3].map(|i| words[i].parse::<u32>().unwrap() - 1)),
            _ => {}
        }
    }
    assert_eq!(v, bits(&loaded.mesh), "{name}: file vertices");
    assert_eq!(f, loaded.mesh.indices(), "{name}: file faces");
    std::fs::remove_dir_all(&dir).unwrap();
    (generated, loaded)
}

#[test]
fn exported_sphere_loads_back_bit_exactly() {
    let (generated, loaded) = export_round_trip("sphere", "sphere", "2000", "1");
    assert!(generated.mesh.len() > 1500, "{}", generated.mesh.len());
    // The sphere is watertight: every vertex is used, none is lost.
    assert_eq!(
        loaded.mesh.positions().len(),
        generated.mesh.positions().len()
    );
}

#[test]
fn exported_soup_loads_back_identical() {
    let (generated, loaded) = export_round_trip("soup", "soup", "700", "7");
    // A soup's vertices are already in first-use order: the very same arrays come back.
    assert_eq!(bits(&loaded.mesh), bits(&generated.mesh));
    assert_eq!(loaded.mesh.indices(), generated.mesh.indices());
    assert_eq!(loaded.mesh.len(), 700);
}

/// Runs a command that must fail; returns stderr after checking nothing was written.
fn fails_cleanly(dir: &Path, before: &[String], args: &[&str]) -> String {
    let out = raybench(args);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded: {stderr}");
    assert!(stderr.contains("error"), "{args:?}: {stderr}");
    assert_eq!(entries(dir), before, "{args:?} left files behind");
    stderr
}

#[test]
fn export_of_bad_input_fails_with_a_clear_message_and_writes_nothing() {
    let dir = temp_dir("export-bad");
    let out = dir.join("x.obj");
    let out = s(&out);
    let err = fails_cleanly(&dir, &[], &["scene", "export", "nosuch", "--out", out]);
    assert!(
        err.contains("unknown generator `nosuch`") && err.contains("sphere"),
        "{err}"
    );

    // A generator without a `triangles` parameter (plane has `quads`).
    let no_triangles = raybench_scenes::generators()
        .iter()
        .find(|g| !g.params.iter().any(|p| p.key == "triangles"))
        .expect("some generator has no `triangles` parameter");
    let err = fails_cleanly(
        &dir,
        &[],
        &[
            "scene",
            "export",
            no_triangles.name,
            "--triangles",
            "100",
            "--out",
            out,
        ],
    );
    assert!(
        err.contains(&format!(
            "`{}` has no `triangles` parameter",
            no_triangles.name
        )),
        "{err}"
    );

    // --triangles on an OBJ path, and twice (flag and spec).
    let err = fails_cleanly(
        &dir,
        &[],
        &["scene", "export", "a.obj", "--triangles", "5", "--out", out],
    );
    assert!(err.contains("OBJ file"), "{err}");
    let err = fails_cleanly(
        &dir,
        &[],
        &[
            "scene",
            "export",
            "sphere:triangles=50",
            "--triangles",
            "60",
            "--out",
            out,
        ],
    );
    assert!(err.contains("give one of them"), "{err}");

    // Unwritable: a missing directory, and an existing directory as the target.
    let missing = dir.join("no-such-dir").join("x.obj");
    let err = fails_cleanly(
        &dir,
        &[],
        &["scene", "export", "sphere", "--out", s(&missing)],
    );
    assert!(err.contains("no-such-dir"), "{err}");
    let target = dir.join("a-directory.obj");
    std::fs::create_dir(&target).unwrap();
    let before = entries(&dir);
    let err = fails_cleanly(
        &dir,
        &before,
        &["scene", "export", "sphere", "--out", s(&target)],
    );
    assert!(err.contains("a-directory.obj"), "{err}");
    assert!(std::fs::read_dir(&target).unwrap().next().is_none());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(bytes.len() > 33, "{} bytes", bytes.len());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk");
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn preview_writes_a_png_of_the_requested_size() {
    let dir = temp_dir("preview");
    for (w, h) in [(160, 120), (90, 50)] {
        let file = dir.join(format!("s{w}.png"));
        let out = raybench(&[
            "scene",
            "preview",
            "sphere",
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--out",
            s(&file),
        ]);
        assert!(
            out.status.success(),
            "{}\n{}",
            text(&out.stdout),
            text(&out.stderr)
        );
        assert_eq!(png_size(&std::fs::read(&file).unwrap()), (w, h));
    }
    assert_eq!(
        entries(&dir),
        ["s160.png", "s90.png"],
        "temporary files left"
    );

    let err = fails_cleanly(
        &dir,
        &entries(&dir),
        &[
            "scene",
            "preview",
            "sphere",
            "--view",
            "sideways",
            "--out",
            s(&dir.join("v.png")),
        ],
    );
    assert!(
        err.contains("no view `sideways`") && err.contains("default"),
        "{err}"
    );
    let missing = dir.join("no-such-dir").join("x.png");
    let err = fails_cleanly(
        &dir,
        &entries(&dir),
        &["scene", "preview", "sphere", "--out", s(&missing)],
    );
    assert!(err.contains("no-such-dir"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Splits a render into background (exactly the sky colour of its row) and surface pixels.
fn surface_mask(pixels: &[[u8; 3]], w: u32, h: u32) -> Vec<bool> {
    pixels
        .iter()
        .enumerate()
        .map(|(i, p)| *p != background(i as u32 / w, h))
        .collect()
}

fn brightness(p: [u8; 3]) -> f64 {
    p.iter().map(|&c| f64::from(c)).sum()
}

/// Mean brightness of surface pixels in the part of the image `keep(x, y)` selects.
fn mean_surface(pixels: &[[u8; 3]], mask: &[bool], w: u32, keep: impl Fn(u32, u32) -> bool) -> f64 {
    let (sum, n) = pixels
        .iter()
        .zip(mask)
        .enumerate()
        .filter(|(i, (_, m))| **m && keep(*i as u32 % w, *i as u32 / w))
        .fold((0.0, 0usize), |(s, n), (_, (p, _))| {
            (s + brightness(*p), n + 1)
        });
    assert!(n > 0);
    sum / n as f64
}

#[test]
fn sphere_preview_is_not_blank() {
    let (w, h) = (160, 120);
    let scene = raybench_scenes::generate("sphere:triangles=2000", 1).unwrap();
    let pixels = render_preview(&scene, &scene.view, w, h).unwrap();
    assert_eq!(pixels.len(), (w * h) as usize);
    let mask = surface_mask(&pixels, w, h);
    let surface = mask.iter().filter(|&&m| m).count();
    let fraction = surface as f64 / pixels.len() as f64;
    assert!(
        fraction > 0.2 && fraction < 0.95,
        "{:.1} % of pixels show the sphere",
        fraction * 100.0
    );
    // The corners are sky, the centre is sphere.
    assert!(!mask[0] && !mask[(w * h - 1) as usize]);
    assert!(mask[(h / 2 * w + w / 2) as usize]);
    // Lit: the brightest surface pixel is well above the ambient-only shade.
    let surface_px: Vec<f64> = pixels
        .iter()
        .zip(&mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| brightness(*p))
        .collect();
    let max = surface_px.iter().copied().fold(0.0, f64::max);
    let min = surface_px.iter().copied().fold(f64::MAX, f64::min);
    assert!(max > 1.5 * min && max > 450.0, "min {min}, max {max}");
}

/// The image is neither upside down nor mirrored: a light above the camera's target brightens
/// the top half of the sphere, a light to the camera's right the right half.
#[test]
fn preview_orientation_follows_the_light() {
    let (w, h) = (160, 120);
    let scene = raybench_scenes::generate("sphere:triangles=2000", 1).unwrap();
    let c = scene.view.camera;
    let forward = (c.target - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let lit_from = |dir: Vec3| {
        let view = View {
            light: c.target + dir * 100.0,
            ..scene.view
        };
        let pixels = render_preview(&scene, &view, w, h).unwrap();
        let mask = surface_mask(&pixels, w, h);
        (pixels, mask)
    };
    let (px, mask) = lit_from(up);
    let top = mean_surface(&px, &mask, w, |_, y| y < h / 2);
    let bottom = mean_surface(&px, &mask, w, |_, y| y >= h / 2);
    assert!(
        top > bottom + 100.0,
        "light above: top {top}, bottom {bottom}"
    );
    let (px, mask) = lit_from(right);
    let left = mean_surface(&px, &mask, w, |x, _| x < w / 2);
    let rt = mean_surface(&px, &mask, w, |x, _| x >= w / 2);
    assert!(rt > left + 100.0, "light right: left {left}, right {rt}");
}

/// A shadow: a small triangle between a floor and the light darkens the floor below it.
#[test]
fn preview_casts_shadows() {
    let floor = [
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(-2.0, 0.0, 2.0),
    ];
    let blocker = [
        Vec3::new(-0.5, 1.0, -0.5),
        Vec3::new(0.5, 1.0, -0.5),
        Vec3::new(0.0, 1.0, 0.5),
    ];
    let positions: Vec<Vec3> = floor.iter().chain(&blocker).copied().collect();
    let (mesh, _) = TriangleMesh::new(positions, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]]).unwrap();
    let mut scene = raybench_scenes::generate("plane:quads=1", 1).unwrap();
    scene.mesh = std::sync::Arc::new(mesh);
    // Light straight above: the blocker's shadow covers the floor's centre. The camera looks
    // from the side and above, past the blocker's edge, at the whole floor.
    let side = View {
        camera: raybench_scenes::Camera {
            eye: Vec3::new(0.0, 2.0, 4.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 60.0,
        },
        light: Vec3::new(0.0, 50.0, 0.0),
    };
    let (w, h) = (64, 64);
    let side_px = render_preview(&scene, &side, w, h).unwrap();
    // The floor point (0, 0, 0) is in the blocker's shadow; (1.5, 0, 1.5) is lit. Their pixels,
    // by projecting with the camera frame.
    let project = |p: Vec3| {
        let c = side.camera;
        let f = (c.target - c.eye).normalize();
        let r = f.cross(c.up).normalize();
        let u = r.cross(f);
        let q = p - c.eye;
        let t = (c.fov_y_deg.to_radians() / 2.0).tan();
        let (x, y) = (q.dot(r) / q.dot(f) / t, q.dot(u) / q.dot(f) / t);
        let px = ((x + 1.0) / 2.0 * w as f32) as usize;
        let py = ((1.0 - y) / 2.0 * h as f32) as usize;
        side_px[py * w as usize + px]
    };
    let shadowed = brightness(project(Vec3::new(0.0, 0.0, 0.0)));
    let lit = brightness(project(Vec3::new(1.5, 0.0, 1.5)));
    assert!(lit > 1.5 * shadowed, "lit {lit}, shadowed {shadowed}");
}
