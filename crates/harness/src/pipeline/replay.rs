//! `raybench replay`: one ray, bit for bit, through every structure, the references and a
//! double-precision recomputation over every triangle, with each answer's validation class
//! against `embree-medium`. The ray comes from a report's `ray_bits` or verify's replay line.

use super::check::verdict_name;
use crate::registry::{BuildContext, Registry};
use anyhow::{Context, Result, bail};
use raybench_accel::classify::{Tolerance, classify, classify_occlusion};
use raybench_accel::{Accel, Hit};
use raybench_geom::{DVec3, Ray, Triangle, TriangleMesh};

/// The reference verdicts are computed against (the one `run` and `verify` use first).
pub const VERDICT_REFERENCE: &str = "embree-medium";

/// Structures always shown, whatever `--structure` asks for: the verify references.
const ALWAYS_SHOWN: [&str; 3] = super::verify::REFERENCES;

/// Parses the 8 hex f32 bit patterns `ox,oy,oz,dx,dy,dz,tmin,tmax` (with or without `0x`,
/// separated by commas and/or spaces; brackets and quotes from a pasted JSON array are
/// ignored) and checks the ray as Embree would.
pub fn parse_ray_bits(text: &str) -> Result<Ray> {
    let cleaned: String = text
        .chars()
        .map(|c| {
            if matches!(c, '[' | ']' | '"' | '\'') {
                ' '
            } else {
                c
            }
        })
        .collect();
    let words: Vec<&str> = cleaned
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .collect();
    if words.len() != 8 {
        bail!(
            "--ray: expected 8 hex f32 bit patterns (ox,oy,oz,dx,dy,dz,tmin,tmax), got {}",
            words.len()
        );
    }
    let mut bits = [0u32; 8];
    for (i, (word, slot)) in words.iter().zip(&mut bits).enumerate() {
        *slot = parse_hex_word(word)
            .with_context(|| format!("--ray value {} ({}) '{word}'", i + 1, FIELD_NAMES[i]))?;
    }
    let ray = Ray::from_bits(bits);
    ray.check()
        .map_err(|e| anyhow::anyhow!("--ray {}: {e}", join_bits(&bits)))?;
    Ok(ray)
}

const FIELD_NAMES: [&str; 8] = [
    "origin.x", "origin.y", "origin.z", "dir.x", "dir.y", "dir.z", "t_min", "t_max",
];

fn parse_hex_word(word: &str) -> Result<u32> {
    let digits = word
        .strip_prefix("0x")
        .or_else(|| word.strip_prefix("0X"))
        .unwrap_or(word);
    if digits.is_empty() || digits.len() > 8 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        bail!("is not a hex f32 bit pattern (1 to 8 hex digits, optional 0x)");
    }
    Ok(u32::from_str_radix(digits, 16)?)
}

pub(crate) fn join_bits(bits: &[u32; 8]) -> String {
    bits.iter()
        .map(|b| format!("{b:#010x}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// Where the ray meets one triangle, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct F64Crossing {
    pub prim: u32,
    pub t: f64,
    pub u: f64,
    pub v: f64,
    /// Signed distance from the crossing point to the triangle's nearest edge (positive
    /// inside), in scene units.
    pub edge_distance: f64,
    /// The arbiter's edge tolerance at this crossing (`position_eps × scale`).
    pub edge_tolerance: f64,
}

/// The double-precision answer over every triangle: the closest crossing inside a triangle
/// (`edge_distance >= 0`) with `t_min < t <= t_max`, and the crossing that came closest to
/// being a hit before it (the largest negative edge distance at a smaller or equal t).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F64Answer {
    pub hit: Option<F64Crossing>,
    pub nearest_miss: Option<F64Crossing>,
}

/// Brute force in f64 over every triangle (ties at equal t go to the lower index, like
/// `bruteforce` and Embree's primitive order).
pub fn f64_answer(mesh: &TriangleMesh, ray: &Ray, tol: &Tolerance) -> F64Answer {
    let crossings: Vec<F64Crossing> = (0..mesh.len())
        .filter_map(|i| crossing(&mesh.triangle(i), i as u32, ray, tol))
        .filter(|x| x.t > ray.t_min() as f64 && x.t <= ray.t_max() as f64)
        .collect();
    let hit = crossings
        .iter()
        .filter(|x| x.edge_distance >= 0.0)
        .min_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)))
        .copied();
    let before = hit.map_or(f64::INFINITY, |h| h.t);
    let nearest_miss = crossings
        .iter()
        .filter(|x| x.edge_distance < 0.0 && x.t <= before)
        .max_by(|a, b| a.edge_distance.total_cmp(&b.edge_distance))
        .copied();
    F64Answer { hit, nearest_miss }
}

