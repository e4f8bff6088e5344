//! The machinery every measuring command runs in: the worker pool (with the run's FPU state on
//! every worker, and the environment fingerprint read on one of them), live progress, the notes
//! and errors a run collects, and panics turned into errors.

use crate::env::Environment;
use anyhow::{Context, Result};
use raybench_embree::{Device, EmbreeParams, fpu};

/// Live progress on a terminal; one plain line per step on stderr otherwise (CI logs).
pub(crate) struct Progress {
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    pub(crate) fn new(enabled: bool, steps: u64) -> Progress {
        let bar = enabled.then(|| {
            let pb = indicatif::ProgressBar::new(steps);
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed} {msg}")
            {
                pb.set_style(style);
            }
            pb
        });
        Progress { bar }
    }

    /// Called between measurements only, never inside a timed region.
    pub(crate) fn step(&self, msg: String) {
        let msg = raybench_scenes::printable(&msg).into_owned();
        match &self.bar {
            Some(pb) => {
                pb.set_message(msg);
                pb.inc(1);
            }
            None => eprintln!("raybench: {msg}"),
        }
    }

    pub(crate) fn note(&self, msg: String) {
        let msg = raybench_scenes::printable(&msg).into_owned();
        match &self.bar {
            Some(pb) => pb.println(msg),
            None => eprintln!("raybench: {msg}"),
        }
    }

    pub(crate) fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}

/// The worker pool every build and trace runs in, with the run's FPU state on every worker, and
/// the environment fingerprint read on one of its workers (shared by `run` and `verify`).
pub(crate) struct Workers {
    pub pool: rayon::ThreadPool,
    pub environment: Environment,
}

impl Workers {
    pub(crate) fn start(threads: usize, ftz: bool) -> Result<Workers> {
        anyhow::ensure!(threads >= 1, "--threads must be at least 1 (got {threads})");
        fpu::set_ftz_daz(ftz);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("raybench-worker-{i}"))
            .start_handler(move |_| fpu::set_ftz_daz(ftz))
            .build()
            .context("creating the thread pool")?;
        let config = EmbreeParams {
            threads,
            ..EmbreeParams::medium()
        }
        .config_string();
        let device = Device::shared(&config)
            .map_err(|e| anyhow::anyhow!("creating the Embree device ({config}): {e}"))?;
        let mxcsr = pool.install(fpu::mxcsr);
        let environment = Environment::capture(threads, mxcsr, device.info());
        Ok(Workers { pool, environment })
    }
}

/// Notes and errors collected while a run goes on (both end up in its report).
#[derive(Debug, Default)]
pub(crate) struct Log {
    pub notes: Vec<String>,
    pub errors: Vec<String>,
}

/// Runs `work`, turning a panic (a bug in a structure or generator) into an error, so one bad
/// structure costs its own result, not the whole run and its report.
pub(crate) fn catch_panic<T>(work: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
        .unwrap_or_else(|payload| Err(anyhow::anyhow!("panicked: {}", panic_message(&*payload))))
}

/// The message a panic was raised with (`panic!("…")` carries a `&str` or a `String`).
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_naming_its_message() {
        let err = catch_panic::<()>(|| panic!("bad node {}", 7)).unwrap_err();
        assert_eq!(err.to_string(), "panicked: bad node 7");
        assert_eq!(catch_panic(|| Ok(5)).unwrap(), 5);
    }
}
