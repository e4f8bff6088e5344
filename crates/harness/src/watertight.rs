//! `raybench watertight`: do rays slip through the cracks between triangles?
//!
//! Meshes whose surfaces are closed sheets (the UV sphere, whose every edge is shared by two
//! triangles, and the teapot, whose body, lid, handle and spout are welded patch sets) are
//! placed at the origin and far from it, where f32 spacing is coarse (Embree's own
//! `watertight_triangles` test puts its sphere at (148376, 1234, −223423)). Rays start outside
//! and are aimed at a point on an interior edge (two rays in three; uniform along the edge) or
//! exactly at an interior vertex (one in three),
//! coming in through the front of every triangle around it (|cos| ≥ 1/4 to each).
//!
//! Each ray is a segment: `origin + t · dir` passes through the aimed point (exact, in f64) at
//! `t = 1` to within the rounding of the direction (see [`segment_through`]) and ends at
//! `t_max = 1.25`, well before the far side of the mesh, so a far-side hit cannot
//! hide a crack at the near side. A ray is kept only when a double-precision test confirms it
//! crosses one of the triangles around the aimed point inside the segment; every kept ray
//! therefore hits in exact arithmetic, and a miss is a crack. The miss rate per structure is
//! printed next to Embree's bar for robust mode, 2e-5.

use crate::env::Environment;
use crate::measure::{Answers, trace_pass};
use crate::registry::{self, BuildContext, StructureEntry};
use crate::report::write_json_atomic;
use crate::run::{Workers, catch_panic};
use crate::verify::brute_force_sample;
use anyhow::{Context, Result, ensure};
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::{DVec3, Ray, TriangleMesh, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Embree's pass mark for `watertight_*` in robust mode (tutorials/verify/verify.cpp).
pub const EMBREE_ROBUST_BAR: f64 = 2e-5;

/// Embree's `watertight_triangles` sphere position.
pub const EMBREE_POSITION: [f64; 3] = [148_376.0, 1_234.0, -223_423.0];

/// Minimum |cos| between a ray and every triangle around its aimed point: steep enough that the
/// crossing is not a graze, loose enough to cover many directions.
const MIN_COS: f64 = 0.25;

/// The segment ends this far past the aimed point, in units of its distance from the origin.
const T_MAX: f32 = 1.25;

/// Stream tag of the ray generator (ASCII, as in `raybench_scenes`' streams).
const WATERTIGHT_STREAM: u64 = u64::from_be_bytes(*b"wt-rays_");

/// One mesh at one place.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Case {
    pub name: String,
    /// The generator spec.
    pub spec: String,
    /// Added to every vertex in f64, then rounded to f32 once.
    pub shift: [f64; 3],
}

/// The default cases: Embree's radius-2 sphere and the teapot, at the origin, at 1e4 per axis,
/// and (the sphere) at Embree's own far position.
pub fn default_cases() -> Vec<Case> {
    let case = |name: &str, spec: &str, shift: [f64; 3]| Case {
        name: name.to_string(),
        spec: spec.to_string(),
        shift,
    };
    let sphere = "offset:triangles=20000,radius=2,offset=0";
    let teapot = "teapot:triangles=6000";
    vec![
        case("sphere@0", sphere, [0.0; 3]),
        case("sphere@1e4", sphere, [1e4; 3]),
        case("sphere@embree", sphere, EMBREE_POSITION),
        case("teapot@0", teapot, [0.0; 3]),
        case("teapot@1e4", teapot, [1e4; 3]),
    ]
}

#[derive(Clone, Debug)]
pub struct WatertightOptions {
    pub cases: Vec<Case>,
    pub structures: Vec<String>,
    /// Rays generated per case (some may be dropped, see [`CaseRecord::dropped`]).
    pub rays: usize,
    pub seed: u64,
    pub threads: usize,
    pub brute_force_budget: u64,
}

/// `watertight.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WatertightReport {
    pub tool_version: String,
    pub environment: Environment,
    pub seed: u64,
    pub embree_robust_bar: f64,
    pub cases: Vec<CaseRecord>,
    pub results: Vec<MissRate>,
    /// Per structure over every case.
    pub totals: Vec<MissRate>,
    pub errors: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CaseRecord {
    pub case: Case,
    pub triangles: usize,
    pub edge_rays: usize,
    pub vertex_rays: usize,
    /// Generated rays the f64 test did not confirm as crossings (left out of every rate).
    pub dropped: usize,
}

