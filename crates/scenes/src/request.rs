//! Which scenes a run loads: the one resolver behind `--scenes` and suite manifests.
//!
//! A request is a spec (a generator spec such as `soup:triangles=5000`, or an `.obj` path) or
//! a suite's file entry, whose path is resolved against the manifest's directory and may be
//! optional. Requests are checked before any work ([`SceneRequest::check`]) and loaded one at
//! a time ([`SceneRequest::load`]), so a run holds one scene in memory at once.

use crate::{Scene, SceneError, Suite, SuiteScene, check_spec, is_obj_path, load_obj, resolve};
use std::path::{Path, PathBuf};

/// A scene to load.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneRequest {
    /// A generator spec or an `.obj` path, as given on the command line or in a manifest.
    Spec(String),
    /// A suite's OBJ entry; an absent optional file is skipped.
    File { path: PathBuf, optional: bool },
}

impl Suite {
    /// The suite's scenes in manifest order, file paths resolved against the directory of
    /// `manifest` (the file the suite was read from).
    pub fn requests(&self, manifest: &Path) -> Vec<SceneRequest> {
        let base = manifest.parent().unwrap_or(Path::new("."));
        self.scenes
            .iter()
            .map(|s| match s {
                SuiteScene::Generated(spec) => SceneRequest::Spec(spec.clone()),
                SuiteScene::File { obj, optional } => SceneRequest::File {
                    path: base.join(obj),
                    optional: *optional,
                },
            })
            .collect()
    }
}

impl SceneRequest {
    /// The request as written: the spec, or the file's path.
    pub fn label(&self) -> String {
        match self {
            SceneRequest::Spec(s) => s.clone(),
            SceneRequest::File { path, .. } => path.display().to_string(),
        }
    }

    /// The name a report gives the scene: the spec as written (`teapot-in-stadium:view=
    /// stadium`), or an OBJ file's name (`teapot.obj`), so a generated teapot and the teapot
    /// file, or two views of one generator, never share a name.
    pub fn report_name(&self) -> String {
        let file_name = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
        match self {
            SceneRequest::Spec(s) if is_obj_path(s) => {
                file_name(Path::new(s)).unwrap_or_else(|| s.clone())
            }
            SceneRequest::Spec(s) => s.trim().to_string(),
            SceneRequest::File { path, .. } => file_name(path).unwrap_or_else(|| self.label()),
        }
    }

    /// What can be checked without loading: a generator spec names a generator and valid
    /// parameters; an OBJ file that is not optional exists.
    pub fn check(&self) -> Result<(), SceneError> {
        match self {
            SceneRequest::Spec(spec) if is_obj_path(spec) => exists(Path::new(spec)),
            SceneRequest::Spec(spec) => check_spec(spec),
            SceneRequest::File { path, optional } if !optional => exists(path),
            SceneRequest::File { .. } => Ok(()),
        }
    }

    /// The scene, or `None` for an optional file that is absent ("not found", including a
    /// missing parent folder; a file that exists but cannot be read is an error).
    pub fn load(&self, seed: u64) -> Result<Option<Scene>, SceneError> {
        match self {
            SceneRequest::Spec(spec) => resolve(spec, seed).map(Some),
            SceneRequest::File { path, optional } => {
                if *optional && is_absent(path) {
                    return Ok(None);
                }
                load_obj(path).map(Some)
            }
        }
    }
}

fn exists(path: &Path) -> Result<(), SceneError> {
    std::fs::metadata(path)
        .map(|_| ())
        .map_err(|e| SceneError::io(path, e))
}

fn is_absent(path: &Path) -> bool {
    matches!(std::fs::metadata(path), Err(e) if e.kind() == std::io::ErrorKind::NotFound)
}
