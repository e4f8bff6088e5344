use crate::input::InputError;
use raybench_geom::MeshError;
use std::path::PathBuf;

/// Everything that can go wrong while making a scene or reading a suite.
///
/// Every message names its subject first (the file, the generator spec or the suite) and then
/// the problem, with a line number where one is known, so it can be printed as it is.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be opened or read (missing, not a regular file, too large,
    /// unreadable): see [`crate::input`].
    #[error(transparent)]
    Input(#[from] InputError),

    /// A directory could not be listed.
    #[error("{}: cannot read: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },

    /// Bytes that are not UTF-8; tobj would stop at the line with a bare "read error". `hint`
    /// names a likely cause when the bytes show one (UTF-16, binary data), else it is empty.
    #[error("{}: line {line}: not UTF-8 text (invalid byte at column {column}){hint}", .path.display())]
    NotUtf8 {
        path: PathBuf,
        line: usize,
        column: usize,
        hint: &'static str,
    },

    /// A line the OBJ loader rejects. `line` is found by our own scan of the text, because tobj
    /// reports only the kind of error; it is `None` when the scan could not pin it down.
    #[error("{}: {}{problem}", .path.display(), line_prefix(*.line))]
    Obj {
        path: PathBuf,
        line: Option<usize>,
        problem: String,
    },

    /// The file parsed but left no triangle to trace.
    #[error("{}: no triangles ({detail})", .path.display())]
    NoTriangles { path: PathBuf, detail: String },

    #[error("{}: {source}", .path.display())]
    Mesh { path: PathBuf, source: MeshError },

    #[error("generator spec `{spec}`: {problem}")]
    Generator { spec: String, problem: String },

    #[error(
        "unknown workload `{name}` (known: primary, random, shadow, diffuse, whitted, points-near, points-volume)"
    )]
    UnknownWorkload { name: String },

    #[error("{}: not a valid suite manifest: {source}", .path.display())]
    SuiteJson {
        path: PathBuf,
        source: serde_json::Error,
    },

    #[error("{}: {problem}", .path.display())]
    Suite { path: PathBuf, problem: String },
}

fn line_prefix(line: Option<usize>) -> String {
    line.map(|n| format!("line {n}: ")).unwrap_or_default()
}

impl SceneError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> SceneError {
        SceneError::Io {
            path: path.into(),
            source,
        }
    }

    pub(crate) fn generator(spec: &str, problem: impl Into<String>) -> SceneError {
        SceneError::Generator {
            spec: spec.to_owned(),
            problem: problem.into(),
        }
    }
}
