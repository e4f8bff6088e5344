//! Procedural scenes from a spec string: `name` or `name:key=value,key=value`.
//!
//! Every generator is one entry of [`GENERATORS`]: its name, description, parameters (with
//! their checks and defaults) and build function, in a file of its own. Parameters are checked
//! before anything is allocated: unknown names and keys, repeated keys, non-numbers, NaN,
//! infinities, fractions where a count is expected, values outside the declared range and sizes
//! beyond [`MAX_TRIANGLES`] are errors that name the spec and the parameter. Every generator
//! also accepts `view=NAME` to pick which of its named views is the default.

mod adversarial;
mod basic;
mod city;
mod grass;
mod hair;
mod stadium;
mod teapot;
mod terrain;

use crate::{Material, NamedView, Scene, SceneError, SceneSource, View};
use raybench_geom::{TriangleMesh, Vec3};
use serde_json::Value;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Largest triangle count a generator will make (a soup this size takes 2.4 GB of vertices and
/// indices): a typo like `triangles=2e9` is an error, not an out-of-memory abort.
pub const MAX_TRIANGLES: u64 = 50_000_000;

/// A generator: listed by [`generators`], run by [`generate`].
#[derive(Debug)]
pub struct GeneratorInfo {
    pub name: &'static str,
    pub description: &'static str,
    pub params: &'static [ParamInfo],
    /// Whether the seed changes the geometry (it is recorded either way).
    pub uses_seed: bool,
    pub(crate) build: BuildFn,
}

/// One parameter of a generator.
#[derive(Clone, Copy, Debug)]
pub struct ParamInfo {
    pub key: &'static str,
    /// What it means (the default and range are printed from `kind` and `default`).
    pub meaning: &'static str,
    pub kind: Kind,
    pub default: f64,
}

/// How a parameter is checked. Ranges are inclusive.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Count { min: u64, max: u64 },
    Real { min: f64, max: f64 },
}

impl ParamInfo {
    /// `meaning (range, default)`, for `raybench list`.
    pub fn describe(&self) -> String {
        match self.kind {
            Kind::Count { min, max } => format!(
                "{} ({min} to {max}, default {})",
                self.meaning, self.default
            ),
            Kind::Real { min, max } => format!(
                "{} ({min} to {max}, default {})",
                self.meaning, self.default
            ),
        }
    }
}

/// A count parameter for a triangle budget.
pub(crate) const fn triangles(meaning: &'static str, default: f64) -> ParamInfo {
    ParamInfo {
        key: "triangles",
        meaning,
        kind: Kind::Count {
            min: 1,
            max: MAX_TRIANGLES,
        },
        default,
    }
}

pub(crate) type BuildFn = fn(&Params, u64) -> Result<Built, String>;

/// What a generator makes: geometry, named views (the first is the default) and materials.
#[derive(Clone, Debug)]
pub(crate) struct Built {
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    pub views: Vec<NamedView>,
    /// Empty: every triangle uses [`Material::DEFAULT`].
    pub materials: Vec<Material>,
    /// Per triangle, an index into `materials` (empty: all use material 0).
    pub triangle_materials: Vec<u32>,
}

impl Built {
    /// Geometry with one view called "default" and the default material.
    pub fn new(positions: Vec<Vec3>, indices: Vec<[u32; 3]>, view: View) -> Built {
        Built {
            positions,
            indices,
            views: vec![NamedView {
                name: "default".into(),
                view,
            }],
            materials: Vec::new(),
            triangle_materials: Vec::new(),
        }
    }
}

/// Checked parameter values, defaults filled in.
#[derive(Debug)]
pub(crate) struct Params(BTreeMap<&'static str, f64>);

impl Params {
    pub fn get(&self, key: &str) -> f64 {
        self.0[key]
    }
    pub fn f32(&self, key: &str) -> f32 {
        self.0[key] as f32
    }
    pub fn count(&self, key: &str) -> u64 {
        self.0[key] as u64
    }
}

static GENERATORS: &[GeneratorInfo] = &[
    basic::SPHERE,
    basic::SOUP,
    basic::PLANE,
    teapot::TEAPOT,
    stadium::TEAPOT_IN_STADIUM,
    grass::GRASS,
    terrain::TERRAIN,
    hair::HAIR,
    city::CITY,
    adversarial::ONE_CENTROID,
    adversarial::COPLANAR,
    adversarial::OFFSET,
    adversarial::ZERO_AREA_MIXED,
    adversarial::SINGLE_TRIANGLE,
    adversarial::EMPTY,
    adversarial::IDENTICAL,
    adversarial::FAN,
    adversarial::HUGE_AND_SMALL,
    adversarial::DEEP,
];

/// The generators [`generate`] knows, with their parameters.
pub fn generators() -> &'static [GeneratorInfo] {
    GENERATORS
}

