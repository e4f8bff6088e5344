mod common;

use common::{Fixtures, shared_scenes};
use raybench_scenes::input::InputError;
use raybench_scenes::{SceneError, SceneSource, Vec3, load_obj, resolve};
use std::path::Path;

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

/// Loads `contents` as `name` and returns the error message, failing if it loaded.
fn load_error(fx: &Fixtures, name: &str, contents: impl AsRef<[u8]>) -> String {
    let path = fx.write(name, contents);
    match load_obj(&path) {
        Ok(scene) => panic!("{name} loaded with {} triangles", scene.mesh.len()),
        Err(e) => e.to_string(),
    }
}

/// The message starts with the file's path and contains every one of `words`.
fn assert_names(message: &str, path: &Path, words: &[&str]) {
    assert!(
        message.starts_with(&path.display().to_string()),
        "message does not start with the path {}: {message}",
        path.display()
    );
    for w in words {
        assert!(message.contains(w), "message lacks `{w}`: {message}");
    }
}

#[test]
fn missing_file_and_directory_are_clear_errors() {
    let fx = Fixtures::new("missing");
    let missing = fx.dir().join("nope.obj");
    let msg = load_obj(&missing).unwrap_err().to_string();
    assert_names(&msg, &missing, &["no such file"]);
    let msg = load_obj(fx.dir()).unwrap_err().to_string();
    assert_names(&msg, fx.dir(), &["is a directory"]);
}

#[test]
fn files_without_triangles_are_rejected_with_the_reason() {
    let fx = Fixtures::new("empty");
    let cases: [(&str, &str, &str); 5] = [
        ("empty.obj", "", "no vertices and no faces"),
        (
            "comments.obj",
            "# only\n# comments\n####\n",
            "no vertices and no faces",
        ),
        ("vertices.obj", TRIANGLE, "3 vertices but no faces"),
        (
            "points.obj",
            "v 0 0 0\nv 1 0 0\nf 1\nl 1 2\n",
            "point/line elements",
        ),
        (
            "nan.obj",
            "v nan 0 0\nv 1 nan 0\nv 0 1 inf\nf 1 2 3\n",
            "all 1 triangles were removed: 1 with a NaN",
        ),
    ];
    for (name, text, reason) in cases {
        let msg = load_error(&fx, name, text);
        assert_names(&msg, &fx.dir().join(name), &["no triangles", reason]);
    }
}

#[test]
fn bad_lines_are_rejected_with_their_line_number() {
    let fx = Fixtures::new("badlines");
    let cases: [(&str, String, &str); 7] = [
        (
            "range.obj",
            format!("{TRIANGLE}f 1 2 3\nf 1 2 9\n"),
            "line 5: vertex index 9 is out of range",
        ),
        (
            "zero.obj",
            format!("{TRIANGLE}f 0 1 2\n"),
            "line 4: vertex index 0",
        ),
        (
            "garbage_face.obj",
            format!("{TRIANGLE}f 1 2 x\n"),
            "line 4: `x` is not an integer index",
        ),
        (
            "short_v.obj",
            "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n".into(),
            "line 2: `v` needs 3 numbers, found 2",
        ),
        (
            "garbage_line.obj",
            format!("{TRIANGLE}f 1 2 3\n%#@! there\n"),
            "line 5: `%#@!` is not an OBJ statement",
        ),
        (
            "relative_vt.obj",
            format!("{TRIANGLE}vt 0 0\nf 1/-5 2/-5 3/-5\n"),
            "line 5: relative texture-coordinate index -5 reaches before the first `vt` (1 defined so far)",
        ),
        (
            "no_mtl_name.obj",
            format!("{TRIANGLE}usemtl\nf 1 2 3\n"),
            "line 4: `usemtl` without a material name",
        ),
    ];
    for (name, text, expected) in cases {
        let msg = load_error(&fx, name, text);
        assert_names(&msg, &fx.dir().join(name), &[expected]);
    }
}

