//! Which parameter a report sweeps, if any: every scene comes from one generator, and the
//! specs differ in exactly one numeric key (`teapot-in-stadium:size_ratio=1e-1` … `=1e-5`,
//! `sphere:triangles=500` … `=8000`). Such a report is drawn against that parameter, and its
//! scenes are named by it ("size_ratio=1e-3") wherever a chart names them.
//!
//! The resolved parameters in each scene's `source` are compared (defaults included, so
//! `teapot` and `teapot:triangles=4096` are one sweep); for a report without them the scene
//! names are parsed as specs instead.

use super::names::scene_names;
use super::ticks::tick_label;
use crate::report::run::Report;
use serde_json::Value;
use std::collections::BTreeMap;

/// One scene of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    pub scene: String,
    /// The swept parameter's value.
    pub value: f64,
    /// Where the scene sits on a chart's x axis: the traced triangle count for a `triangles`
    /// sweep (what the structures really held, which a generator may round), else `value`.
    pub x: f64,
    /// "size_ratio=1e-3": the key and the value as the spec wrote it, or its tick label when
    /// that is shorter.
    pub label: String,
    /// Triangles traced.
    pub triangles: u64,
}

/// A report's swept parameter and its scenes in increasing order of the parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub generator: String,
    pub key: String,
    pub points: Vec<SweepPoint>,
}

/// Fewest scenes that make a sweep: two points show no trend and fit no exponent.
const MIN_POINTS: usize = 3;

impl Sweep {
    pub fn detect(report: &Report) -> Option<Sweep> {
        let scenes = scene_names(report);
        if scenes.len() < MIN_POINTS {
            return None;
        }
        let specs: Vec<Spec> = scenes
            .iter()
            .map(|s| Spec::of(report, s))
            .collect::<Option<_>>()?;
        let first = &specs[0];
        if specs
            .iter()
            .any(|s| s.generator != first.generator || s.seed != first.seed)
        {
            return None;
        }
        let keys: std::collections::BTreeSet<&String> =
            specs.iter().flat_map(|s| s.params.keys()).collect();
        let mut differing = keys.into_iter().filter(|k| {
            specs
                .iter()
                .any(|s| s.params.get(*k) != first.params.get(*k))
        });
        let key = differing.next()?.clone();
        if differing.next().is_some() {
            return None;
        }
        let mut points = Vec::new();
        for (scene, spec) in scenes.iter().zip(&specs) {
            let value = spec.params.get(&key)?.as_f64()?;
            let triangles = triangles_of(report, scene);
            let x = if key == "triangles" && triangles > 0 {
                triangles as f64
            } else {
                value
            };
            points.push(SweepPoint {
                scene: scene.clone(),
                value,
                x,
                label: String::new(),
                triangles,
            });
        }
        // The values as the specs wrote them ("1e-3"), unless one is missing or long
        // ("4194304"): then every label is a tick label ("4.19M"), so that one chart never
        // mixes the two styles.
        let written: Option<Vec<String>> = points
            .iter()
            .map(|p| {
                written_value(&p.scene, &key)
                    .filter(|w| w.chars().count() <= 6)
                    .map(str::to_string)
            })
            .collect();
        for (i, p) in points.iter_mut().enumerate() {
            let text = match &written {
                Some(w) => w[i].clone(),
                None => tick_label(p.value),
            };
            p.label = format!("{key}={text}");
        }
        points.sort_by(|a, b| a.value.total_cmp(&b.value));
        if points.windows(2).any(|p| p[0].value == p[1].value) {
            return None;
        }
        Some(Sweep {
            generator: first.generator.clone(),
            key,
            points,
        })
    }

    /// The chart label of `scene` (its swept value), if it is one of the sweep's.
    pub fn label(&self, scene: &str) -> Option<&str> {
        self.points
            .iter()
            .find(|p| p.scene == scene)
            .map(|p| p.label.as_str())
    }

    /// A logarithmic x axis when the values span more than a factor of 10.
    pub fn log_x(&self) -> bool {
        let xs = || self.points.iter().map(|p| p.x);
        let lo = xs().fold(f64::INFINITY, f64::min);
        let hi = xs().fold(f64::NEG_INFINITY, f64::max);
        lo > 0.0 && hi / lo > 10.0
    }

