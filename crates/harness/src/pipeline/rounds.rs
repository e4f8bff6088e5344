//! Interleaved timing. Every structure of a scene is first built, traced once and checked
//! (`run.rs`); only then is anything timed, in rounds: round `r` builds each structure once and
//! traces each of its workloads once, the structures in an order rotated by `r`. On a shared
//! machine a slow spell then lands on every structure alike instead of on whichever one was
//! being timed, and each round's ratio to the reference compares passes run moments apart.
//! Every timed pass is kept (the report's `samples`); the ratio to the reference is the median
//! of the per-round ratios, with a confidence interval ([`crate::report::interval`]).
//!
//! The price is memory: all of a scene's structures (and their prepared rays) are alive
//! together, where measuring one after the other held one at a time.
//!
//! Each timed build replaces the copy the passes trace: that copy is dropped just before the
//! clock starts. Every build then starts from the same state, the memory its own last copy
//! freed, whatever ran before it in the round. Kept beside the traced copy instead, a build's
//! time would depend on its neighbour: Embree's builds fault their memory in from the kernel,
//! and run far faster on pages their own last copy just freed than on pages another structure
//! freed, so the rotation would time them fast in some rounds and slow in others.

use super::measure::{Answers, LONG_PASS, point_pass, trace_pass};
use super::run::RunOptions;
use super::workers::catch_panic;
use super::workloads::SceneRun;
use crate::memory::gib;
use crate::registry::{BuildContext, Built, StructureEntry};
use crate::report::interval::{median_with_interval, paired_ratios};
use crate::report::run::{ResultEntry, Throughput, Timing};
use anyhow::{Result, bail};
use raybench_accel::{Accel, PointHit, PreparedRays};
use std::time::{Duration, Instant};

/// One structure of a scene, built and checked, waiting for its timed passes.
pub(super) struct Pending<'e> {
    pub entry: &'e StructureEntry,
    /// The copy every pass traces: the warm-up build, then each timed build in its place.
    /// `None` only while a timed build runs, or after one failed (which ends the structure's
    /// rounds).
    built: Option<Built>,
    /// Everything but the timings, which [`finish`](Pending::finish) fills in.
    pub result: ResultEntry,
    pub jobs: Vec<Job>,
    build_ms: Vec<f64>,
    /// How long the warm-up build took: the build's time when no timed build had room.
    warm_up_ms: f64,
    /// The memory available when a timed build was left out for want of room (no later one is
    /// tried).
    no_room: Option<u64>,
}

/// One workload of a [`Pending`] structure: what a timed pass needs, and its samples.
pub(super) struct Job {
    /// Its place in the result's `workloads`.
    result_index: usize,
    kind: JobKind,
    /// Timed passes: `trace_runs`, or one when the warm-up took longer than [`LONG_PASS`].
    runs: usize,
    /// Millions of queries per second, one per timed pass, in round order.
    samples: Vec<f64>,
}

enum JobKind {
    /// `workload` indexes the scene's ray workloads.
    Rays {
        workload: usize,
        prepared: PreparedRays,
        scratch: Answers,
    },
    /// `workload` indexes the scene's closest-point workloads.
    Points {
        workload: usize,
        scratch: Vec<Option<PointHit>>,
    },
}

impl Job {
    /// A ray workload whose warm-up pass took `warm_up`.
    pub(super) fn rays(
        result_index: usize,
        workload: usize,
        prepared: PreparedRays,
        scratch: Answers,
        warm_up: Duration,
        trace_runs: usize,
    ) -> Job {
        Job {
            result_index,
            kind: JobKind::Rays {
                workload,
                prepared,
                scratch,
            },
            runs: runs_after(warm_up, trace_runs),
            samples: Vec::new(),
        }
    }

    /// A closest-point workload whose warm-up pass took `warm_up`.
    pub(super) fn points(
        result_index: usize,
        workload: usize,
        queries: usize,
        warm_up: Duration,
        trace_runs: usize,
    ) -> Job {
        Job {
            result_index,
            kind: JobKind::Points {
                workload,
                scratch: vec![None; queries],
            },
            runs: runs_after(warm_up, trace_runs),
            samples: Vec::new(),
        }
    }
}

/// A warm-up pass longer than [`LONG_PASS`] is measured once more, not `trace_runs` times.
fn runs_after(warm_up: Duration, trace_runs: usize) -> usize {
    if warm_up > LONG_PASS {
        1
    } else {
        trace_runs.max(1)
    }
}