#[test]
fn non_utf8_bytes_are_rejected_with_line_and_column() {
    let fx = Fixtures::new("utf8");
    let msg = load_error(&fx, "latin1.obj", b"v 0 0 0\n# caf\xe9\nv 1 0 0\n");
    assert_names(
        &msg,
        &fx.dir().join("latin1.obj"),
        &["line 2: not UTF-8", "column 6"],
    );
}

#[test]
fn a_byte_order_mark_is_skipped_and_noted() {
    let fx = Fixtures::new("bom");
    let path = fx.write("bom.obj", format!("\u{feff}{TRIANGLE}f 1 2 3\n"));
    let scene = load_obj(&path).unwrap();
    assert_eq!(scene.mesh.len(), 1);
    assert_eq!(scene.loader_notes, ["UTF-8 byte-order mark skipped"]);
}

#[test]
fn material_files_are_never_read() {
    // tobj panics on `Kd 1 2` in every build; the loader must not even open the file.
    let fx = Fixtures::new("mtl");
    fx.write("bad.mtl", "newmtl red\nKd 1 2\n");
    let path = fx.write(
        "uses_mtl.obj",
        format!("mtllib bad.mtl\n{TRIANGLE}usemtl red\nf 1 2 3\n"),
    );
    let scene = load_obj(&path).unwrap();
    assert_eq!(scene.mesh.len(), 1);
    assert!(
        scene.loader_notes.iter().any(|n| n.contains("mtllib")),
        "{:?}",
        scene.loader_notes
    );
}

#[test]
fn bad_coordinates_drop_only_their_triangles_and_are_counted() {
    let fx = Fixtures::new("coords");
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                v nan 0 0\nv inf 0 0\nv 0 0 1e39\nv 0 0 2e18\n\
                f 1 2 3\nf 2 4 3\nf 1 2 5\nf 1 6 2\nf 7 1 2\nf 8 1 2\nf 1 1 2\n";
    let path = fx.write("mixed.obj", text);
    let scene = load_obj(&path).unwrap();
    assert_eq!(scene.mesh.len(), 3, "two good triangles and one degenerate");
    assert_eq!(
        scene.removed.non_finite, 3,
        "nan, inf and 1e39 (inf in f32)"
    );
    assert_eq!(
        scene.removed.too_large, 1,
        "2e18 is beyond Embree's 1.844e18"
    );
    assert_eq!(scene.removed.degenerate_kept, 1);
    assert_eq!(scene.name, "mixed");
    let sha256 = raybench_scenes::sha256::sha256_hex(&std::fs::read(&path).unwrap());
    assert_eq!(
        scene.source,
        SceneSource::Obj {
            path: path.clone(),
            sha256
        }
    );
}

/// The three corners of triangle `i`, for checking what the loader built.
fn corners(scene: &raybench_scenes::Scene, i: usize) -> [Vec3; 3] {
    let t = scene.mesh.triangle(i);
    [t.v0, t.v1, t.v2]
}

#[test]
fn quads_and_ngons_are_fan_triangulated() {
    let fx = Fixtures::new("ngon");
    let square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    let pentagon = "v 3 0 0\nv 4 0 0\nv 4.5 1 0\nv 3.5 2 0\nv 2.5 1 0\n";
    let path = fx.write(
        "ngon.obj",
        format!("{square}{pentagon}f 1 2 3 4\nf 5 6 7 8 9\n"),
    );
    let scene = load_obj(&path).unwrap();
    assert_eq!(scene.mesh.len(), 2 + 3);
    let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    assert_eq!(corners(&scene, 1), [v(0., 0.), v(1., 1.), v(0., 1.)]);
    assert_eq!(corners(&scene, 4), [v(3., 0.), v(3.5, 2.), v(2.5, 1.)]);
    assert!(
        scene
            .loader_notes
            .iter()
            .any(|n| n.starts_with("2 polygons")),
        "{:?}",
        scene.loader_notes
    );
}

