//! The names a report's figures are grouped by (scenes, structures, workloads, in the order
//! they first appear) and the file-name slugs made from them.

use super::sweep::Sweep;
use crate::report::run::{Report, ResultEntry};

/// A file-name-safe form of a name: lower-case letters and digits, everything else `-`
/// (`teapot.obj` → `teapot-obj`, so it never meets the generator `teapot`).
pub fn slug(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    let s = s.trim_matches('-').to_string();
    if s.is_empty() { "unnamed".into() } else { s }
}

/// File-name slugs for the report's scenes, made unique with a `-2`, `-3`… suffix when two
/// names map to the same slug (`a:b` and `a-b`).
pub(crate) fn scene_slugs(report: &Report) -> std::collections::HashMap<String, String> {
    let mut used = std::collections::HashSet::new();
    scene_names(report)
        .into_iter()
        .map(|name| {
            let base = slug(&name);
            let mut candidate = base.clone();
            let mut k = 2;
            while !used.insert(candidate.clone()) {
                candidate = format!("{base}-{k}");
                k += 1;
            }
            (name, candidate)
        })
        .collect()
}

/// Longest scene label a chart draws; past it a spec keeps its parameters and loses the middle
/// of its generator's name (`teapot-in-…:view=stadium`), and the full name goes into the hover
/// title.
const LABEL_CHARS: usize = 24;

/// How charts name `scene`: by its swept value in a sweep ("size_ratio=1e-3"), otherwise by
/// its name (`.obj` kept: the generator `teapot` and the file `teapot.obj` are different
/// scenes), shortened to [`LABEL_CHARS`].
pub(crate) fn scene_label(sweep: Option<&Sweep>, scene: &str) -> String {
    if let Some(label) = sweep.and_then(|s| s.label(scene)) {
        return label.to_string();
    }
    let name = scene;
    let chars = |s: &str| s.chars().count();
    if chars(name) <= LABEL_CHARS {
        return name.to_string();
    }
    let take = |s: &str, n: usize| s.chars().take(n).collect::<String>();
    match name.split_once(':') {
        Some((generator, params)) if chars(params) + 6 <= LABEL_CHARS => {
            let keep = LABEL_CHARS - chars(params) - 2;
            format!("{}…:{params}", take(generator, keep))
        }
        _ => format!("{}…", take(name, LABEL_CHARS - 1)),
    }
}

pub(crate) fn scene_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = report.scenes.iter().map(|s| s.name.clone()).collect();
    for r in &report.results {
        if !names.contains(&r.scene) {
            names.push(r.scene.clone());
        }
    }
    names
}

/// The structures with results, in the order of the run's structure list (the order the
/// palette colours them in), then any the list does not name.
pub(crate) fn structure_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = report
        .run
        .structures
        .iter()
        .filter(|s| report.results.iter().any(|r| &r.structure == *s))
        .cloned()
        .collect();
    for r in &report.results {
        if !names.contains(&r.structure) {
            names.push(r.structure.clone());
        }
    }
    names
}

pub(crate) fn workload_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for w in report.results.iter().flat_map(|r| &r.workloads) {
        if !names.contains(&w.workload) {
            names.push(w.workload.clone());
        }
    }
    names
}

pub(crate) fn entry<'a>(
    report: &'a Report,
    scene: &str,
    structure: &str,
) -> Option<&'a ResultEntry> {
    report
        .results
        .iter()
        .find(|r| r.scene == scene && r.structure == structure)
}

#[cfg(test)]
mod tests {
    use super::{scene_label, slug};

    #[test]
    fn slugs_keep_files_and_generators_apart() {
        assert_eq!(slug("teapot.obj"), "teapot-obj");
        assert_ne!(slug("teapot.obj"), slug("teapot"));
        assert_eq!(slug("sphere:triangles=2000"), "sphere-triangles-2000");
        assert_eq!(slug("::"), "unnamed");
    }

    #[test]
    fn long_scene_labels_keep_their_parameters() {
        assert_eq!(scene_label(None, "teapot.obj"), "teapot.obj");
        assert_ne!(scene_label(None, "teapot.obj"), scene_label(None, "teapot"));
        assert_eq!(
            scene_label(None, "teapot-in-stadium:view=stadium"),
            "teapot-in-…:view=stadium"
        );
        let long = "teapot-in-stadium:stadium_triangles=20000,teapot_triangles=4000";
        let label = scene_label(None, long);
        assert_eq!(label.chars().count(), 24);
        assert!(label.starts_with("teapot-in-stadium:stadi") && label.ends_with('…'));
    }
}