impl<'e> Pending<'e> {
    pub(super) fn new(
        entry: &'e StructureEntry,
        built: Built,
        warm_up_ms: f64,
        result: ResultEntry,
    ) -> Self {
        Pending {
            entry,
            built: Some(built),
            result,
            jobs: Vec::new(),
            build_ms: Vec::new(),
            warm_up_ms,
            no_room: None,
        }
    }

    /// The warm-up build, before the rounds begin.
    pub(super) fn warm_up(&self) -> Option<&dyn Accel> {
        self.built.as_ref().map(|b| b.accel.as_ref())
    }

    /// Round `r`: one timed build while `r < build_runs` and there is room for it
    /// ([`short_of_room`]), which replaces the copy the passes trace (dropped outside the
    /// timed window, just before it), and one timed pass of each workload that still has runs
    /// left.
    /// An `extra` round (past the fixed ones, see [`time_in_rounds`]) builds nothing and
    /// traces every workload that is not timed once.
    fn round(&mut self, r: usize, extra: bool, sr: &SceneRun, opts: &RunOptions) -> Result<()> {
        let mesh = &sr.scene.scene.mesh;
        let builds = !extra && r < opts.build_runs.max(1) && self.no_room.is_none();
        if builds {
            self.no_room = short_of_room(self.result.memory_bytes, crate::memory::available());
        }
        if builds && self.no_room.is_none() {
            let ctx = BuildContext::new(opts.threads);
            drop(self.built.take());
            let start = Instant::now();
            let next = self.entry.build(mesh.clone(), &ctx)?;
            self.build_ms.push(start.elapsed().as_secs_f64() * 1e3);
            self.built = Some(next);
        }
        // The checks ran on the warm-up build; a timed build stands for it, since each of our
        // builders gives the same structure on every build (the tests assert it) and Embree's
        // is the same scene built with the same settings.
        let Some(built) = &self.built else {
            bail!("no structure to trace: its timed build failed");
        };
        let accel = built.accel.as_ref();
        let runs_now = |j: &Job| if extra { j.runs > 1 } else { r < j.runs };
        for job in self.jobs.iter_mut().filter(|j| runs_now(j)) {
            let (queries, took) = match &mut job.kind {
                JobKind::Rays {
                    workload,
                    prepared,
                    scratch,
                } => {
                    let rays = &sr.workloads[*workload].rays;
                    let took = trace_pass(accel, rays, prepared, opts.threads, scratch);
                    (rays.len(), took)
                }
                JobKind::Points { workload, scratch } => {
                    let pw = &sr.point_workloads[*workload];
                    let took = point_pass(accel, &pw.points, pw.radius, opts.threads, scratch);
                    (pw.points.len(), took)
                }
            };
            job.samples
                .push(queries as f64 / took.as_secs_f64().max(1e-9) / 1e6);
        }
        Ok(())
    }

    /// The result with its timings from the samples, and a note when builds were left out.
    fn finish(mut self, build_runs: usize) -> Timed {
        let note = self.no_room.map(|available| {
            let timed = match self.build_ms.len() {
                0 => "its build time is the warm-up build's".to_string(),
                n => format!("{n} of {build_runs} builds timed"),
            };
            format!(
                "{} on {}: {timed}: timing another needs room for a new copy of its {} and the \
                 build's working memory, and {} were available",
                self.entry.name,
                self.result.scene,
                gib(self.result.memory_bytes as f64),
                gib(available as f64)
            )
        });
        if self.build_ms.is_empty() {
            self.build_ms.push(self.warm_up_ms);
        }
        self.result.build = Timing::from_samples(self.build_ms);
        for job in self.jobs {
            self.result.workloads[job.result_index].mqueries_per_s =
                Throughput::from_samples(job.samples);
        }
        (self.result, note)
    }
}

/// A timed build needs room for its new copy and for its working memory, taken as the copy's
/// size again. The copy it replaces is dropped first, but an allocator may keep what it frees,
/// so that copy is not counted as room. Without that room (`available` bytes, when known) the
/// build is left out and the passes go on tracing the copy they have, instead of the kernel
/// killing the run and losing every scene's results: returns the memory available then.
fn short_of_room(memory_bytes: u64, available: Option<u64>) -> Option<u64> {
    available.filter(|&a| memory_bytes.saturating_mul(2) > a)
}

