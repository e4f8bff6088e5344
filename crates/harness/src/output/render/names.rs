//! The names a report's figures are grouped by (scenes, structures, workloads, in the order
//! they first appear) and the file-name slugs made from them.

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

pub(crate) fn scene_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = report.scenes.iter().map(|s| s.name.clone()).collect();
    for r in &report.results {
        if !names.contains(&r.scene) {
            names.push(r.scene.clone());
        }
    }
    names
}

pub(crate) fn structure_names(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
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
    use super::slug;

    #[test]
    fn slugs_keep_files_and_generators_apart() {
        assert_eq!(slug("teapot.obj"), "teapot-obj");
        assert_ne!(slug("teapot.obj"), slug("teapot"));
        assert_eq!(slug("sphere:triangles=2000"), "sphere-triangles-2000");
        assert_eq!(slug("::"), "unnamed");
    }
}
