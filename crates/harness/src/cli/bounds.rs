//! Bounds on every number a user gives, checked before any work: a count that cannot fit in
//! this machine's memory is refused with the estimate and the bound, not discovered as a
//! failed allocation an hour later, and a count that means nothing (0 timed runs) or only
//! measures the operating system (100,000 threads) is refused with the reason.

use crate::memory::gib;
use anyhow::{Result, bail};

/// Bytes a run holds per ray of one ray workload while a scene is measured: the ray (44
/// bytes) and the reference's answer (20) for every workload at once, plus, for the workload
/// being traced, the structure's converted copy (Embree's `RTCRayHit` is 80 bytes), its timed
/// and counted answers and the per-ray work and picture inputs. Rounded up to leave room for
/// what the estimate does not itemise.
const BYTES_PER_RAY_HELD: u64 = 128;
const BYTES_PER_RAY_TRACED: u64 = 256;
/// Whitted's recursion makes up to several rays per primary ray (reflection and refraction at
/// each of up to five bounces); the estimate counts its workload as this many.
const WHITTED_FACTOR: u64 = 4;
/// Bytes per closest-point query: the point and three answers (the reference's, the timed and
/// the counted path's), rounded up.
const BYTES_PER_POINT: u64 = 128;
/// The share of physical memory a run may plan to use.
const MEMORY_SHARE: f64 = 0.5;

/// Most timed builds or trace passes: enough for any median, and a bound on a typo.
pub const MAX_RUNS: usize = 1000;
/// Most worker threads per core: oversubscription can be measured, a thread storm cannot.
pub const THREADS_PER_CORE: usize = 8;

/// Refuses `--rays n` when the ray workloads would not fit in memory. `ray_workloads` counts
/// them; `whitted` says whether one of them is Whitted's.
pub fn check_rays(n: usize, ray_workloads: usize, whitted: bool) -> Result<()> {
    if ray_workloads == 0 {
        return Ok(());
    }
    let held = ray_workloads as u64 + if whitted { WHITTED_FACTOR - 1 } else { 0 };
    let per_ray = held * BYTES_PER_RAY_HELD + BYTES_PER_RAY_TRACED;
    let what = match (ray_workloads, whitted) {
        (1, _) => "1 ray workload".to_string(),
        (n, false) => format!("{n} ray workloads"),
        (n, true) => format!("{n} ray workloads, Whitted's counted {WHITTED_FACTOR} times"),
    };
    check_count("--rays", "ray", n, per_ray, &what)
}

/// Refuses `--points n` when the closest-point workloads would not fit in memory.
pub fn check_points(n: usize, point_workloads: usize) -> Result<()> {
    if point_workloads == 0 {
        return Ok(());
    }
    let per_point = (point_workloads as u64 + 1) * BYTES_PER_POINT;
    let what = match point_workloads {
        1 => "1 closest-point workload".to_string(),
        n => format!("{n} closest-point workloads"),
    };
    check_count("--points", "query point", n, per_point, &what)
}

fn check_count(flag: &str, unit: &str, n: usize, per_item: u64, what: &str) -> Result<()> {
    let memory = crate::memory::physical();
    let allowed = (memory as f64 * MEMORY_SHARE / per_item as f64) as u64;
    if n as u64 > allowed {
        bail!(
            "{flag} {n} is more than this machine can hold: at about {per_item} bytes a {unit} \
             ({what}) that is {}, and a run may plan on half of its {} of memory; at most \
             {allowed} here",
            gib(n as f64 * per_item as f64),
            gib(memory as f64)
        );
    }
    Ok(())
}

/// `--build-runs` / `--trace-runs`: 1 to [`MAX_RUNS`].
pub fn runs(text: &str) -> Result<usize, String> {
    match text.trim().parse::<u64>() {
        Ok(0) => Err("0 timed runs would measure nothing: give at least 1".into()),
        Ok(n) if n <= MAX_RUNS as u64 => Ok(n as usize),
        Ok(_) => Err(format!(
            "at most {MAX_RUNS} (the median of {MAX_RUNS} runs is already as steady as this \
             machine allows)"
        )),
        Err(_) => Err("must be a whole number from 1 to 1000".into()),
    }
}

/// `--time-budget`: seconds of timed passes per structure and scene, above 0 and at most an
/// hour.
pub fn seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x <= 3600.0 => Ok(x),
        _ => Err("must be a number of seconds above 0 and at most 3600".into()),
    }
}

/// `--threads`: 1 to [`THREADS_PER_CORE`] × the cores of this machine.
pub fn threads(text: &str) -> Result<usize, String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let most = THREADS_PER_CORE * cores;
    match text.trim().parse::<u64>() {
        Ok(0) => Err("at least 1 thread is needed".into()),
        Ok(n) if n <= most as u64 => Ok(n as usize),
        Ok(_) => Err(format!(
            "at most {most} on this machine ({THREADS_PER_CORE} × its {cores} cores): more \
             threads would measure the scheduler, not the structures"
        )),
        Err(_) => Err(format!("must be a whole number from 1 to {most}")),
    }
}

/// A size in bytes: a whole number with an optional binary suffix (`K`, `M`, `G`, `T`, with
/// or without `iB`/`B`), e.g. `4G` or `1073741824`.
pub fn byte_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, suffix) = t.split_at(digits);
    let shift = match suffix.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err("a size such as 4G, 512M or 1073741824 (bytes)".into()),
    };
    let n: u64 = number
        .parse()
        .map_err(|_| "a size such as 4G, 512M or 1073741824 (bytes)".to_string())?;
    n.checked_mul(1 << shift)
        .filter(|&b| b > 0)
        .ok_or_else(|| "a size of at least 1 byte and at most 16 EiB".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(byte_size("4096"), Ok(4096));
        assert_eq!(byte_size("4G"), Ok(4 << 30));
        assert_eq!(byte_size("512MiB"), Ok(512 << 20));
        assert_eq!(byte_size(" 2 kb"), Ok(2048));
        assert!(byte_size("2x").is_err());
        assert!(byte_size("0").is_err());
        assert!(byte_size("99999999999T").is_err());
        assert!(byte_size("-1").is_err());
    }

    #[test]
    fn runs_and_threads_are_bounded_with_the_reason() {
        assert_eq!(runs("3"), Ok(3));
        assert!(runs("0").unwrap_err().contains("measure nothing"));
        assert!(
            runs("18446744073709551615")
                .unwrap_err()
                .contains("at most 1000")
        );
        assert_eq!(threads("1"), Ok(1));
        assert!(threads("0").is_err());
        assert!(
            threads("100000")
                .unwrap_err()
                .contains("measure the scheduler")
        );
    }

    #[test]
    fn counts_beyond_memory_are_refused_with_the_estimate() {
        assert!(check_rays(100_000, 5, true).is_ok());
        let err = check_rays(usize::MAX, 5, true).unwrap_err().to_string();
        assert!(err.starts_with("--rays 18446744073709551615 is more than this machine can hold"));
        assert!(
            err.contains("about 1280 bytes a ray (5 ray workloads, Whitted's counted 4 times)"),
            "{err}"
        );
        assert!(
            check_rays(usize::MAX, 0, false).is_ok(),
            "no ray workload, no rays held"
        );
        assert!(check_points(10_000, 2).is_ok());
        assert!(
            check_points(usize::MAX, 2)
                .unwrap_err()
                .to_string()
                .contains("--points")
        );
    }
}