/// Checks a spec (generator name, parameter names and values, and the view if one is named)
/// without generating the scene: cheap even for 10M-triangle specs.
pub fn check_spec(spec: &str) -> Result<(), SceneError> {
    let parsed = parse_spec(spec)?;
    if let Some(name) = &parsed.view {
        let names = view_names(parsed.info)?;
        if !names.contains(name) {
            return Err(unknown_view(spec, name, &names));
        }
    }
    Ok(())
}

/// Triangle budget used to learn a generator's views: views come from the generator's layout,
/// not from its size, and a few hundred triangles cost nothing.
const VIEW_PROBE_TRIANGLES: u64 = 200;

/// The spec [`view_names`] generates: the generator at `VIEW_PROBE_TRIANGLES` if it has a
/// `triangles` parameter, else at its defaults.
pub fn view_probe_spec(info: &GeneratorInfo) -> String {
    match info.params.iter().find(|p| p.key == "triangles") {
        Some(p) => {
            let n = match p.kind {
                Kind::Count { min, max } => VIEW_PROBE_TRIANGLES.clamp(min, max),
                Kind::Real { .. } => VIEW_PROBE_TRIANGLES,
            };
            format!("{}:triangles={n}", info.name)
        }
        None => info.name.to_owned(),
    }
}

/// The names of a generator's views (the first is its default), learned by generating it
/// small ([`view_probe_spec`]).
pub fn view_names(info: &GeneratorInfo) -> Result<Vec<String>, SceneError> {
    let scene = generate(&view_probe_spec(info), 1)?;
    Ok(scene.views.into_iter().map(|v| v.name).collect())
}

fn unknown_view(spec: &str, name: &str, known: &[String]) -> SceneError {
    SceneError::generator(
        spec,
        format!("unknown view `{name}` (known: {})", known.join(", ")),
    )
}

/// Makes a procedural scene from a spec.
pub fn generate(spec: &str, seed: u64) -> Result<Scene, SceneError> {
    let parsed = parse_spec(spec)?;
    let info = parsed.info;
    let built = (info.build)(&parsed.params, seed).map_err(|e| SceneError::generator(spec, e))?;
    let view = pick_view(spec, &built.views, parsed.view.as_deref())?;
    let expected = built.indices.len();
    let (mesh, removed) = TriangleMesh::new(built.positions, built.indices)
        .map_err(|e| SceneError::generator(spec, e.to_string()))?;
    let mut loader_notes = Vec::new();
    // Material indices are per generated triangle; if the mesh dropped any, they no longer line
    // up, so the scene falls back to the default material and says so.
    let triangle_materials = if mesh.len() == expected {
        built.triangle_materials
    } else {
        loader_notes.push(format!(
            "{} triangles removed; per-triangle materials dropped",
            expected - mesh.len()
        ));
        Vec::new()
    };
    let mut params = params_json(info, &parsed.params);
    if let Some(v) = &parsed.view {
        params.insert("view".into(), Value::from(v.clone()));
    }
    Ok(Scene {
        name: info.name.to_owned(),
        source: SceneSource::Procedural {
            generator: info.name.to_owned(),
            params,
            seed,
        },
        mesh: Arc::new(mesh),
        removed,
        loader_notes,
        view,
        views: built.views,
        materials: if built.materials.is_empty() {
            vec![Material::DEFAULT]
        } else {
            built.materials
        },
        triangle_materials,
    })
}

fn pick_view(spec: &str, views: &[NamedView], wanted: Option<&str>) -> Result<View, SceneError> {
    let Some(name) = wanted else {
        return Ok(views[0].view);
    };
    views
        .iter()
        .find(|v| v.name == name)
        .map(|v| v.view)
        .ok_or_else(|| {
            let known: Vec<String> = views.iter().map(|v| v.name.clone()).collect();
            unknown_view(spec, name, &known)
        })
}

struct ParsedSpec {
    info: &'static GeneratorInfo,
    params: Params,
    view: Option<String>,
}

