//! The machine and settings a report was measured with, as a table a person reads: grouped
//! (machine, build, this run, Embree, run settings), each field under a human label, lists
//! joined with commas, nested objects as indented sub-rows. Fields the report gains later
//! still appear, under their key with `_` read as a space.

use super::page::escape;
use crate::report::run::Report;
use serde_json::Value;
use std::fmt::Write as _;

/// The groups of `environment` fields, in the order the table shows them. An object field
/// listed alone in a group (`embree`) gives the group its sub-fields as rows.
const GROUPS: [(&str, &[&str]); 4] = [
    (
        "Machine",
        &[
            "cpu_model",
            "cores",
            "cpu_flags",
            "os",
            "hostname",
            "transparent_hugepages",
        ],
    ),
    (
        "Build",
        &[
            "rustc",
            "profile",
            "target_cpu",
            "compile_time_target_features",
        ],
    ),
    (
        "This run",
        &[
            "command_line",
            "git_revision",
            "timestamp",
            "threads",
            "ftz",
            "daz",
            "mxcsr",
            "glibc_tunables",
        ],
    ),
    ("Embree", &["embree"]),
];

/// The run settings in reading order; any others follow.
const RUN_ORDER: [&str; 12] = [
    "suite",
    "structures",
    "workloads",
    "reference",
    "rays",
    "points",
    "threads",
    "seed",
    "build_runs",
    "trace_runs",
    "tolerance",
    "whitted",
];

/// A field's label; unknown fields read as their key.
fn label(key: &str) -> String {
    let known = match key {
        "cpu_model" => "CPU",
        "cores" => "logical cores",
        "cpu_flags" => "SIMD features (detected at run time)",
        "os" => "operating system",
        "hostname" => "host name",
        "rustc" => "compiler",
        "profile" => "Cargo profile",
        "target_cpu" => "target CPU",
        "compile_time_target_features" => "features assumed at compile time",
        "command_line" => "command line",
        "git_revision" => "git revision",
        "timestamp" => "started (UTC)",
        "threads" => "worker threads",
        "ftz" => "flush to zero (FTZ)",
        "daz" => "denormals are zero (DAZ)",
        "mxcsr" => "MXCSR register",
        "transparent_hugepages" => "transparent huge pages (kernel mode)",
        "glibc_tunables" => "GLIBC_TUNABLES",
        "config" => "device configuration",
        "tasking_system" => "tasking system",
        "ray_mask_supported" => "ray masks compiled in",
        "backface_culling" => "back-face culling",
        "ignore_invalid_rays" => "ignores invalid rays",
        "isa" => "instruction set",
        "isa_source" => "instruction set from",
        "suite" => "suite",
        "seed" => "seed",
        "rays" => "rays per ray workload",
        "points" => "points per point workload",
        "reference" => "reference (every answer checked against it)",
        "build_runs" => "timed builds after the warm-up",
        "trace_runs" => "timed passes after the warm-up",
        "tolerance" => "validation tolerance",
        "ulps" => "units in the last place",
        "position_eps" => "position epsilon",
        "structures" => "structures",
        "workloads" => "workloads",
        "whitted" => "whitted workload",
        "max_depth" => "maximum depth",
        "min_contribution" => "minimum contribution",
        _ => return key.replace('_', " "),
    };
    known.to_string()
}

/// A scalar or a list of scalars as text; `None` for what needs sub-rows.
fn text(v: &Value) -> Option<String> {
    match v {
        Value::Null => Some("–".into()),
        Value::Bool(b) => Some(if *b { "yes" } else { "no" }.into()),
        // Most fractions in a report were f32 (0.01 stored as 0.009999999776482582): shown
        // at f32 precision they read as written.
        Value::Number(n) => Some(match (n.is_f64(), n.as_f64()) {
            (true, Some(f)) if f != 0.0 && !(1e-3..1e7).contains(&f.abs()) => {
                format!("{:e}", f as f32)
            }
            (true, Some(f)) => (f as f32).to_string(),
            _ => n.to_string(),
        }),
        Value::String(s) => Some(s.clone()),
        Value::Array(items) => items
            .iter()
            .map(|i| match i {
                Value::Object(_) | Value::Array(_) => None,
                other => text(other),
            })
            .collect::<Option<Vec<String>>>()
            .map(|v| {
                if v.is_empty() {
                    "–".into()
                } else {
                    v.join(", ")
                }
            }),
        Value::Object(_) => None,
    }
}

