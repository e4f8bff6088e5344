//! Timing: builds, trace passes and closest-point passes, medians of repeated runs after a
//! warm-up.
//!
//! Nothing here counts or checks inside a timed region: the trace passes call the structures'
//! prepared batch path (rays already in each structure's layout), the point passes their batch
//! closest-point path ([`Accel::closest_points`]), both over the same rayon chunks, and the
//! counting passes are separate, untimed, single-threaded walks.

use crate::registry::{BuildContext, Built, StructureEntry};
use crate::report::run::{Throughput, Timing};
use raybench_accel::{Accel, BuildError, Counters, Hit, PointHit, PreparedRays};
use raybench_geom::{Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Queries per rayon task when tracing with several threads: large enough that scheduling
/// costs are noise (~1 µs per task vs ≥ 25 µs of tracing), small enough to balance 2 cores.
const CHUNK: usize = 256;

/// A warm-up pass longer than this is measured once more, not `trace_runs` times: a pass that
/// long already averages over thousands of scheduler ticks, and repeating it (brute force, or
/// the BVHs and Embree on `hair` at under 0.1 Mrays/s) took a third of the default suite's time
/// for precision no ratio needed. The report records the runs.
const LONG_PASS: Duration = Duration::from_secs(2);

/// Median, minimum and maximum of samples (the median of an even count is the mean of the
/// middle two).
pub fn median_min_max(samples: &[f64]) -> (f64, f64, f64) {
    assert!(!samples.is_empty(), "no samples");
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let mid = s.len() / 2;
    let median = if s.len().is_multiple_of(2) {
        (s[mid - 1] + s[mid]) / 2.0
    } else {
        s[mid]
    };
    (median, s[0], s[s.len() - 1])
}

/// One warm-up build (which also creates shared state such as Embree's device), then `runs`
/// timed builds. Returns the last build. Each build's predecessor is dropped outside the
/// timed window.
pub fn time_builds(
    entry: &StructureEntry,
    mesh: &Arc<TriangleMesh>,
    ctx: &BuildContext,
    runs: usize,
) -> Result<(Built, Timing), BuildError> {
    let mut built = entry.build(mesh.clone(), ctx)?;
    let mut ms = Vec::with_capacity(runs);
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        let next = entry.build(mesh.clone(), ctx)?;
        ms.push(start.elapsed().as_secs_f64() * 1e3);
        built = next;
    }
    let (median_ms, min_ms, max_ms) = median_min_max(&ms);
    Ok((
        built,
        Timing {
            median_ms,
            min_ms,
            max_ms,
            runs: ms.len(),
        },
    ))
}

/// Answers of one structure to one workload.
#[derive(Clone, Debug, PartialEq)]
pub enum Answers {
    Closest(Vec<Option<Hit>>),
    Any(Vec<bool>),
}

impl Answers {
    pub fn new(any_hit: bool, n: usize) -> Answers {
        if any_hit {
            Answers::Any(vec![false; n])
        } else {
            Answers::Closest(vec![None; n])
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Answers::Closest(h) => h.len(),
            Answers::Any(o) => o.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The answers at `indices` (a subsample), in that order.
    pub fn gather(&self, indices: &[usize]) -> Answers {
        match self {
            Answers::Closest(h) => Answers::Closest(indices.iter().map(|&i| h[i]).collect()),
            Answers::Any(o) => Answers::Any(indices.iter().map(|&i| o[i]).collect()),
        }
    }

    pub fn closest(&self) -> Option<&[Option<Hit>]> {
        match self {
            Answers::Closest(h) => Some(h),
            Answers::Any(_) => None,
        }
    }
}

/// One pass over every ray through the structure's prepared batch path. Must run inside the
/// run's thread pool; with one thread it is a plain loop on that worker.
pub fn trace_pass(
    accel: &dyn Accel,
    rays: &[Ray],
    prepared: &PreparedRays,
    threads: usize,
    out: &mut Answers,
) -> Duration {
    let start = Instant::now();
    match out {
        Answers::Closest(hits) if threads <= 1 => accel.intersect_prepared(rays, prepared, 0, hits),
        Answers::Any(occ) if threads <= 1 => accel.occluded_prepared(rays, prepared, 0, occ),
        Answers::Closest(hits) => hits
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(i, chunk)| accel.intersect_prepared(rays, prepared, i * CHUNK, chunk)),
        Answers::Any(occ) => occ
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(i, chunk)| accel.occluded_prepared(rays, prepared, i * CHUNK, chunk)),
    }
    start.elapsed()
}

