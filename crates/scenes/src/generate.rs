//! Procedural scenes from a spec string: `name` or `name:key=value,key=value`.
//!
//! Parameters are checked before anything is allocated: unknown names and keys, repeated keys,
//! non-numbers, NaN, infinities, fractions where a count is expected, zero, negative values and
//! sizes beyond [`MAX_TRIANGLES`] are errors that name the spec and the parameter.

use crate::rng::{self, SOUP_STREAM};
use crate::{Camera, Scene, SceneError, SceneSource, View};
use raybench_geom::{TriangleMesh, Vec3};
use serde_json::Value;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Largest triangle count a generator will make (a soup this size takes 2.4 GB of vertices and
/// indices): a typo like `triangles=2e9` is an error, not an out-of-memory abort.
pub const MAX_TRIANGLES: u64 = 50_000_000;

/// A generator as listed by [`generators`].
#[derive(Debug)]
pub struct GeneratorInfo {
    pub name: &'static str,
    pub description: &'static str,
    /// `(key, meaning and default)`.
    pub params: &'static [(&'static str, &'static str)],
}

static GENERATORS: [GeneratorInfo; 3] = [
    GeneratorInfo {
        name: "sphere",
        description: "UV sphere centred at the origin, watertight (shared vertices, one vertex per pole)",
        params: &[
            (
                "triangles",
                "approximate triangle count, rounded to the nearest 4·s·(s-1) for s stacks and 2s slices, at least 8 (default 20000)",
            ),
            ("radius", "sphere radius, 1e-6 to 1e6 (default 1)"),
        ],
    },
    GeneratorInfo {
        name: "soup",
        description: "unconnected random triangles in the unit cube [0,1]³, edges about 0.02–0.1 long (uses the seed)",
        params: &[("triangles", "number of triangles (default 10000)")],
    },
    GeneratorInfo {
        name: "plane",
        description: "square grid over [-1,1]² of quads split into two triangles, shared vertices, tilted about the x axis",
        params: &[
            (
                "quads",
                "quads per side, so 2·quads² triangles, 1 to 5000 (default 64)",
            ),
            (
                "tilt_deg",
                "tilt about the x axis in degrees, 0 (flat, axis-aligned) to 80 (default 10)",
            ),
        ],
    },
];

/// The generators [`generate`] knows, with their parameters.
pub fn generators() -> &'static [GeneratorInfo] {
    &GENERATORS
}

/// How a parameter is checked. Ranges are inclusive.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Count { min: u64, max: u64 },
    Real { min: f64, max: f64 },
}

#[derive(Clone, Copy, Debug)]
struct ParamRule {
    key: &'static str,
    kind: Kind,
    default: f64,
}

/// The checking rules, in the same order as [`GENERATORS`]' `params` (a test keeps them in step).
fn rules(generator: &str) -> &'static [ParamRule] {
    const SPHERE: &[ParamRule] = &[
        ParamRule {
            key: "triangles",
            kind: Kind::Count {
                min: 1,
                max: MAX_TRIANGLES,
            },
            default: 20_000.0,
        },
        ParamRule {
            key: "radius",
            kind: Kind::Real {
                min: 1e-6,
                max: 1e6,
            },
            default: 1.0,
        },
    ];
    const SOUP: &[ParamRule] = &[ParamRule {
        key: "triangles",
        kind: Kind::Count {
            min: 1,
            max: MAX_TRIANGLES,
        },
        default: 10_000.0,
    }];
    const PLANE: &[ParamRule] = &[
        ParamRule {
            key: "quads",
            // 2 · 5000² = MAX_TRIANGLES.
            kind: Kind::Count { min: 1, max: 5000 },
            default: 64.0,
        },
        ParamRule {
            key: "tilt_deg",
            kind: Kind::Real {
                min: 0.0,
                max: 80.0,
            },
            default: 10.0,
        },
    ];
    match generator {
        "sphere" => SPHERE,
        "soup" => SOUP,
        "plane" => PLANE,
        _ => &[],
    }
}