fn crossing(tri: &Triangle, prim: u32, ray: &Ray, tol: &Tolerance) -> Option<F64Crossing> {
    let x = tri.plane_crossing_f64(ray)?;
    let [p0, p1, p2] = [tri.v0, tri.v1, tri.v2].map(|p| p.as_dvec3());
    let q = ray.origin().as_dvec3() + ray.dir().as_dvec3() * x.t;
    let (e1, e2) = (p1 - p0, p2 - p0);
    let n = e1.cross(e2);
    let nn = n.length_squared();
    // q = p0 + u e1 + v e2  ⇒  (q - p0) × e2 = u n  and  e1 × (q - p0) = v n.
    let bary = |a: DVec3, b: DVec3| a.cross(b).dot(n) / nn;
    Some(F64Crossing {
        prim,
        t: x.t,
        u: bary(q - p0, e2),
        v: bary(e1, q - p0),
        edge_distance: x.edge_distance,
        edge_tolerance: tol.position_eps * x.scale,
    })
}

/// One structure's answers to the ray.
#[derive(Clone, Debug)]
pub struct StructureAnswer {
    pub name: String,
    pub closest: Option<Hit>,
    pub occluded: bool,
    /// Against [`VERDICT_REFERENCE`]: the closest-hit class and the any-hit class.
    pub closest_verdict: &'static str,
    pub any_verdict: &'static str,
}

/// Everything `replay` prints.
#[derive(Clone, Debug)]
pub struct Replay {
    pub scene: String,
    pub triangles: usize,
    pub seed: u64,
    pub ray: Ray,
    pub f64_answer: F64Answer,
    pub answers: Vec<StructureAnswer>,
}

/// [`replay_with`] the built-in structures.
pub fn replay(scene_spec: &str, structures: &[String], ray: Ray, seed: u64) -> Result<Replay> {
    replay_with(&Registry::builtin(), scene_spec, structures, ray, seed)
}

