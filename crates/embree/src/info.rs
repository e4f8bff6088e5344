//! [`EmbreeInfo`]: what a report needs to say about the Embree it measured.

use crate::Device;
use raybench_embree_sys::RTCDeviceProperty as P;
use serde::{Deserialize, Serialize};

/// Where [`EmbreeInfo::isa`] came from.
pub const ISA_FROM_CONFIG: &str = "config";
/// See [`EmbreeInfo::isa`].
pub const ISA_INFERRED: &str = "inferred from CPU features";
/// The config's `max_isa=` capped the ISA inferred from CPU features.
pub const ISA_CAPPED: &str = "inferred from CPU features, capped by config max_isa";

/// Version, build options and ISA of an Embree device.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EmbreeInfo {
    /// `major.minor.patch` from `rtcGetDeviceProperty`, e.g. `"3.13.5"`.
    pub version: String,
    /// The config string the device was created with.
    pub config: String,
    /// `"internal"`, `"TBB"` or `"PPL"` (`RTC_DEVICE_PROPERTY_TASKING_SYSTEM`).
    pub tasking_system: String,
    /// Ray masks compiled in: every ray must carry mask `0xFFFFFFFF` (Debian: true).
    pub ray_mask_supported: bool,
    pub backface_culling: bool,
    /// False on Debian: invalid rays abort the process, hence `Ray::check` before every call.
    pub ignore_invalid_rays: bool,
    /// The ISA Embree's kernels run with: `"AVX512"`, `"AVX2"`, `"AVX"`, `"SSE4.2"`, `"SSE2"`.
    /// Embree has no API that reports its choice, so unless the config pins `isa=`, this is
    /// inferred from the CPU's features with the rule Embree's dispatch uses; `isa_source`
    /// says which.
    pub isa: String,
    /// [`ISA_FROM_CONFIG`], [`ISA_INFERRED`] or [`ISA_CAPPED`].
    pub isa_source: String,
}

impl EmbreeInfo {
    pub(crate) fn query(device: &Device) -> EmbreeInfo {
        let flag = |p: P| device.property(p) != 0;
        let version = format!(
            "{}.{}.{}",
            device.property(P::RTC_DEVICE_PROPERTY_VERSION_MAJOR),
            device.property(P::RTC_DEVICE_PROPERTY_VERSION_MINOR),
            device.property(P::RTC_DEVICE_PROPERTY_VERSION_PATCH)
        );
        let (isa, isa_source) = isa_for_config(device.config());
        EmbreeInfo {
            version,
            config: device.config().to_string(),
            tasking_system: tasking_name(device.property(P::RTC_DEVICE_PROPERTY_TASKING_SYSTEM)),
            ray_mask_supported: flag(P::RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED),
            backface_culling: flag(P::RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED),
            ignore_invalid_rays: flag(P::RTC_DEVICE_PROPERTY_IGNORE_INVALID_RAYS_ENABLED),
            isa: isa.to_string(),
            isa_source: isa_source.to_string(),
        }
    }
}

/// Values documented in rtcGetDeviceProperty(3).
fn tasking_name(code: isize) -> String {
    match code {
        0 => "internal".to_string(),
        1 => "TBB".to_string(),
        2 => "PPL".to_string(),
        other => format!("unknown ({other})"),
    }
}

/// Embree's ISA levels, lowest first, in [`EmbreeInfo::isa`]'s spelling.
const ISA_LEVELS: [&str; 5] = ["SSE2", "SSE4.2", "AVX", "AVX2", "AVX512"];

/// The last `key=` value of an Embree config string.
fn config_value(config: &str, key: &str) -> Option<String> {
    config
        .split(',')
        .filter_map(|entry| entry.split_once('='))
        .filter(|(k, _)| k.trim() == key)
        .map(|(_, value)| value.trim().to_ascii_lowercase())
        .next_back()
}

/// An Embree ISA name as a level. Embree silently falls back to SSE2 for a name it does not
/// know (measured: `isa=pentium` runs the SSE2 kernels, no error).
fn isa_level(name: &str) -> &'static str {
    match name {
        "sse4.2" | "sse42" => "SSE4.2",
        "avx" => "AVX",
        "avx2" => "AVX2",
        "avx512" | "avx512skx" => "AVX512",
        _ => "SSE2",
    }
}

/// Whether `name` is an ISA name Embree knows (see [`isa_level`] for what happens otherwise).
pub(crate) fn is_known_isa(name: &str) -> bool {
    matches!(
        name.to_ascii_lowercase().as_str(),
        "sse2" | "sse4.2" | "sse42" | "avx" | "avx2" | "avx512" | "avx512skx"
    )
}

/// The ISA a device with `config` runs, and where that answer comes from: `isa=` pins it,
/// `max_isa=` caps what the CPU offers, otherwise the CPU decides.
pub(crate) fn isa_for_config(config: &str) -> (&'static str, &'static str) {
    if let Some(name) = config_value(config, "isa") {
        return (isa_level(&name), ISA_FROM_CONFIG);
    }
    let cpu = infer_isa();
    let rank = |isa: &str| ISA_LEVELS.iter().position(|&level| level == isa);
    let cap = config_value(config, "max_isa").and_then(|cap| rank(isa_level(&cap)));
    match (rank(cpu), cap) {
        (Some(cpu_rank), Some(cap_rank)) => (ISA_LEVELS[cpu_rank.min(cap_rank)], ISA_CAPPED),
        _ => (cpu, ISA_INFERRED),
    }
}

/// The best ISA Embree 3.13 would pick on this CPU. Each level requires the one below plus the
/// features Embree's `sysinfo.h` adds for it (AVX2 includes FMA, BMI1/2, LZCNT and F16C; the
/// AVX512 kernels are the SKX set F/CD/DQ/BW/VL). `is_x86_feature_detected!` also checks that
/// the OS saves the wide registers, as Embree's YMM/ZMM checks do. Debian's library has kernels
/// for every level.
pub fn infer_isa() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        let sse42 = has!("sse4.2") && has!("popcnt");
        let avx = sse42 && has!("avx");
        let avx2 = avx
            && has!("f16c")
            && has!("avx2")
            && has!("fma")
            && has!("bmi1")
            && has!("bmi2")
            && has!("lzcnt");
        let avx512 = avx2
            && has!("avx512f")
            && has!("avx512cd")
            && has!("avx512dq")
            && has!("avx512bw")
            && has!("avx512vl");
        match (avx512, avx2, avx, sse42) {
            (true, ..) => "AVX512",
            (_, true, ..) => "AVX2",
            (_, _, true, _) => "AVX",
            (.., true) => "SSE4.2",
            _ => "SSE2",
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        "unknown (not x86_64)"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isa_pinned_by_config_wins() {
        assert_eq!(
            isa_for_config("threads=1,isa=avx2"),
            ("AVX2", ISA_FROM_CONFIG)
        );
        assert_eq!(
            isa_for_config("isa=sse4.2 ,threads=2"),
            ("SSE4.2", ISA_FROM_CONFIG)
        );
        assert_eq!(isa_for_config("isa=pentium"), ("SSE2", ISA_FROM_CONFIG));
        assert_eq!(isa_for_config(""), (infer_isa(), ISA_INFERRED));
        assert_eq!(isa_for_config("max_isa=sse2"), ("SSE2", ISA_CAPPED));
        assert_eq!(isa_for_config("max_isa=avx512").0, infer_isa());
    }

    #[test]
    fn inferred_isa_is_one_of_embrees() {
        assert!(ISA_LEVELS.contains(&infer_isa()));
    }
}