/// Rays traced and missed, and how many of each were aimed at a vertex (the rest at edges).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    pub rays: usize,
    pub misses: usize,
    pub vertex_rays: usize,
    pub vertex_misses: usize,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, o: Tally) {
        self.rays += o.rays;
        self.misses += o.misses;
        self.vertex_rays += o.vertex_rays;
        self.vertex_misses += o.vertex_misses;
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MissRate {
    pub case: String,
    pub structure: String,
    pub rays: usize,
    pub misses: usize,
    /// Of `rays` and `misses`, those aimed at vertices (the rest were aimed at edges).
    pub vertex_rays: usize,
    pub vertex_misses: usize,
    pub miss_rate: f64,
    /// 95 % upper bound: 3/n with no miss (rule of three), else the observed rate.
    pub upper95: f64,
}

impl MissRate {
    fn new(case: &str, structure: &str, t: Tally) -> MissRate {
        let n = t.rays.max(1) as f64;
        let rate = t.misses as f64 / n;
        MissRate {
            case: case.to_string(),
            structure: structure.to_string(),
            rays: t.rays,
            misses: t.misses,
            vertex_rays: t.vertex_rays,
            vertex_misses: t.vertex_misses,
            miss_rate: rate,
            upper95: if t.misses == 0 {
                (3.0 / n).min(1.0)
            } else {
                rate
            },
        }
    }

    /// Against Embree's bar: within it, over it, or too few rays to tell.
    pub fn judgement(&self) -> &'static str {
        if self.miss_rate > EMBREE_ROBUST_BAR {
            "over the bar"
        } else if self.upper95 > EMBREE_ROBUST_BAR {
            "0 misses, too few rays to show <= 2e-5"
        } else {
            "within the bar"
        }
    }
}

impl WatertightReport {
    pub fn write_atomic(&self, dir: &Path) -> Result<PathBuf> {
        write_json_atomic(dir, "watertight.json", self)
    }
}

/// Rays aimed at a mesh's edges and vertices, every one confirmed in f64 to cross it.
#[derive(Clone, Debug, Default)]
pub struct AimedRays {
    pub rays: Vec<Ray>,
    /// Per ray: aimed at a vertex (else at a point on an edge).
    pub at_vertex: Vec<bool>,
    pub dropped: usize,
}

impl AimedRays {
    pub fn vertex_rays(&self) -> usize {
        self.at_vertex.iter().filter(|&&v| v).count()
    }

    pub fn edge_rays(&self) -> usize {
        self.rays.len() - self.vertex_rays()
    }
}

/// Interior edges and vertices of a mesh, with the triangles around each.
struct Topology {
    /// (vertex a, vertex b, the two triangles sharing the edge)
    edges: Vec<(u32, u32, [u32; 2])>,
    /// (vertex, every triangle around it), for vertices whose every edge is interior.
    vertices: Vec<(u32, Vec<u32>)>,
}

impl Topology {
    fn of(mesh: &TriangleMesh) -> Topology {
        let mut by_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut around: HashMap<u32, Vec<u32>> = HashMap::new();
        for (prim, t) in mesh.indices().iter().enumerate() {
            if mesh.triangle(prim).area() == 0.0 {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(prim as u32);
                around.entry(t[k]).or_default().push(prim as u32);
            }
        }
        let interior = |a: u32, b: u32| {
            by_edge
                .get(&(a.min(b), a.max(b)))
                .is_some_and(|p| p.len() == 2)
        };
        let mut edges: Vec<(u32, u32, [u32; 2])> = by_edge
            .iter()
            .filter(|(_, p)| p.len() == 2)
            .map(|(&(a, b), p)| (a, b, [p[0], p[1]]))
            .collect();
        edges.sort_unstable();
        let mut vertices: Vec<(u32, Vec<u32>)> = around
            .into_iter()
            .filter(|(v, prims)| {
                prims.iter().all(|&p| {
                    let t = mesh.indices()[p as usize];
                    t.iter().all(|&w| w == *v || interior(*v, w))
                })
            })
            .collect();
        vertices.sort_unstable();
        Topology { edges, vertices }
    }
}

fn unit_f64(rng: &mut Pcg64Mcg) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

fn below(rng: &mut Pcg64Mcg, n: usize) -> usize {
    ((unit_f64(rng) * n as f64) as usize).min(n - 1)
}

