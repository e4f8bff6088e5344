//! What `raybench replay` prints: the ray, the double-precision answer over every triangle, and
//! each structure's answers with their classes against the reference.

use crate::pipeline::replay::{F64Crossing, Replay, VERDICT_REFERENCE, join_bits};
use raybench_accel::Hit;
use std::fmt::Write;

fn hit_text(h: &Option<Hit>) -> String {
    match h {
        Some(h) => format!(
            "prim {} t {} ({:#010x}) u {} v {}",
            h.prim,
            h.t,
            h.t.to_bits(),
            h.u,
            h.v
        ),
        None => "miss".to_string(),
    }
}

fn crossing_text(x: &F64Crossing) -> String {
    format!(
        "prim {} t {:.17e} u {:.17e} v {:.17e}, {:.3e} {} the nearest edge (arbiter's edge tolerance {:.3e})",
        x.prim,
        x.t,
        x.u,
        x.v,
        x.edge_distance.abs(),
        if x.edge_distance >= 0.0 {
            "inside"
        } else {
            "outside"
        },
        x.edge_tolerance
    )
}

/// The text `raybench replay` prints.
pub fn replay_text(replay: &Replay) -> String {
    let mut out = String::new();
    let r = &replay.ray;
    let (o, d) = (r.origin(), r.dir());
    let _ = writeln!(
        out,
        "ray      origin ({}, {}, {})  dir ({}, {}, {})  t_min {}  t_max {}",
        o.x,
        o.y,
        o.z,
        d.x,
        d.y,
        d.z,
        r.t_min(),
        r.t_max()
    );
    let _ = writeln!(out, "bits     {}", join_bits(&r.to_bits()));
    let _ = writeln!(
        out,
        "scene    {} ({} triangles traced, seed {})\n",
        replay.scene, replay.triangles, replay.seed
    );
    let f = &replay.f64_answer;
    let _ = writeln!(out, "double precision, every triangle:");
    let _ = writeln!(
        out,
        "  closest hit:  {}",
        f.hit.as_ref().map_or("miss".to_string(), crossing_text)
    );
    if let Some(m) = &f.nearest_miss {
        let _ = writeln!(out, "  nearest miss: {}", crossing_text(m));
    }
    let w = replay
        .answers
        .iter()
        .map(|a| a.name.len())
        .max()
        .unwrap_or(9)
        .max(9);
    let _ = writeln!(
        out,
        "\n{:<w$}  {:<62}  {:<8}  verdict vs {VERDICT_REFERENCE} (closest / any)",
        "structure", "closest hit", "any hit"
    );
    for a in &replay.answers {
        let _ = writeln!(
            out,
            "{:<w$}  {:<62}  {:<8}  {} / {}",
            a.name,
            hit_text(&a.closest),
            if a.occluded { "occluded" } else { "clear" },
            a.closest_verdict,
            a.any_verdict
        );
    }
    out
}