#[test]
fn non_convex_polygons_are_noted() {
    let fx = Fixtures::new("concave");
    let arrow = "v 0 0 0\nv 2 0 0\nv 1 0.5 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4 5\n";
    let scene = load_obj(&fx.write("arrow.obj", arrow)).unwrap();
    assert!(
        scene.loader_notes.iter().any(|n| n.contains("non-convex")),
        "{:?}",
        scene.loader_notes
    );
}

#[test]
fn models_are_merged_with_index_offsets() {
    let fx = Fixtures::new("models");
    // Three models; the second uses relative indices, the third refers back to the first's
    // vertices, so each model's local indices must be offset correctly.
    let text = "o first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
                g second\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf -3 -2 -1\n\
                o third\nv 9 9 9\nf 7 1 2\n";
    let scene = load_obj(&fx.write("models.obj", text)).unwrap();
    assert_eq!(scene.mesh.len(), 3);
    assert_eq!(
        corners(&scene, 1),
        [
            Vec3::new(5., 0., 0.),
            Vec3::new(6., 0., 0.),
            Vec3::new(5., 1., 0.)
        ]
    );
    assert_eq!(corners(&scene, 2), [Vec3::splat(9.0), Vec3::ZERO, Vec3::X]);
}

#[test]
fn resolve_picks_the_loader_by_extension() {
    let fx = Fixtures::new("resolve");
    let path = fx.write("UPPER.OBJ", format!("{TRIANGLE}f 1 2 3\n"));
    let scene = resolve(path.to_str().unwrap(), 0).unwrap();
    assert_eq!(scene.name, "UPPER");
    assert!(matches!(
        resolve("sphere:triangles=100", 0).unwrap().source,
        SceneSource::Procedural { .. }
    ));
    let missing = resolve("/no/such/dir/x.obj", 0).unwrap_err();
    assert!(
        matches!(missing, SceneError::Input(InputError::Missing { .. })),
        "{missing}"
    );
}

/// Triangle counts from /work/shared/scenes/README.md.
const SHARED_SCENES: [(&str, usize); 7] = [
    ("stanford-bunny.obj", 69_451),
    ("teapot.obj", 6_320),
    ("sibenik.obj", 75_284),
    ("sponza_dabrovic.obj", 66_454),
    ("conference.obj", 331_179),
    ("stanford_dragon_res2.obj", 202_520),
    ("sionna_san_francisco.obj", 268_041),
];

/// Returns false, and says so on stderr, when the shared scenes folder is absent.
fn shared_scenes_present(test: &str) -> bool {
    let dir = shared_scenes();
    if dir.is_dir() {
        return true;
    }
    eprintln!(
        "NOT RUN: {test}: the shared scenes folder {} is absent on this machine",
        dir.display()
    );
    false
}

#[test]
fn the_stanford_bunny_loads() {
    if !shared_scenes_present("the_stanford_bunny_loads") {
        return;
    }
    let scene = load_obj(&shared_scenes().join("stanford-bunny.obj")).unwrap();
    assert_eq!(scene.name, "stanford-bunny");
    assert_eq!(scene.mesh.len(), 69_451);
    assert_eq!(scene.removed.total(), 0);
}

#[test]
fn every_shared_scene_loads_with_its_documented_triangle_count() {
    if !shared_scenes_present("every_shared_scene_loads") {
        return;
    }
    for (file, triangles) in SHARED_SCENES {
        let scene = load_obj(&shared_scenes().join(file)).unwrap();
        eprintln!(
            "{file}: {} triangles, {:?}, notes {:?}",
            scene.mesh.len(),
            scene.removed,
            scene.loader_notes
        );
        let total = scene.mesh.len() as u64 + scene.removed.total();
        assert_eq!(
            total, triangles as u64,
            "{file}: notes {:?}",
            scene.loader_notes
        );
        assert!(scene.view.is_usable(), "{file}");
    }
}