/// How many rounds a run's settings take: enough for every timed build and pass.
pub(super) fn rounds(opts: &RunOptions) -> usize {
    opts.build_runs.max(opts.trace_runs).max(1)
}

/// The precision extra rounds aim for: every ratio's interval within ±2 % of it.
const TARGET_HALF_WIDTH: f64 = 0.02;

/// A structure's result with its timings, and a note when builds were left out.
pub(super) type Timed = (ResultEntry, Option<String>);

/// The most rounds a scene takes, fixed and extra together.
const MAX_ROUNDS: usize = 1000;

/// Times every pending structure in interleaved rounds and returns, in the order given, each
/// structure's name with its result (and a note when builds were left out for want of memory)
/// or what went wrong (a failed build or a panic in any round takes that structure out of the
/// later rounds; the others go on). `None` when a graceful stop is asked for
/// ([`crate::interrupt`]): checked before each structure's turn.
///
/// With a time budget (`opts.time_budget`, seconds per structure and scene), the fixed rounds
/// are followed by extra ones, traces only, as criterion and hyperfine adapt their sample
/// counts: a structure takes part while one of its ratios to the reference has an interval
/// wider than ±[`TARGET_HALF_WIDTH`] and its timed passes have used less than the budget; the
/// reference takes part while anyone does, so every structure's rounds pair with its rounds.
pub(super) fn time_in_rounds(
    pending: Vec<Pending<'_>>,
    sr: &SceneRun,
    opts: &RunOptions,
) -> Option<Vec<(&'static str, Result<Timed>)>> {
    let n = pending.len();
    let mut failed: Vec<Option<anyhow::Error>> = (0..n).map(|_| None).collect();
    let mut spent = vec![Duration::ZERO; n];
    let mut pending = pending;
    let fixed = rounds(opts);
    let reference = pending.iter().position(|p| p.entry.name == opts.reference);
    for r in 0..MAX_ROUNDS {
        let extra = r >= fixed;
        let active: Vec<bool> = if extra {
            wanting_more(&pending, reference, &spent, opts)
        } else {
            vec![true; n]
        };
        if !active.iter().any(|&a| a) {
            break;
        }
        for k in 0..n {
            let i = (k + r) % n;
            if failed[i].is_some() || !active[i] {
                continue;
            }
            if crate::interrupt::requested() {
                return None;
            }
            let p = &mut pending[i];
            let start = Instant::now();
            if let Err(e) = catch_panic(|| p.round(r, extra, sr, opts)) {
                failed[i] = Some(e.context(format!("timing round {}", r + 1)));
            }
            spent[i] += start.elapsed();
        }
    }
    let results = pending
        .into_iter()
        .zip(failed)
        .map(|(p, f)| match f {
            None => (p.entry.name, Ok(p.finish(opts.build_runs.max(1)))),
            Some(e) => (p.entry.name, Err(e)),
        })
        .collect();
    Some(results)
}

/// Which structures take part in the next extra round (see [`time_in_rounds`]).
fn wanting_more(
    pending: &[Pending<'_>],
    reference: Option<usize>,
    spent: &[Duration],
    opts: &RunOptions,
) -> Vec<bool> {
    let n = pending.len();
    let (Some(budget), Some(ref_i)) = (opts.time_budget, reference) else {
        return vec![false; n];
    };
    let base = &pending[ref_i];
    let mut active: Vec<bool> = (0..n)
        .map(|i| {
            i != ref_i
                && spent[i] < budget
                && pending[i].jobs.iter().filter(|j| j.runs > 1).any(|j| {
                    let Some(b) = base.jobs.iter().find(|b| b.kind.same_workload(&j.kind)) else {
                        return false;
                    };
                    let ratios = paired_ratios(&j.samples, &b.samples);
                    match median_with_interval(&ratios) {
                        Some((m, Some(i))) => i.relative_half_width(m) > TARGET_HALF_WIDTH,
                        _ => false,
                    }
                })
        })
        .collect();
    active[ref_i] = active.iter().any(|&a| a);
    active
}

impl JobKind {
    fn same_workload(&self, o: &JobKind) -> bool {
        match (self, o) {
            (JobKind::Rays { workload: a, .. }, JobKind::Rays { workload: b, .. }) => a == b,
            (JobKind::Points { workload: a, .. }, JobKind::Points { workload: b, .. }) => a == b,
            _ => false,
        }
    }
}