fn unit_vector(rng: &mut Pcg64Mcg) -> DVec3 {
    let z = 1.0 - 2.0 * unit_f64(rng);
    let phi = std::f64::consts::TAU * unit_f64(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn unit_normal(mesh: &TriangleMesh, prim: u32) -> DVec3 {
    let t = mesh.triangle(prim as usize);
    let [a, b, c] = [t.v0, t.v1, t.v2].map(Vec3::as_dvec3);
    (b - a).cross(c - a).normalize()
}

/// A direction into the front of every triangle in `prims` (|cos| ≥ [`MIN_COS`] to each):
/// against their mean normal, tilted at random; `None` if no try qualifies.
fn inward_direction(mesh: &TriangleMesh, prims: &[u32], rng: &mut Pcg64Mcg) -> Option<DVec3> {
    let normals: Vec<DVec3> = prims.iter().map(|&p| unit_normal(mesh, p)).collect();
    let mean = normals.iter().copied().sum::<DVec3>().normalize_or_zero();
    let qualifies = |d: DVec3| normals.iter().all(|n| n.dot(d) <= -MIN_COS);
    (0..8)
        .map(|_| (-mean + unit_vector(rng) * 0.6).normalize_or_zero())
        .chain([-mean])
        .find(|&d| d != DVec3::ZERO && qualifies(d))
}

/// The segment from outside through `target` (reached at t = 1), `length` long before it.
/// The origin is rounded to f32 first and the direction is then the f64 difference rounded
/// once, so the ray passes within about one f32 ulp *of the direction* of the exact target,
/// however far from the origin the mesh is (rounding the target itself to f32 would move it
/// by an ulp of its coordinates: at 1e5, more than a thin triangle is wide).
fn segment_through(target: DVec3, dir: DVec3, length: f64) -> Ray {
    let origin = (target - dir * length).as_vec3();
    Ray::new(origin, (target - origin.as_dvec3()).as_vec3(), 0.0, T_MAX)
}

/// True when an f64 test finds the ray crossing one of `prims` inside its segment.
fn confirmed(mesh: &TriangleMesh, prims: &[u32], ray: &Ray) -> bool {
    prims.iter().any(|&p| {
        mesh.triangle(p as usize)
            .plane_crossing_f64(ray)
            .is_some_and(|x| x.edge_distance >= 0.0 && x.t > 0.0 && x.t <= T_MAX as f64)
    })
}

/// `n` rays aimed at interior edges (two in three) and vertices (one in three) from outside;
/// ray `i` draws from its own seeded stream, so the set does not depend on the thread count.
pub fn aimed_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> AimedRays {
    let topo = Topology::of(mesh);
    let length = 0.25 * mesh.bounds().extent().as_dvec3().length();
    let mut out = AimedRays::default();
    if topo.edges.is_empty() || length == 0.0 {
        out.dropped = n;
        return out;
    }
    for i in 0..n {
        let mut rng = Pcg64Mcg::seed_from_u64(
            seed ^ WATERTIGHT_STREAM ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let at_vertex = i % 3 == 2 && !topo.vertices.is_empty();
        let position = |v: u32| mesh.positions()[v as usize].as_dvec3();
        let (target, prims): (DVec3, &[u32]) = if at_vertex {
            let (v, prims) = &topo.vertices[below(&mut rng, topo.vertices.len())];
            (position(*v), prims)
        } else {
            let (a, b, prims) = &topo.edges[below(&mut rng, topo.edges.len())];
            let (a, b) = (position(*a), position(*b));
            (a + (b - a) * unit_f64(&mut rng), &prims[..])
        };
        let ray =
            inward_direction(mesh, prims, &mut rng).map(|d| segment_through(target, d, length));
        match ray {
            Some(r) if r.check().is_ok() && confirmed(mesh, prims, &r) => {
                out.rays.push(r);
                out.at_vertex.push(at_vertex);
            }
            _ => out.dropped += 1,
        }
    }
    out
}

/// The case's mesh: the generator's, shifted in f64 and rounded to f32 once.
pub fn case_mesh(case: &Case, seed: u64) -> Result<Arc<TriangleMesh>> {
    let scene = raybench_scenes::generate(&case.spec, seed)
        .with_context(|| format!("case {}", case.name))?;
    if case.shift == [0.0; 3] {
        return Ok(scene.mesh);
    }
    let shift = DVec3::from_array(case.shift);
    let positions = scene
        .mesh
        .positions()
        .iter()
        .map(|p| (p.as_dvec3() + shift).as_vec3())
        .collect();
    let (mesh, _) = TriangleMesh::new(positions, scene.mesh.indices().to_vec())
        .map_err(|e| anyhow::anyhow!("case {}: {e}", case.name))?;
    Ok(Arc::new(mesh))
}

/// Misses of one structure on one case's rays (brute force on its budgeted subsample).
fn count_misses(
    entry: &StructureEntry,
    mesh: &Arc<TriangleMesh>,
    aimed: &AimedRays,
    opts: &WatertightOptions,
) -> Result<Tally> {
    let ctx = BuildContext {
        threads: opts.threads,
    };
    let accel = entry.build(mesh.clone(), &ctx)?.accel;
    let n = aimed.rays.len();
    let indices: Vec<usize> = if entry.is_exhaustive() {
        brute_force_sample(n, mesh.len(), opts.brute_force_budget)
    } else {
        (0..n).collect()
    };
    let rays: Vec<Ray> = indices.iter().map(|&i| aimed.rays[i]).collect();
    let prepared = accel
        .prepare_rays(&rays)
        .map_err(|e| anyhow::anyhow!("{} rejected a ray: {e}", entry.name))?;
    let mut answers = Answers::new(false, rays.len());
    trace_pass(accel.as_ref(), &rays, &prepared, opts.threads, &mut answers);
    let hits = answers.closest().expect("closest-hit answers");
    let mut tally = Tally::default();
    for (&i, hit) in indices.iter().zip(hits) {
        let (miss, vertex) = (hit.is_none(), aimed.at_vertex[i]);
        tally += Tally {
            rays: 1,
            misses: usize::from(miss),
            vertex_rays: usize::from(vertex),
            vertex_misses: usize::from(miss && vertex),
        };
    }
    Ok(tally)
}

/// Runs every case through every structure.
pub fn watertight(opts: &WatertightOptions) -> Result<WatertightReport> {
    ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    let entries = registry::select(&opts.structures)?;
    let workers = Workers::start(opts.threads, false)?;
    let mut report = WatertightReport {
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        environment: workers.environment.clone(),
        seed: opts.seed,
        embree_robust_bar: EMBREE_ROBUST_BAR,
        cases: Vec::new(),
        results: Vec::new(),
        totals: Vec::new(),
        errors: Vec::new(),
    };
    workers.pool.install(|| {
        for case in &opts.cases {
            if let Err(e) = run_case(case, &entries, opts, &mut report) {
                report.errors.push(format!("{}: {e:#}", case.name));
            }
        }
    });
    report.totals = entries
        .iter()
        .map(|e| {
            let mut all = Tally::default();
            for r in report.results.iter().filter(|r| r.structure == e.name) {
                all += Tally {
                    rays: r.rays,
                    misses: r.misses,
                    vertex_rays: r.vertex_rays,
                    vertex_misses: r.vertex_misses,
                };
            }
            MissRate::new("all", e.name, all)
        })
        .filter(|t| t.rays > 0)
        .collect();
    Ok(report)
}

fn run_case(
    case: &Case,
    entries: &[StructureEntry],
    opts: &WatertightOptions,
    report: &mut WatertightReport,
) -> Result<()> {
    let mesh = case_mesh(case, opts.seed)?;
    let aimed = aimed_rays(&mesh, opts.rays, opts.seed);
    report.cases.push(CaseRecord {
        case: case.clone(),
        triangles: mesh.len(),
        edge_rays: aimed.edge_rays(),
        vertex_rays: aimed.vertex_rays(),
        dropped: aimed.dropped,
    });
    for entry in entries {
        match catch_panic(|| count_misses(entry, &mesh, &aimed, opts)) {
            Ok(tally) => report
                .results
                .push(MissRate::new(&case.name, entry.name, tally)),
            Err(e) => report
                .errors
                .push(format!("{} on {}: {e:#}", entry.name, case.name)),
        }
    }
    Ok(())
}

/// The table `raybench watertight` prints.
pub fn watertight_table(report: &WatertightReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Rays from outside aimed exactly at interior edges (2 in 3) and vertices (1 in 3), each a \
         segment ending a quarter past the aimed point and confirmed in f64 to cross the mesh: a \
         miss is a crack."
    );
    let _ = writeln!(
        out,
        "Embree's own bar for robust mode is a miss rate <= {EMBREE_ROBUST_BAR:.0e} for random \
         rays from inside its sphere (watertight_triangles); rays aimed at edges are far harder.\n"
    );
    let _ = writeln!(
        out,
        "{:<16} {:<42} {:>9} {:>9} {:>9} {:>8}",
        "case", "mesh", "triangles", "edge", "vertex", "dropped"
    );
    for c in &report.cases {
        let _ = writeln!(
            out,
            "{:<16} {:<42} {:>9} {:>9} {:>9} {:>8}",
            c.case.name,
            format!("{} + {:?}", c.case.spec, c.case.shift),
            c.triangles,
            c.edge_rays,
            c.vertex_rays,
            c.dropped
        );
    }
    let _ = write!(out, "\n{:<22}", "misses / rays");
    for c in &report.cases {
        let _ = write!(out, " {:>15}", c.case.name);
    }
    let _ = writeln!(
        out,
        " {:>15} {:>10} {:>9}  vs 2e-5",
        "at vertices", "miss rate", "upper95"
    );
    for t in &report.totals {
        let _ = write!(out, "{:<22}", t.structure);
        for c in &report.cases {
            let cell = report
                .results
                .iter()
                .find(|r| r.structure == t.structure && r.case == c.case.name)
                .map_or("-".to_string(), |r| format!("{}/{}", r.misses, r.rays));
            let _ = write!(out, " {cell:>15}");
        }
        let _ = writeln!(
            out,
            " {:>15} {:>10.1e} {:>9.1e}  {}",
            format!("{}/{}", t.vertex_misses, t.vertex_rays),
            t.miss_rate,
            t.upper95,
            t.judgement()
        );
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(shift: [f64; 3]) -> Arc<TriangleMesh> {
        let case = Case {
            name: "t".into(),
            spec: "offset:triangles=500,radius=2,offset=0".into(),
            shift,
        };
        case_mesh(&case, 1).unwrap()
    }

    #[test]
    fn every_sphere_edge_and_vertex_is_interior() {
        let mesh = sphere([0.0; 3]);
        let topo = Topology::of(&mesh);
        // A closed mesh: edges = 3/2 · triangles, and Euler: V - E + F = 2.
        assert_eq!(topo.edges.len() * 2, mesh.len() * 3);
        assert_eq!(topo.vertices.len() + mesh.len() - topo.edges.len(), 2);
    }

    #[test]
    fn aimed_rays_pass_through_their_target_and_are_confirmed() {
        let mesh = sphere(EMBREE_POSITION);
        let a = aimed_rays(&mesh, 300, 5);
        assert_eq!(a.rays.len() + a.dropped, 300);
        assert!(a.rays.len() > 250, "{a:?}");
        assert!(
            a.vertex_rays() > 60 && a.edge_rays() > 150,
            "{} {}",
            a.vertex_rays(),
            a.edge_rays()
        );
        for r in &a.rays {
            // Origin outside the radius-2 sphere, the segment stopping well short of its far side.
            let centre = DVec3::from_array(EMBREE_POSITION);
            let d = (r.origin().as_dvec3() - centre).length();
            assert!(d > 2.0, "origin {d} from the centre");
            assert_eq!(r.t_max(), T_MAX);
        }
        // Seeded: the same rays again.
        assert_eq!(aimed_rays(&mesh, 300, 5).rays, a.rays);
        assert_ne!(aimed_rays(&mesh, 300, 6).rays, a.rays);
    }

    #[test]
    fn rays_aimed_where_the_surface_was_removed_count_as_misses() {
        let mesh = sphere([0.0; 3]);
        let aimed = aimed_rays(&mesh, 600, 3);
        let mut idx = mesh.indices().to_vec();
        idx.truncate(idx.len() / 2); // half a sphere: rays at the removed half miss
        let (half, _) = TriangleMesh::new(mesh.positions().to_vec(), idx).unwrap();
        let brute = registry::find("bruteforce-watertight").unwrap();
        let opts = WatertightOptions {
            cases: vec![],
            structures: vec![],
            rays: 0,
            seed: 1,
            threads: 1,
            brute_force_budget: u64::MAX,
        };
        let half = count_misses(&brute, &Arc::new(half), &aimed, &opts).unwrap();
        let n = aimed.rays.len();
        assert_eq!(half.rays, n);
        assert_eq!(half.vertex_rays, aimed.vertex_rays());
        let misses = half.misses;
        assert!(misses > n / 4 && misses < 3 * n / 4, "{misses} of {n}");
        assert!(
            half.vertex_misses > 0 && half.vertex_misses < misses,
            "{half:?}"
        );
        let whole = count_misses(&brute, &mesh, &aimed, &opts).unwrap();
        assert_eq!(
            whole.misses, 0,
            "the watertight test finds no crack in the whole sphere"
        );
    }
}
