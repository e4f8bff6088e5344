//! Which scenes a run loads: the one resolver behind `--scenes` and suite manifests.
//!
//! A request is a spec (a generator spec such as `soup:triangles=5000`, or an `.obj` path) or
//! a suite's file entry, whose path is resolved against the manifest's directory and may be
//! optional. Requests are checked before any work ([`SceneRequest::check`]) and loaded one at
//! a time ([`SceneRequest::load`]), so a run holds one scene in memory at once.

use crate::input::{check_input, is_absent};
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
    /// file, or two views of one generator, never share a name. Control characters are
    /// escaped ([`printable`]): the name is printed in tables and pages.
    pub fn report_name(&self) -> String {
        let file_name = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
        let name = match self {
            SceneRequest::Spec(s) if is_obj_path(s) => {
                file_name(Path::new(s)).unwrap_or_else(|| s.clone())
            }
            SceneRequest::Spec(s) => s.trim().to_string(),
            SceneRequest::File { path, .. } => file_name(path).unwrap_or_else(|| self.label()),
        };
        printable(&name).into_owned()
    }

    /// What can be checked without loading: a generator spec names a generator, valid
    /// parameters and a view it has; an OBJ file is a regular file within the size limit
    /// (an optional one only when it is there).
    pub fn check(&self) -> Result<(), SceneError> {
        let file = match self {
            SceneRequest::Spec(spec) if is_obj_path(spec) => Path::new(spec),
            SceneRequest::Spec(spec) => return check_spec(spec),
            SceneRequest::File { path, optional } if *optional && is_absent(path) => return Ok(()),
            SceneRequest::File { path, .. } => path,
        };
        check_input(file)?;
        Ok(())
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

/// `text` safe to print on a terminal and in reports: control characters (an ANSI escape in a
/// file name would clear the screen) are written as `\u{1b}`, everything else as it is.
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() && c != '\n' {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}