/// One row per field of `value` under `label`, nested objects and lists of them as sub-rows
/// indented `depth` steps.
fn rows(s: &mut String, label_text: &str, value: &Value, depth: usize) {
    let indent = format!(" style=\"padding-left:{}px\"", 8 + 16 * depth);
    match text(value) {
        Some(t) => {
            let _ = writeln!(
                s,
                "<tr><td class=\"l\"{indent}>{}</td><td class=\"l\">{}</td></tr>",
                escape(label_text),
                escape(&t)
            );
        }
        None => {
            let _ = writeln!(
                s,
                "<tr><td class=\"l\"{indent}>{}</td><td class=\"l\"></td></tr>",
                escape(label_text)
            );
            children(s, value, depth + 1);
        }
    }
}

fn children(s: &mut String, value: &Value, depth: usize) {
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                rows(s, &label(k), v, depth);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                rows(s, &format!("{}", i + 1), v, depth);
            }
        }
        _ => {}
    }
}

fn group(s: &mut String, title: &str) {
    let _ = writeln!(
        s,
        "<tr><td class=\"l group\" colspan=\"2\">{}</td></tr>",
        escape(title)
    );
}

/// The environment and run settings table.
pub(crate) fn environment(s: &mut String, report: &Report) {
    s.push_str("<h2 id=\"environment\">Environment</h2>\n<table class=\"environment\">\n");
    let env = serde_json::to_value(&report.header.environment).unwrap_or_default();
    let Value::Object(env) = env else {
        s.push_str("</table>\n");
        return;
    };
    let mut shown = Vec::new();
    for (title, keys) in GROUPS {
        let present: Vec<&str> = keys
            .iter()
            .copied()
            .filter(|k| env.contains_key(*k))
            .collect();
        if present.is_empty() {
            continue;
        }
        group(s, title);
        if let [only] = present.as_slice()
            && env[*only].is_object()
        {
            children(s, &env[*only], 1);
        } else {
            for k in &present {
                rows(s, &label(k), &env[*k], 1);
            }
        }
        shown.extend(present);
    }
    let rest: Vec<(&String, &Value)> = env
        .iter()
        .filter(|(k, _)| !shown.contains(&k.as_str()))
        .collect();
    if !rest.is_empty() {
        group(s, "Other");
        for (k, v) in rest {
            rows(s, &label(k), v, 1);
        }
    }
    group(s, "Run settings");
    if let Value::Object(run) = serde_json::to_value(&report.run).unwrap_or_default() {
        let known = RUN_ORDER.iter().filter_map(|k| run.get_key_value(*k));
        let rest = run.iter().filter(|(k, _)| !RUN_ORDER.contains(&k.as_str()));
        for (k, v) in known.chain(rest) {
            rows(s, &label(k), v, 1);
        }
    }
    s.push_str("</table>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_values_become_rows_and_lists_are_joined() {
        let mut s = String::new();
        let v = serde_json::json!({"tolerance": {"ulps": 16, "position_eps": 7.6e-6},
            "structures": ["a", "b<c"], "suite": null, "ftz": true});
        children(&mut s, &v, 1);
        assert!(!s.contains('{') && !s.contains('['), "{s}");
        assert!(
            s.contains(">units in the last place</td><td class=\"l\">16<"),
            "{s}"
        );
        assert!(s.contains(">a, b&lt;c<"), "{s}");
        assert!(s.contains(">yes<") && s.contains(">–<"), "{s}");
    }
}