/// Checked parameter values, defaults filled in.
struct Params(BTreeMap<&'static str, f64>);

impl Params {
    fn get(&self, key: &str) -> f64 {
        self.0[key]
    }
    fn count(&self, key: &str) -> u64 {
        self.0[key] as u64
    }
}

/// Makes a procedural scene. `seed` matters only for generators that say so (`soup`); it is
/// recorded in [`SceneSource::Procedural`] either way.
pub fn generate(spec: &str, seed: u64) -> Result<Scene, SceneError> {
    let (name, params) = parse_spec(spec)?;
    let (positions, indices, view) = match name {
        "sphere" => sphere(params.count("triangles"), params.get("radius") as f32),
        "soup" => soup(params.count("triangles"), seed),
        _ => plane(params.count("quads"), params.get("tilt_deg") as f32),
    };
    let (mesh, removed) = TriangleMesh::new(positions, indices)
        .map_err(|e| SceneError::generator(spec, e.to_string()))?;
    Ok(Scene {
        name: name.to_owned(),
        source: SceneSource::Procedural {
            generator: name.to_owned(),
            params: params_json(name, &params),
            seed,
        },
        mesh: Arc::new(mesh),
        removed,
        loader_notes: Vec::new(),
        view,
    })
}

fn parse_spec(spec: &str) -> Result<(&'static str, Params), SceneError> {
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
    let rules = rules(info.name);
    let mut values = BTreeMap::new();
    for item in rest.split(',').filter(|s| !s.trim().is_empty()) {
        let (key, value) = parse_item(spec, info.name, rules, item)?;
        if values.insert(key, value).is_some() {
            return Err(SceneError::generator(
                spec,
                format!("`{key}` is given twice"),
            ));
        }
    }
    for rule in rules {
        values.entry(rule.key).or_insert(rule.default);
    }
    Ok((info.name, Params(values)))
}

fn parse_item(
    spec: &str,
    generator: &str,
    rules: &'static [ParamRule],
    item: &str,
) -> Result<(&'static str, f64), SceneError> {
    let err = |problem: String| SceneError::generator(spec, problem);
    let (key, text) = item
        .split_once('=')
        .ok_or_else(|| err(format!("`{}` is not key=value", item.trim())))?;
    let (key, text) = (key.trim(), text.trim());
    let rule = rules.iter().find(|r| r.key == key).ok_or_else(|| {
        let known: Vec<_> = rules.iter().map(|r| r.key).collect();
        err(format!(
            "unknown parameter `{key}` for {generator} (known: {})",
            known.join(", ")
        ))
    })?;
    let value: f64 = text
        .parse()
        .map_err(|_| err(format!("{key} = `{text}` is not a number")))?;
    check_value(rule, value).map_err(|why| err(format!("{key} = {text}: {why}")))?;
    Ok((rule.key, value))
}

fn check_value(rule: &ParamRule, value: f64) -> Result<(), String> {
    if !value.is_finite() {
        return Err("not a finite number".into());
    }
    match rule.kind {
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
fn params_json(generator: &str, params: &Params) -> BTreeMap<String, Value> {
    rules(generator)
        .iter()
        .map(|rule| {
            let v = params.get(rule.key);
            let json = match rule.kind {
                Kind::Count { .. } => Value::from(v as u64),
                Kind::Real { .. } => Value::from(v),
            };
            (rule.key.to_owned(), json)
        })
        .collect()
}

type Built = (Vec<Vec3>, Vec<[u32; 3]>, View);

/// UV sphere with `s` stacks and `2s` slices: `2s` triangles in each polar cap, `4s` in each of
/// the `s - 2` bands, `4s(s-1)` in all. Rings are shared between neighbouring bands and the seam
/// wraps by index, so every edge belongs to exactly two triangles. Counter-clockwise seen from
/// outside.
fn sphere(target_triangles: u64, radius: f32) -> Built {
    let stacks = sphere_stacks(target_triangles);
    let slices = 2 * stacks;
    let mut positions = vec![Vec3::Y * radius];
    for ring in 1..stacks {
        let theta = std::f64::consts::PI * ring as f64 / stacks as f64;
        for j in 0..slices {
            let phi = std::f64::consts::TAU * j as f64 / slices as f64;
            let p = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            positions.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * radius);
        }
    }
    positions.push(-Vec3::Y * radius);
    let south = positions.len() as u32 - 1;
    let at = |ring: u32, j: u32| 1 + (ring - 1) * slices + j % slices;
    let mut indices = Vec::with_capacity((4 * stacks * (stacks - 1)) as usize);
    for j in 0..slices {
        indices.push([0, at(1, j + 1), at(1, j)]);
        indices.push([south, at(stacks - 1, j), at(stacks - 1, j + 1)]);
    }
    for ring in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b) = (at(ring, j), at(ring, j + 1));
            let (c, d) = (at(ring + 1, j), at(ring + 1, j + 1));
            indices.push([a, b, d]);
            indices.push([a, d, c]);
        }
    }
    (positions, indices, sphere_view(radius))
}

/// Stacks `s` such that `4s(s-1)` is nearest `target`: `s ≈ (1 + sqrt(1 + target)) / 2`.
fn sphere_stacks(target: u64) -> u32 {
    let s = ((1.0 + (1.0 + target as f64).sqrt()) / 2.0).round();
    s.max(2.0) as u32
}