    /// What the x axis shows: "size_ratio of teapot-in-stadium".
    pub fn x_desc(&self) -> String {
        if self.key == "triangles" {
            format!("triangles traced ({} sweep)", self.generator)
        } else {
            format!("{} of {}", self.key, self.generator)
        }
    }

    /// True when the scenes grow: at least three different triangle counts spanning a factor
    /// of 4 or more. Then time and work per ray can be fitted against N.
    pub fn is_size_sweep(&self) -> bool {
        let mut n: Vec<u64> = self.points.iter().map(|p| p.triangles).collect();
        n.sort_unstable();
        n.dedup();
        n.len() >= MIN_POINTS && n[0] > 0 && n[n.len() - 1] >= 4 * n[0]
    }
}

/// The triangles every structure traced on `scene`.
fn triangles_of(report: &Report, scene: &str) -> u64 {
    report
        .scenes
        .iter()
        .find(|s| s.name == scene)
        .map(|s| s.triangles.traced)
        .or_else(|| {
            report
                .results
                .iter()
                .find(|r| r.scene == scene)
                .map(|r| r.triangles.traced)
        })
        .unwrap_or(0)
}

/// A procedural scene's generator, seed and parameters.
#[derive(Debug)]
struct Spec {
    generator: String,
    seed: Option<u64>,
    params: BTreeMap<String, Value>,
}

impl Spec {
    /// From the scene record's `source`, or from the name when the report has no record.
    /// `None` for an OBJ file.
    fn of(report: &Report, scene: &str) -> Option<Spec> {
        match report.scenes.iter().find(|s| s.name == scene) {
            Some(record) => {
                let p = record.source.get("procedural")?;
                Some(Spec {
                    generator: p.get("generator")?.as_str()?.to_string(),
                    seed: p.get("seed").and_then(Value::as_u64),
                    params: p
                        .get("params")?
                        .as_object()?
                        .iter()
                        .map(|(k, v)| (k.clone(), v.clone()))
                        .collect(),
                })
            }
            None => Spec::parse(scene),
        }
    }

    /// `name:key=value,key=value`; numbers become JSON numbers, anything else strings.
    fn parse(name: &str) -> Option<Spec> {
        if name.ends_with(".obj") || name.contains('/') {
            return None;
        }
        let (generator, args) = name.split_once(':').unwrap_or((name, ""));
        let mut params = BTreeMap::new();
        for pair in args.split(',').filter(|p| !p.is_empty()) {
            let (k, v) = pair.split_once('=')?;
            let value = match v.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => serde_json::json!(x),
                _ => Value::String(v.trim().to_string()),
            };
            params.insert(k.trim().to_string(), value);
        }
        Some(Spec {
            generator: generator.to_string(),
            seed: None,
            params,
        })
    }
}

/// The text a scene name gives for `key` (`1e-3` in `teapot-in-stadium:size_ratio=1e-3`).
fn written_value<'a>(scene: &'a str, key: &str) -> Option<&'a str> {
    let (_, args) = scene.split_once(':')?;
    args.split(',')
        .filter_map(|p| p.split_once('='))
        .find(|(k, _)| k.trim() == key)
        .map(|(_, v)| v.trim())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spec_parses_into_generator_and_numbers() {
        let s = Spec::parse("teapot-in-stadium:size_ratio=1e-3,view=stadium").unwrap();
        assert_eq!(s.generator, "teapot-in-stadium");
        assert_eq!(s.params["size_ratio"].as_f64(), Some(1e-3));
        assert_eq!(s.params["view"].as_str(), Some("stadium"));
        assert!(Spec::parse("teapot").unwrap().params.is_empty());
        assert!(Spec::parse("bunny.obj").is_none());
        assert!(Spec::parse("sphere:triangles").is_none());
    }

    #[test]
    fn the_written_value_is_found_by_key() {
        assert_eq!(
            written_value("a:size_ratio=1e-3,b=2", "size_ratio"),
            Some("1e-3")
        );
        assert_eq!(written_value("a:b=2", "c"), None);
        assert_eq!(written_value("teapot", "triangles"), None);
    }
}
