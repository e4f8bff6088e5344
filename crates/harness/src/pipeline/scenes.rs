//! Scenes as a command meets them: every request checked before any work, then loaded in turn
//! under a name unique within the run, an absent optional file a note and a failure an error.

use super::workers::{Log, Progress, catch_panic};
use anyhow::{Context, Result};
use raybench_scenes::{Scene, SceneRequest};
use std::time::Instant;

/// A scene as loaded, with the time its loading or generation took.
pub(crate) struct LoadedScene {
    pub scene: Scene,
    pub load_ms: f64,
}

fn load(request: &SceneRequest, seed: u64) -> Result<Option<LoadedScene>> {
    let start = Instant::now();
    Ok(request.load(seed)?.map(|scene| LoadedScene {
        scene,
        load_ms: start.elapsed().as_secs_f64() * 1e3,
    }))
}

/// `name`, or `name #2`, `name #3`, … if the run already has a scene of that name.
fn unique_name(name: String, used: &mut std::collections::HashSet<String>) -> String {
    let unique = (1..)
        .map(|i| {
            if i == 1 {
                name.clone()
            } else {
                format!("{name} #{i}")
            }
        })
        .find(|n| !used.contains(n))
        .expect("some suffix is free");
    used.insert(unique.clone());
    unique
}

/// Loads every requested scene in turn, names it uniquely and hands it to `visit`. An absent
/// optional file becomes a note and a load failure an error; the run goes on either way.
pub(crate) fn for_each_scene(
    requests: &[SceneRequest],
    seed: u64,
    progress: &Progress,
    log: &mut Log,
    mut visit: impl FnMut(&SceneRequest, &LoadedScene, &mut Log),
) {
    let mut used_names = std::collections::HashSet::new();
    for request in requests {
        let mut scene = match catch_panic(|| load(request, seed)) {
            Ok(Some(s)) => s,
            Ok(None) => {
                let note = format!("skipped {}: optional scene file is absent", request.label());
                progress.note(note.clone());
                log.notes.push(note);
                continue;
            }
            Err(e) => {
                let err = format!("scene {}: {e:#}", request.label());
                progress.note(err.clone());
                log.errors.push(err);
                continue;
            }
        };
        scene.scene.name = unique_name(request.report_name(), &mut used_names);
        visit(request, &scene, log);
    }
}

/// Checks what can be checked before any work: generator specs (names, parameters), and that
/// OBJ files that are not optional exist. A bad scene then fails the command at once, before
/// a report or dump is written, instead of after the scenes listed before it were measured.
pub fn check_requests(requests: &[SceneRequest]) -> Result<()> {
    for request in requests {
        request.check().with_context(|| match request {
            SceneRequest::Spec(spec) if !spec.to_ascii_lowercase().ends_with(".obj") => {
                format!("scene '{spec}'")
            }
            _ => "scene file".to_string(),
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_specs_and_missing_files_are_found_before_any_work() {
        let ok = SceneRequest::Spec("sphere:triangles=100".into());
        let optional = SceneRequest::File {
            path: "/nonexistent/optional.obj".into(),
            optional: true,
        };
        assert!(check_requests(&[ok.clone(), optional]).is_ok());
        let bad = SceneRequest::Spec("sphere:triangles=-5".into());
        let err = format!("{:#}", check_requests(&[ok.clone(), bad]).unwrap_err());
        assert!(err.contains("sphere:triangles=-5"), "{err}");
        let missing = SceneRequest::Spec("/nonexistent/scene.OBJ".into());
        let err = format!("{:#}", check_requests(&[ok, missing]).unwrap_err());
        assert!(err.contains("/nonexistent/scene.OBJ"), "{err}");
    }
}