fn parse_spec(spec: &str) -> Result<ParsedSpec, SceneError> {
    let (name, rest) = spec.trim().split_once(':').unwrap_or((spec.trim(), ""));
    let info = GENERATORS
        .iter()
        .find(|g| g.name.eq_ignore_ascii_case(name.trim()))
        .ok_or_else(|| {
            let known: Vec<_> = GENERATORS.iter().map(|g| g.name).collect();
            SceneError::generator(
                spec,
                format!(
                    "unknown generator `{}` (known: {}; or a path ending in .obj)",
                    name.trim(),
                    known.join(", ")
                ),
            )
        })?;
    let mut values = BTreeMap::new();
    let mut view = None;
    for item in rest.split(',').filter(|s| !s.trim().is_empty()) {
        if let Some((key, name)) = item.split_once('=').filter(|(k, _)| k.trim() == "view") {
            if view.replace(name.trim().to_owned()).is_some() {
                return Err(SceneError::generator(
                    spec,
                    format!("`{}` is given twice", key.trim()),
                ));
            }
            continue;
        }
        let (key, value) = parse_item(spec, info, item)?;
        if values.insert(key, value).is_some() {
            return Err(SceneError::generator(
                spec,
                format!("`{key}` is given twice"),
            ));
        }
    }
    for p in info.params {
        values.entry(p.key).or_insert(p.default);
    }
    Ok(ParsedSpec {
        info,
        params: Params(values),
        view,
    })
}

fn parse_item(
    spec: &str,
    info: &GeneratorInfo,
    item: &str,
) -> Result<(&'static str, f64), SceneError> {
    let err = |problem: String| SceneError::generator(spec, problem);
    let (key, text) = item
        .split_once('=')
        .ok_or_else(|| err(format!("`{}` is not key=value", item.trim())))?;
    let (key, text) = (key.trim(), text.trim());
    let param = info.params.iter().find(|p| p.key == key).ok_or_else(|| {
        let known: Vec<_> = info.params.iter().map(|p| p.key).chain(["view"]).collect();
        err(format!(
            "unknown parameter `{key}` for {} (known: {})",
            info.name,
            known.join(", ")
        ))
    })?;
    let value: f64 = text
        .parse()
        .map_err(|_| err(format!("{key} = `{text}` is not a number")))?;
    check_value(param, value).map_err(|why| err(format!("{key} = {text}: {why}")))?;
    Ok((param.key, value))
}

fn check_value(param: &ParamInfo, value: f64) -> Result<(), String> {
    if !value.is_finite() {
        return Err("not a finite number".into());
    }
    match param.kind {
        Kind::Count { min, max } => {
            if value.fract() != 0.0 {
                Err("must be a whole number".into())
            } else if value < min as f64 {
                Err(format!("must be at least {min}"))
            } else if value > max as f64 {
                Err(format!("more than the limit {max} (memory)"))
            } else {
                Ok(())
            }
        }
        Kind::Real { min, max } if !(min..=max).contains(&value) => {
            Err(format!("must be between {min} and {max}"))
        }
        Kind::Real { .. } => Ok(()),
    }
}

/// Counts as JSON integers, reals as JSON floats, for the scene's recorded source.
fn params_json(info: &GeneratorInfo, params: &Params) -> BTreeMap<String, Value> {
    info.params
        .iter()
        .map(|p| {
            let v = params.get(p.key);
            let json = match p.kind {
                Kind::Count { .. } => Value::from(v as u64),
                Kind::Real { .. } => Value::from(v),
            };
            (p.key.to_owned(), json)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_lie_in_their_ranges_and_names_are_unique() {
        let mut names = std::collections::HashSet::new();
        for g in generators() {
            assert!(names.insert(g.name), "{} registered twice", g.name);
            for p in g.params {
                assert!(
                    check_value(p, p.default).is_ok(),
                    "{}.{} default {}",
                    g.name,
                    p.key,
                    p.default
                );
            }
        }
    }

    #[test]
    fn unknown_view_is_an_error_naming_the_views() {
        let err = generate("sphere:view=sideways", 1).unwrap_err().to_string();
        assert!(err.contains("sideways") && err.contains("default"), "{err}");
        let checked = check_spec("sphere:view=sideways").unwrap_err().to_string();
        assert_eq!(checked, err);
        let err = check_spec("teapot-in-stadium:view=nowhere,size_ratio=1e-4")
            .unwrap_err()
            .to_string();
        assert!(err.contains("`nowhere` (known: closeup, stadium)"), "{err}");
        assert!(check_spec("teapot-in-stadium:view=stadium,size_ratio=1e-4").is_ok());
        assert!(check_spec("sphere:view=default").is_ok());
        assert!(generate("sphere:view=default", 1).is_ok());
    }
}