/// The sphere seen from outside: at `r / sin 20°` it subtends 40° of the 50° field of view.
fn sphere_view(radius: f32) -> View {
    let distance = radius / 20f32.to_radians().sin();
    View {
        camera: Camera {
            eye: Vec3::new(0.3, 0.4, 1.0).normalize() * distance,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: Vec3::new(2.0, 4.0, 3.0) * radius,
    }
}

/// Edge lengths of soup triangles before the angle jitter.
const SOUP_EDGE: (f32, f32) = (0.02, 0.1);

/// `n` independent triangles: a random centre, a random plane through it, and three corners at
/// about 120° around the centre (±0.3 rad jitter). Corners stay inside the unit cube because the
/// centre keeps a margin of the largest corner radius, 0.1 / √3.
fn soup(n: u64, seed: u64) -> Built {
    let mut rng = rng::stream(seed, SOUP_STREAM);
    let margin = SOUP_EDGE.1 / 3f32.sqrt() + 1e-3;
    let mut positions = Vec::with_capacity(3 * n as usize);
    for _ in 0..n {
        let center = Vec3::new(
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
            rng::range_f32(&mut rng, margin, 1.0 - margin),
        );
        let normal = rng::uniform_sphere(&mut rng);
        let (e1, e2) = rng::orthonormal_basis(normal);
        let radius = rng::range_f32(&mut rng, SOUP_EDGE.0, SOUP_EDGE.1) / 3f32.sqrt();
        let spin = std::f32::consts::TAU * rng::unit_f32(&mut rng);
        for k in 0..3 {
            let angle =
                spin + k as f32 * std::f32::consts::TAU / 3.0 + rng::range_f32(&mut rng, -0.3, 0.3);
            positions.push(center + (e1 * angle.cos() + e2 * angle.sin()) * radius);
        }
    }
    let indices = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let view = View::of_bounds(&raybench_geom::Aabb::new(Vec3::ZERO, Vec3::ONE));
    (positions, indices, view)
}

/// A `quads × quads` grid over `[-1, 1]²`, the x–z plane tilted about the x axis by `tilt_deg`
/// (the point (x, z) goes to (x, z·sin t, z·cos t)), normals facing +y.
fn plane(quads: u64, tilt_deg: f32) -> Built {
    let n = quads as u32;
    let (sin_t, cos_t) = tilt_deg.to_radians().sin_cos();
    let coord = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for row in 0..=n {
        let z = coord(row);
        for col in 0..=n {
            positions.push(Vec3::new(coord(col), z * sin_t, z * cos_t));
        }
    }
    let at = |row: u32, col: u32| row * (n + 1) + col;
    let mut indices = Vec::with_capacity(2 * (n * n) as usize);
    for row in 0..n {
        for col in 0..n {
            let (a, b) = (at(row, col), at(row, col + 1));
            let (c, d) = (at(row + 1, col), at(row + 1, col + 1));
            indices.push([a, c, d]);
            indices.push([a, d, b]);
        }
    }
    (positions, indices, plane_view())
}

/// From above and in front of the plane, which spans about ±1 around the origin.
fn plane_view() -> View {
    View {
        camera: Camera {
            eye: Vec3::new(0.0, 1.6, 2.2),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 50.0,
        },
        light: Vec3::new(0.6, 2.5, 0.8),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_match_the_published_parameters() {
        for g in generators() {
            let keys: Vec<_> = rules(g.name).iter().map(|r| r.key).collect();
            let published: Vec<_> = g.params.iter().map(|p| p.0).collect();
            assert_eq!(keys, published, "{}", g.name);
        }
    }

    #[test]
    fn sphere_stacks_track_the_target() {
        assert_eq!(sphere_stacks(1), 2);
        let s = sphere_stacks(20_000) as u64;
        assert_eq!(4 * s * (s - 1), 19_880);
        let s = sphere_stacks(MAX_TRIANGLES) as u64;
        assert!(4 * s * (s - 1) <= MAX_TRIANGLES + MAX_TRIANGLES / 1000);
    }

    #[test]
    fn sphere_and_plane_face_outwards_and_up() {
        let (p, idx, _) = sphere(500, 2.0);
        for t in &idx {
            let [a, b, c] = t.map(|i| p[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "{t:?}");
        }
        let (p, idx, _) = plane(4, 10.0);
        for t in &idx {
            let [a, b, c] = t.map(|i| p[i as usize]);
            assert!((b - a).cross(c - a).y > 0.0, "{t:?}");
        }
    }

    #[test]
    fn soup_triangles_stay_in_the_unit_cube() {
        let (p, _, _) = soup(2000, 3);
        let cube = raybench_geom::Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!(p.iter().all(|&v| cube.contains(v)));
    }
}