/// A warm-up pass (whose answers are returned to be checked), then timed passes.
pub fn time_traces(
    accel: &dyn Accel,
    rays: &[Ray],
    prepared: &PreparedRays,
    any_hit: bool,
    threads: usize,
    runs: usize,
) -> (Answers, Throughput) {
    let mut answers = Answers::new(any_hit, rays.len());
    let warm = trace_pass(accel, rays, prepared, threads, &mut answers);
    let mut scratch = Answers::new(any_hit, rays.len());
    let throughput = time_passes(rays.len(), warm, runs, || {
        trace_pass(accel, rays, prepared, threads, &mut scratch)
    });
    (answers, throughput)
}

/// Millions of queries per second over `runs` timed passes (one when the warm-up took longer
/// than [`LONG_PASS`]): median, minimum and maximum.
fn time_passes(
    queries: usize,
    warm_up: Duration,
    runs: usize,
    mut pass: impl FnMut() -> Duration,
) -> Throughput {
    let runs = if warm_up > LONG_PASS { 1 } else { runs.max(1) };
    let per_pass: Vec<f64> = (0..runs)
        .map(|_| queries as f64 / pass().as_secs_f64().max(1e-9) / 1e6)
        .collect();
    let (median, min, max) = median_min_max(&per_pass);
    Throughput {
        median,
        min,
        max,
        runs,
    }
}

/// One closest-point pass over every point through the structure's batch path, like
/// [`trace_pass`]: a plain loop with one thread, rayon chunks of `CHUNK` points otherwise.
pub fn point_pass(
    accel: &dyn Accel,
    points: &[Vec3],
    radius: f32,
    threads: usize,
    out: &mut [Option<PointHit>],
) -> Duration {
    let start = Instant::now();
    if threads <= 1 {
        accel.closest_points(points, radius, 0, out);
    } else {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(i, chunk)| accel.closest_points(points, radius, i * CHUNK, chunk));
    }
    start.elapsed()
}

/// A warm-up closest-point pass (whose answers are returned to be checked), then timed
/// passes: the method of [`time_traces`]. Throughput is in millions of queries per second.
pub fn time_point_queries(
    accel: &dyn Accel,
    points: &[Vec3],
    radius: f32,
    threads: usize,
    runs: usize,
) -> (Vec<Option<PointHit>>, Throughput) {
    let mut answers = vec![None; points.len()];
    let warm = point_pass(accel, points, radius, threads, &mut answers);
    let mut scratch = vec![None; points.len()];
    let throughput = time_passes(points.len(), warm, runs, || {
        point_pass(accel, points, radius, threads, &mut scratch)
    });
    (answers, throughput)
}

/// The untimed counted closest-point walk over every point, single-threaded so the counters
/// are exact (`prim_tests` counts point–triangle distance tests).
pub fn count_point_pass(
    accel: &dyn Accel,
    points: &[Vec3],
    radius: f32,
) -> (Vec<Option<PointHit>>, Counters) {
    let mut c = Counters::default();
    let answers = points
        .iter()
        .map(|&p| accel.closest_point_counted(p, radius, &mut c))
        .collect();
    (answers, c)
}

/// The counted walk over every ray, single-threaded (counters are exact, not timed). Also
/// returns each ray's work (interior nodes + leaves + triangle tests + cells), for the
/// traversal-cost images.
pub fn count_pass(accel: &dyn Accel, rays: &[Ray], any_hit: bool) -> (Answers, Counters, Vec<u32>) {
    let mut c = Counters::default();
    let mut per_ray = Vec::with_capacity(rays.len());
    let work = |c: &Counters| c.nodes + c.leaves + c.prim_tests + c.cells;
    let mut before = 0;
    let mut note = |c: &Counters| {
        let now = work(c);
        per_ray.push((now - before).min(u32::MAX as u64) as u32);
        before = now;
    };
    let answers = if any_hit {
        Answers::Any(
            rays.iter()
                .map(|r| {
                    let a = accel.occluded_counted(r, &mut c);
                    note(&c);
                    a
                })
                .collect(),
        )
    } else {
        Answers::Closest(
            rays.iter()
                .map(|r| {
                    let h = accel.intersect_counted(r, &mut c);
                    note(&c);
                    h
                })
                .collect(),
        )
    };
    (answers, c, per_ray)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median_min_max(&[3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(median_min_max(&[4.0, 1.0, 2.0, 3.0]), (2.5, 1.0, 4.0));
    }
}
