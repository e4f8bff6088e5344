//! Inputs too big to keep as files: a 100k-vertex face, 50 MB lines, a million vertices.

use super::{big_input_name, load_catching_panics};
use raybench_scenes::{Scene, SceneError, load_obj_bytes};

fn load_generated(bytes: &[u8]) -> Result<Scene, SceneError> {
    load_catching_panics(|| load_obj_bytes(big_input_name(), bytes))
        .unwrap_or_else(|panic| panic!("PANIC: {panic}"))
}

/// A convex polygon with `n` corners on the unit circle, as one `f` line.
fn circle_polygon(n: usize, last_index: usize) -> String {
    let mut text = String::new();
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        text += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    text += "f";
    for i in 1..n {
        text += &format!(" {i}");
    }
    text + &format!(" {last_index}\n")
}

#[test]
fn a_face_with_100k_vertices_is_fan_triangulated() {
    let n = 100_000;
    let scene = load_generated(circle_polygon(n, n).as_bytes()).unwrap();
    assert_eq!(scene.mesh.len(), n - 2);
    assert_eq!(
        scene.loader_notes,
        ["1 polygons with 4+ vertices fan-triangulated"]
    );
    // The same face with its last corner out of range: named by line and index.
    let message = load_generated(circle_polygon(n, n + 1).as_bytes())
        .unwrap_err()
        .to_string();
    let expected = format!(
        "generated.obj: line {}: vertex index {} is out of range",
        n + 1,
        n + 1
    );
    assert!(message.starts_with(&expected), "{message}");
}

const FIFTY_MB: usize = 50 << 20;

#[test]
fn a_50_mb_garbage_line_gives_a_short_message() {
    let mut text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_owned();
    text.push_str(&"x@".repeat(FIFTY_MB / 2));
    let message = load_generated(text.as_bytes()).unwrap_err().to_string();
    assert!(
        message.starts_with("generated.obj: line 5: `x@x@"),
        "{}",
        &message[..200.min(message.len())]
    );
    assert!(
        message.len() < 200,
        "the token is shortened: {} bytes",
        message.len()
    );
}

#[test]
fn a_50_mb_vertex_line_is_rejected_and_a_50_mb_comment_is_not() {
    let mut numbers = "v".to_owned();
    numbers.push_str(&" 1".repeat(FIFTY_MB / 2));
    let message = load_generated(numbers.as_bytes()).unwrap_err().to_string();
    let expected = format!("generated.obj: line 1: `v` with {} values", FIFTY_MB / 2);
    assert!(message.starts_with(&expected), "{message}");

    let mut comment = "#".to_owned();
    comment.push_str(&"-".repeat(FIFTY_MB));
    comment.push_str("\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(load_generated(comment.as_bytes()).unwrap().mesh.len(), 1);
}

/// A million `v` lines and one face: the scan and tobj stay linear.
#[test]
fn a_million_vertices_and_one_face_load() {
    let mut text = "v 0 0 0\n".repeat(1_000_000);
    text.push_str("v 1 0 0\nv 0 1 0\nf 1 -2 -1\n");
    let scene = load_generated(text.as_bytes()).unwrap();
    assert_eq!(scene.mesh.len(), 1);
    assert_eq!(
        scene.mesh.triangle(0).v2,
        raybench_scenes::Vec3::new(0.0, 1.0, 0.0)
    );
}
