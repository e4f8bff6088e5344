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
//! `t = 1` to within the rounding of the direction (see `aimed::segment_through`) and ends at
//! `t_max = 1.25`, well before the far side of the mesh, so a far-side hit cannot
//! hide a crack at the near side. A ray is kept only when a double-precision test confirms it
//! crosses one of the triangles around the aimed point inside the segment; every kept ray
//! therefore hits in exact arithmetic, and a miss is a crack. The miss rate per structure is
//! printed next to Embree's bar for robust mode, 2e-5.

mod aimed;

use super::measure::{Answers, trace_pass};
use super::verify::brute_force_sample;
use super::workers::{Workers, catch_panic};
use crate::registry::{BuildContext, Registry, StructureEntry};
use crate::report::Header;
use crate::report::watertight::{
    Case, CaseRecord, EMBREE_ROBUST_BAR, MissRate, Tally, WATERTIGHT_SCHEMA_VERSION,
    WatertightReport,
};
use aimed::{AimedRays, aimed_rays};
use anyhow::{Context, Result, ensure};
use raybench_geom::{DVec3, Ray, TriangleMesh};
use std::sync::Arc;

/// Embree's `watertight_triangles` sphere position.
pub const EMBREE_POSITION: [f64; 3] = [148_376.0, 1_234.0, -223_423.0];

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
    let ctx = BuildContext::new(opts.threads);
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

/// [`watertight_with`] the built-in structures.
pub fn watertight(opts: &WatertightOptions) -> Result<WatertightReport> {
    watertight_with(&Registry::builtin(), opts)
}

/// Runs every case through every structure, looking names up in `registry`.
pub fn watertight_with(registry: &Registry, opts: &WatertightOptions) -> Result<WatertightReport> {
    ensure!(opts.rays >= 1, "--rays must be at least 1 (got 0)");
    let entries = registry.select(&opts.structures)?;
    let workers = Workers::start(opts.threads, false)?;
    let mut report = WatertightReport {
        header: Header::new(WATERTIGHT_SCHEMA_VERSION, workers.environment.clone()),
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
    fn rays_aimed_where_the_surface_was_removed_count_as_misses() {
        let mesh = sphere([0.0; 3]);
        let aimed = aimed_rays(&mesh, 600, 3);
        let mut idx = mesh.indices().to_vec();
        idx.truncate(idx.len() / 2); // half a sphere: rays at the removed half miss
        let (half, _) = TriangleMesh::new(mesh.positions().to_vec(), idx).unwrap();
        let brute = Registry::builtin().find("bruteforce-watertight").unwrap();
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