/// Loads the scene, builds the requested structures (default: every one in `registry`) plus
/// the references, and traces the one ray through each.
pub fn replay_with(
    registry: &Registry,
    scene_spec: &str,
    structures: &[String],
    ray: Ray,
    seed: u64,
) -> Result<Replay> {
    let mut names: Vec<String> = if structures.is_empty() {
        registry.names()
    } else {
        structures.to_vec()
    };
    for r in ALWAYS_SHOWN.iter().rev() {
        if !names.iter().any(|n| n == r) {
            names.insert(0, r.to_string());
        }
    }
    let entries = registry.select(&names)?;
    let scene = raybench_scenes::resolve(scene_spec, seed)
        .with_context(|| format!("scene '{scene_spec}'"))?;
    let mesh = scene.mesh.clone();
    let ctx = BuildContext::new(1);
    let tol = Tolerance::default();
    let mut built: Vec<(String, Box<dyn Accel>)> = Vec::new();
    for e in &entries {
        let b = e
            .build(mesh.clone(), &ctx)
            .with_context(|| format!("building {}", e.name))?;
        built.push((e.name.to_string(), b.accel));
    }
    let reference = &built
        .iter()
        .find(|(n, _)| n == VERDICT_REFERENCE)
        .expect("references are always built")
        .1;
    let (ref_hit, ref_occluded) = (reference.intersect(&ray), reference.occluded(&ray));
    let answers = built
        .iter()
        .map(|(name, accel)| {
            let closest = accel.intersect(&ray);
            let occluded = accel.occluded(&ray);
            let any = classify_occlusion(
                &mesh,
                &ray,
                occluded,
                ref_occluded,
                || (closest, ref_hit),
                &tol,
            );
            StructureAnswer {
                name: name.clone(),
                closest,
                occluded,
                closest_verdict: verdict_name(classify(&mesh, &ray, closest, ref_hit, &tol)),
                any_verdict: verdict_name(any),
            }
        })
        .collect();
    Ok(Replay {
        scene: scene_spec.to_string(),
        triangles: mesh.len(),
        seed,
        ray,
        f64_answer: f64_answer(&mesh, &ray, &tol),
        answers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Vec3;

    #[test]
    fn bits_parse_in_every_pasted_form() {
        let want = Ray::new(
            Vec3::new(1.0, 0.5, -2.0),
            Vec3::new(0.0, -0.0, 1.0),
            0.0,
            f32::INFINITY,
        );
        for text in [
            "0x3f800000,0x3f000000,0xc0000000,0x00000000,0x80000000,0x3f800000,0x00000000,0x7f800000",
            "3f800000 3f000000 c0000000 0 80000000 3f800000 0 7f800000",
            r#"["0x3f800000", "0x3f000000", "0xc0000000", "0x0", "0x80000000", "0x3F800000", "0x0", "0x7f800000"]"#,
        ] {
            let r = parse_ray_bits(text).unwrap();
            assert_eq!(r.to_bits(), want.to_bits(), "{text}");
        }
    }

    #[test]
    fn bad_rays_are_one_clear_line() {
        let err = |t: &str| format!("{:#}", parse_ray_bits(t).unwrap_err());
        assert!(err("1,2,3").contains("expected 8") && err("1,2,3").contains("got 3"));
        let e = err("0x3f800000,0,0,0,0,zz,0,0");
        assert!(
            e.contains("value 6") && e.contains("dir.z") && e.contains("'zz'"),
            "{e}"
        );
        assert!(err("123456789,0,0,0,0,0,0,0").contains("hex f32"));
        // NaN origin (0x7fc00000): Embree would abort on it.
        let e = err("0x7fc00000,0,0,0,0,0x3f800000,0,0x7f800000");
        assert!(
            e.contains("origin.x is NaN") && e.contains("0x7fc00000"),
            "{e}"
        );
        assert!(err("0,0,0,0,0,0,0,0x7f800000").contains("direction is (0, 0, 0)"));
        assert!(!e.contains('\n'));
    }

    #[test]
    fn double_precision_answer_finds_the_closest_and_the_near_miss() {
        // Two unit squares at z = 0 (split on the diagonal) and z = -1.
        let quad = |z: f32| {
            [
                Triangle::new(
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(1.0, 0.0, z),
                    Vec3::new(1.0, 1.0, z),
                ),
                Triangle::new(
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(1.0, 1.0, z),
                    Vec3::new(0.0, 1.0, z),
                ),
            ]
        };
        let tris: Vec<Triangle> = quad(0.0).into_iter().chain(quad(-1.0)).collect();
        let mesh = TriangleMesh::from_triangles(&tris).unwrap().0;
        let tol = Tolerance::default();
        let down = |x: f32, y: f32| Ray::infinite(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let a = f64_answer(&mesh, &down(0.75, 0.25), &tol);
        let h = a.hit.unwrap();
        assert_eq!((h.prim, h.t), (0, 1.0));
        assert!(
            (h.u - 0.5).abs() < 1e-12 && (h.v - 0.25).abs() < 1e-12,
            "{h:?}"
        );
        assert!((h.edge_distance - 0.25).abs() < 1e-12);
        // Just outside the squares: no hit; the nearest miss is 0.01 outside an edge.
        let a = f64_answer(&mesh, &down(1.01, 0.5), &tol);
        assert_eq!(a.hit, None);
        let m = a.nearest_miss.unwrap();
        assert!((m.edge_distance + 0.01).abs() < 1e-6, "{m:?}");
    }
}
