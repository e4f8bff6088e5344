//! raybench-scenes: the scenes and rays every structure is measured on.
//!
//! * Scenes: procedural generators ([`fn@generate`], listed by [`generators`]) and Wavefront OBJ
//!   files ([`load_obj`]), both behind [`resolve`]. OBJ files are untrusted input: every problem
//!   is a [`SceneError`] naming the file (and line), never a panic.
//! * Workloads ([`Workload`]): primary, random, shadow, diffuse and Whitted rays, and
//!   closest-point queries. Each is a pure function of its inputs and a seed, using `rand_pcg`
//!   streams that are independent per purpose; [`RayRecipe`] makes a scene's ray workloads
//!   from a reference's primary hits, the one way every caller makes them.
//! * Suites ([`Suite`]): JSON manifests in the repository's `bench-scenes/`, and
//!   [`SceneRequest`], the one resolver of the scenes a run asks for.
#![forbid(unsafe_code)]

mod error;
mod generate;
pub mod input;
mod material;
mod obj;
pub mod points;
mod recipe;
mod request;
mod rng;
pub mod sha256;
mod suite;
mod view;
mod workload;

pub use error::SceneError;
pub use generate::{
    GeneratorInfo, Kind, MAX_TRIANGLES, ParamInfo, check_spec, generate, generators, view_names,
    view_probe_spec,
};
pub use material::Material;
pub use obj::export::{in_file_order, write_obj};
pub use obj::{load_obj, load_obj_bytes};
pub use recipe::{RayRecipe, TraceFn};
pub use request::{SceneRequest, printable};
pub use suite::{Suite, SuiteScene, list_suites, load_suite, suites_dir};
pub use view::{Camera, View};
pub use workload::{
    SHADOW_T_MAX, SurfaceHit, SurfacePoint, WhittedParams, Workload, diffuse_rays, primary_rays,
    primary_rays_sized, random_rays, shadow_rays, surface_point, whitted_children,
};

use raybench_geom::{RemovedTriangles, TriangleMesh};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

// Re-exported so users of the scene API need not depend on raybench-geom for `View`'s fields.
pub use raybench_geom::Vec3;

/// A mesh ready to trace, with where it came from and how to look at it.
#[derive(Clone, Debug)]
pub struct Scene {
    /// "sphere", "soup", "plane", or the OBJ file stem (e.g. "stanford-bunny").
    pub name: String,
    pub source: SceneSource,
    pub mesh: Arc<TriangleMesh>,
    /// Triangles [`TriangleMesh::new`] removed (and zero-area ones it kept), for the report.
    pub removed: RemovedTriangles,
    /// What the loader skipped or changed, e.g. "12 point/line elements skipped".
    pub loader_notes: Vec<String>,
    /// The default view (primary rays use it).
    pub view: View,
    /// Every named view of the scene; the first is the one `view` defaults to.
    pub views: Vec<NamedView>,
    /// At least one entry; `triangle_materials` indexes it.
    pub materials: Vec<Material>,
    /// Material per triangle; empty means every triangle uses `materials[0]`.
    pub triangle_materials: Vec<u32>,
}

/// A view with a name, e.g. "closeup" and "stadium" for `teapot-in-stadium`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NamedView {
    pub name: String,
    pub view: View,
}

impl Scene {
    /// The material of triangle `prim`.
    pub fn material(&self, prim: u32) -> Material {
        let index = self
            .triangle_materials
            .get(prim as usize)
            .copied()
            .unwrap_or(0);
        self.materials
            .get(index as usize)
            .copied()
            .unwrap_or_default()
    }
}

/// Where a scene came from, enough to make it again.
///
/// Serialises as `{"procedural": {"generator": "sphere", "params": {...}, "seed": 1}}` or
/// `{"obj": {"path": "..."}}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SceneSource {
    Procedural {
        generator: String,
        /// Every parameter, defaults filled in (counts as integers).
        params: BTreeMap<String, serde_json::Value>,
        seed: u64,
    },
    Obj {
        path: PathBuf,
        /// SHA-256 of the file's bytes (as `sha256sum` prints it); empty in older reports.
        #[serde(default)]
        sha256: String,
    },
}

/// A scene from a spec: a path ending in `.obj` (any case) is loaded, anything else is a
/// generator spec such as `sphere:triangles=20000`.
pub fn resolve(spec: &str, seed: u64) -> Result<Scene, SceneError> {
    if is_obj_path(spec) {
        load_obj(Path::new(spec))
    } else {
        generate(spec, seed)
    }
}

pub(crate) fn is_obj_path(spec: &str) -> bool {
    spec.len() >= 4
        && spec.is_char_boundary(spec.len() - 4)
        && spec[spec.len() - 4..].eq_ignore_ascii_case(".obj")
}
