//! The environment fingerprint stamped on every report: machine, toolchain, revision, command,
//! Embree's configuration and the floating-point state the numbers were measured under.

use raybench_embree::EmbreeInfo;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Environment {
    pub cpu_model: String,
    /// SIMD features the CPU offers (runtime detection).
    pub cpu_flags: Vec<String>,
    pub cores: usize,
    pub os: String,
    pub rustc: String,
    /// Cargo profile the binary was built with.
    pub profile: String,
    /// Compile-time target: raybench builds for the x86-64 baseline and selects SIMD kernels at
    /// run time, so this lists the features the compiler may assume everywhere.
    pub target_cpu: String,
    pub compile_time_target_features: Vec<String>,
    pub git_revision: String,
    pub command_line: String,
    /// UTC, RFC 3339.
    pub timestamp: String,
    pub hostname: String,
    pub threads: usize,
    /// Flush-to-zero and denormals-are-zero, set identically on every worker thread for Embree
    /// and native code; `mxcsr` is the register value read on a worker.
    pub ftz: bool,
    pub daz: bool,
    pub mxcsr: String,
    /// The kernel's transparent huge page mode (`always`, `madvise` or `never`, from
    /// /sys/kernel/mm/transparent_hugepage/enabled), absent where the kernel has none. Embree's
    /// allocator asks for huge pages for its structures' memory, ours do not, so under
    /// `madvise` only Embree's get them (docs/methodology.md, "Memory pages").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transparent_hugepages: Option<String>,
    /// `GLIBC_TUNABLES` when set: `glibc.malloc.hugetlb=1` there gives our structures' large
    /// arrays huge pages too.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glibc_tunables: Option<String>,
    pub embree: EmbreeInfo,
}

fn read_trimmed(path: &str) -> Option<String> {
    std::fs::read_to_string(path)
        .ok()
        .map(|s| s.trim().to_string())
}

fn cpu_model() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    info.lines()
        .find_map(|l| {
            l.strip_prefix("model name")
                .and_then(|r| r.split(':').nth(1))
        })
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

fn os_name() -> String {
    let release = std::fs::read_to_string("/etc/os-release").unwrap_or_default();
    let pretty = release
        .lines()
        .find_map(|l| l.strip_prefix("PRETTY_NAME="))
        .map(|s| s.trim_matches('"').to_string())
        .unwrap_or_else(|| std::env::consts::OS.to_string());
    match read_trimmed("/proc/sys/kernel/osrelease") {
        Some(kernel) => format!("{pretty}, kernel {kernel}"),
        None => pretty,
    }
}

/// The selected mode of a sysfs choice list such as `always [madvise] never`: the bracketed word.
fn selected_mode(list: &str) -> Option<String> {
    let start = list.find('[')? + 1;
    let len = list[start..].find(']')?;
    Some(list[start..start + len].to_string())
}

#[cfg(target_arch = "x86_64")]
fn cpu_flags() -> Vec<String> {
    let mut flags = Vec::new();
    macro_rules! probe {
        ($($f:tt),*) => {$(
            if std::arch::is_x86_feature_detected!($f) { flags.push($f.to_string()); }
        )*};
    }
    probe!(
        "sse4.2", "avx", "avx2", "fma", "bmi2", "avx512f", "avx512cd", "avx512dq", "avx512bw",
        "avx512vl"
    );
    flags
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_flags() -> Vec<String> {
    Vec::new()
}

fn compile_time_features() -> Vec<String> {
    let mut f = Vec::new();
    macro_rules! probe {
        ($($name:tt),*) => {$( if cfg!(target_feature = $name) { f.push($name.to_string()); } )*};
    }
    probe!("sse2", "sse4.2", "avx", "avx2", "fma", "avx512f");
    f
}

/// Civil date from days since 1970-01-01 (Howard Hinnant's algorithm), to avoid a date crate
/// for one timestamp.
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(month <= 2), month, day)
}

/// Current UTC time as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_timestamp() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (y, m, d) = civil_from_days(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

pub fn git_revision() -> &'static str {
    env!("RAYBENCH_GIT_REV")
}

impl Environment {
    /// `mxcsr` is read on a worker thread of the run's pool, after FTZ/DAZ were applied.
    pub fn capture(threads: usize, mxcsr: u32, embree: EmbreeInfo) -> Environment {
        Environment {
            cpu_model: cpu_model(),
            cpu_flags: cpu_flags(),
            cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            os: os_name(),
            rustc: env!("RAYBENCH_RUSTC").to_string(),
            profile: env!("RAYBENCH_PROFILE").to_string(),
            target_cpu: "x86-64 baseline (no -C target-cpu); SIMD selected at run time".to_string(),
            compile_time_target_features: compile_time_features(),
            git_revision: git_revision().to_string(),
            command_line: std::env::args().collect::<Vec<_>>().join(" "),
            timestamp: utc_timestamp(),
            hostname: read_trimmed("/proc/sys/kernel/hostname").unwrap_or_default(),
            threads,
            ftz: mxcsr & (1 << 15) != 0,
            daz: mxcsr & (1 << 6) != 0,
            mxcsr: format!("{mxcsr:#06x}"),
            transparent_hugepages: read_trimmed("/sys/kernel/mm/transparent_hugepage/enabled")
                .and_then(|l| selected_mode(&l)),
            glibc_tunables: std::env::var("GLIBC_TUNABLES").ok(),
            embree,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_778), (2026, 11, 21));
    }

    #[test]
    fn the_selected_huge_page_mode_is_the_bracketed_one() {
        assert_eq!(
            selected_mode("always [madvise] never").as_deref(),
            Some("madvise")
        );
        assert_eq!(
            selected_mode("[always] madvise never").as_deref(),
            Some("always")
        );
        assert_eq!(selected_mode("always madvise never"), None);
        assert_eq!(selected_mode("always [madvise"), None);
    }
}
