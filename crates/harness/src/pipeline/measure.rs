//! Timing: one trace pass or closest-point pass, and the warm-up passes; `rounds.rs` repeats
//! them (and the builds) in interleaved rounds.
//!
//! Nothing here counts or checks inside a timed region: the trace passes call the structures'
//! prepared batch path (rays already in each structure's layout), the point passes their batch
//! closest-point path ([`Accel::closest_points`]), both over the same rayon chunks, and the
//! counting passes are separate, untimed, single-threaded walks.

use raybench_accel::{Accel, Counters, Hit, PointHit, PreparedRays};
use raybench_geom::{Ray, Vec3};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Queries per structure call when tracing with several threads: large enough that the call's
/// setup is noise, small enough to balance 2 cores. Rayon gets at most [`CHUNKS_PER_TASK`] of
/// them per task.
pub const CHUNK: usize = 256;

/// Chunks per rayon task (`with_max_len`): about 25–100 µs of tracing, ~1 µs of scheduling.
/// Left to itself, rayon cuts a batch into a few long runs of chunks up front, and a thread
/// that has finished its runs cannot take over part of another's, so a batch whose cheap rays
/// (misses around a small object) sit in one half runs partly on one thread: with rayon's own
/// cuts the teapot's primary rays traced 1.76× faster on 2 threads than on 1, with these tasks
/// 1.97× (measured: see docs/experiments.md, "rayon tasks of at most four chunks").
const CHUNKS_PER_TASK: usize = 4;

/// A warm-up pass longer than this is measured once more, not `trace_runs` times: a pass that
/// long already averages over thousands of scheduler ticks, and repeating it (brute force, or
/// the BVHs and Embree on `hair` at under 0.1 Mrays/s) took a third of the default suite's time
/// for precision no ratio needed. The report records the runs.
pub(super) const LONG_PASS: Duration = Duration::from_secs(2);

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
            .with_max_len(CHUNKS_PER_TASK)
            .enumerate()
            .for_each(|(i, chunk)| accel.intersect_prepared(rays, prepared, i * CHUNK, chunk)),
        Answers::Any(occ) => occ
            .par_chunks_mut(CHUNK)
            .with_max_len(CHUNKS_PER_TASK)
            .enumerate()
            .for_each(|(i, chunk)| accel.occluded_prepared(rays, prepared, i * CHUNK, chunk)),
    }
    start.elapsed()
}

/// The warm-up pass: its answers (checked against the reference) and how long it took (which
/// decides how many timed passes follow, see `rounds.rs`).
pub fn warm_up_trace(
    accel: &dyn Accel,
    rays: &[Ray],
    prepared: &PreparedRays,
    any_hit: bool,
    threads: usize,
) -> (Answers, Duration) {
    let mut answers = Answers::new(any_hit, rays.len());
    let took = trace_pass(accel, rays, prepared, threads, &mut answers);
    (answers, took)
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
            .with_max_len(CHUNKS_PER_TASK)
            .enumerate()
            .for_each(|(i, chunk)| accel.closest_points(points, radius, i * CHUNK, chunk));
    }
    start.elapsed()
}

/// The warm-up closest-point pass, like [`warm_up_trace`].
pub fn warm_up_points(
    accel: &dyn Accel,
    points: &[Vec3],
    radius: f32,
    threads: usize,
) -> (Vec<Option<PointHit>>, Duration) {
    let mut answers = vec![None; points.len()];
    let took = point_pass(accel, points, radius, threads, &mut answers);
    (answers, took)
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
