//! [`EmbreeParams`]: the Embree knobs a report records, and the device config they imply.

use raybench_embree_sys::RTCBuildQuality;
use serde::{Deserialize, Serialize};

/// Embree's BVH build quality (`rtcSetSceneBuildQuality`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    /// Fast, refit-friendly build (Embree's "dynamic" branch).
    Low,
    /// Embree's default: binned SAH.
    #[default]
    Medium,
    /// Adds spatial splits: slower build, faster traversal.
    High,
}

impl Quality {
    pub fn name(self) -> &'static str {
        match self {
            Quality::Low => "low",
            Quality::Medium => "medium",
            Quality::High => "high",
        }
    }

    pub(crate) fn to_rtc(self) -> RTCBuildQuality {
        match self {
            Quality::Low => RTCBuildQuality::RTC_BUILD_QUALITY_LOW,
            Quality::Medium => RTCBuildQuality::RTC_BUILD_QUALITY_MEDIUM,
            Quality::High => RTCBuildQuality::RTC_BUILD_QUALITY_HIGH,
        }
    }
}

/// How an Embree scene is built. The default is Embree's own: medium quality, fast mode.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EmbreeParams {
    pub quality: Quality,
    /// `RTC_SCENE_FLAG_ROBUST`: conservative traversal and Plücker triangle test, no cracks
    /// along shared edges, inclusive at `t_min` (docs/validation.md, E3).
    pub robust: bool,
    /// Embree worker threads; 0 = all cores. Goes into the device config as `threads=N`.
    pub threads: usize,
    /// Pins Embree's ISA (`isa=avx2`, …); `None` lets Embree pick the best the CPU has.
    pub isa: Option<String>,
    /// Batches prepared as coherent (`Accel::prepare_coherent_rays`: the primary rays) are
    /// traced for closest hit through `rtcIntersect1M` with
    /// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`, 64 rays a call, so Embree may trace them in
    /// packets of its own (its stream mode sorts them by octant into packets). Any hit stays
    /// `rtcOccluded1`, as the wide BVH's packet walk is closest-hit only. Off, every ray goes
    /// through `rtcIntersect1`/`rtcOccluded1`, hint or not.
    #[serde(default)]
    pub coherent_stream: bool,
    /// Batches prepared as coherent are traced through Embree's packet API,
    /// `rtcIntersect16`/`rtcOccluded16` with `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`, sixteen
    /// consecutive rays a packet (the packets `bvh8-packets` walks), laid out outside timing;
    /// the last packet of a batch masks its missing lanes invalid. Takes precedence over
    /// `coherent_stream`. Other batches go ray by ray. Coherent any-hit batches go through
    /// `rtcOccluded16` only with `coherent_occluded16`. Written into reports only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub coherent_packet16: bool,
    /// With `coherent_packet16`, coherent any-hit batches (the shadow rays) go through
    /// `rtcOccluded16` too. Off in every preset: `rtcOccluded16` reports rays lying in a
    /// triangle's plane as occluded where `rtcOccluded1` and brute force do not
    /// (docs/validation.md, E11), so without it they go through `rtcOccluded1`. Written into
    /// reports only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub coherent_occluded16: bool,
    /// The most bytes Embree may allocate for this build, scenes already on the device left
    /// out (the device's memory monitor refuses the allocation past it, and the build fails with
    /// [`raybench_accel::BuildError::MemoryLimitReached`]); `None`: no limit. Written
    /// into reports only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory_limit_bytes: Option<u64>,
}

impl EmbreeParams {
    pub fn low() -> EmbreeParams {
        EmbreeParams {
            quality: Quality::Low,
            ..EmbreeParams::default()
        }
    }

    pub fn medium() -> EmbreeParams {
        EmbreeParams::default()
    }

    pub fn high() -> EmbreeParams {
        EmbreeParams {
            quality: Quality::High,
            ..EmbreeParams::default()
        }
    }

    /// Medium quality, coherent batches through Embree's stream API (`coherent_stream`).
    pub fn medium_stream() -> EmbreeParams {
        EmbreeParams {
            coherent_stream: true,
            ..EmbreeParams::default()
        }
    }

    /// Medium quality, coherent batches through Embree's 16-wide packet API
    /// (`coherent_packet16`).
    pub fn medium_packet16() -> EmbreeParams {
        EmbreeParams {
            coherent_packet16: true,
            ..EmbreeParams::default()
        }
    }

    /// Medium quality on the kernels of `isa` (e.g. `avx2`) instead of the widest the CPU
    /// has, which Embree picks by itself: beside `medium()` it shows what Embree's own choice
    /// buys on the machine, and races the 8-wide trees, whose walks use AVX2, on the same
    /// instructions.
    pub fn medium_on(isa: &str) -> EmbreeParams {
        EmbreeParams {
            isa: Some(isa.to_string()),
            ..EmbreeParams::default()
        }
    }

    /// Medium quality with `RTC_SCENE_FLAG_ROBUST`.
    pub fn robust() -> EmbreeParams {
        EmbreeParams {
            robust: true,
            ..EmbreeParams::default()
        }
    }

    /// The device config: `threads=N`, thread start-up at device creation rather than in the
    /// first timed build (`start_threads=1`), no pinning (`set_affinity=0`), and `isa=` when
    /// pinned.
    pub fn config_string(&self) -> String {
        let mut config = format!("threads={},start_threads=1,set_affinity=0", self.threads);
        if let Some(isa) = &self.isa {
            config.push_str(",isa=");
            config.push_str(isa);
        }
        config
    }

    /// Registered name: `embree-<quality>`, with robust medium as `embree-robust` and other
    /// robust qualities as `embree-<quality>-robust`; `-packet16` appended with
    /// `coherent_packet16` (`-packet16-occluded16` with `coherent_occluded16` too), else
    /// `-stream` with `coherent_stream`; `-<isa>` last when the ISA is pinned.
    pub fn name(&self) -> String {
        let name = match (self.quality, self.robust) {
            (q, false) => format!("embree-{}", q.name()),
            (Quality::Medium, true) => "embree-robust".to_string(),
            (q, true) => format!("embree-{}-robust", q.name()),
        };
        let name = if self.coherent_packet16 && self.coherent_occluded16 {
            name + "-packet16-occluded16"
        } else if self.coherent_packet16 {
            name + "-packet16"
        } else if self.coherent_stream {
            name + "-stream"
        } else {
            name
        };
        match &self.isa {
            Some(isa) => format!("{name}-{isa}"),
            None => name,
        }
    }

    /// Refuses an `isa` Embree does not know: Embree would silently run SSE2 instead, and a
    /// comma could smuggle other options into the config string.
    pub(crate) fn check_isa(&self) -> Result<(), String> {
        match &self.isa {
            Some(isa) if !crate::info::is_known_isa(isa) => Err(format!(
                "isa {isa:?} is not one of Embree's: sse2, sse4.2, avx, avx2, avx512"
            )),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_names_and_config() {
        let names: Vec<String> = [
            EmbreeParams::low(),
            EmbreeParams::medium(),
            EmbreeParams::high(),
            EmbreeParams::robust(),
            EmbreeParams::medium_stream(),
            EmbreeParams::medium_packet16(),
            EmbreeParams::medium_on("avx2"),
        ]
        .iter()
        .map(EmbreeParams::name)
        .collect();
        assert_eq!(
            names,
            [
                "embree-low",
                "embree-medium",
                "embree-high",
                "embree-robust",
                "embree-medium-stream",
                "embree-medium-packet16",
                "embree-medium-avx2"
            ]
        );
        let high_robust = EmbreeParams {
            robust: true,
            ..EmbreeParams::high()
        };
        assert_eq!(high_robust.name(), "embree-high-robust");
        let pinned = EmbreeParams {
            threads: 2,
            isa: Some("avx2".into()),
            ..EmbreeParams::default()
        };
        assert_eq!(
            pinned.config_string(),
            "threads=2,start_threads=1,set_affinity=0,isa=avx2"
        );
        assert_eq!(
            EmbreeParams::default().config_string(),
            "threads=0,start_threads=1,set_affinity=0"
        );
    }

    #[test]
    fn serialises_with_lowercase_quality() {
        let json = serde_json::to_string(&EmbreeParams::robust()).unwrap();
        assert_eq!(
            json,
            r#"{"quality":"medium","robust":true,"threads":0,"isa":null,"coherent_stream":false}"#
        );
        let back: EmbreeParams = serde_json::from_str(&json).unwrap();
        assert_eq!(back, EmbreeParams::robust());
        // A report without `coherent_stream` still reads (the field defaults to false).
        let old = r#"{"quality":"medium","robust":true,"threads":0,"isa":null}"#;
        assert_eq!(
            serde_json::from_str::<EmbreeParams>(old).unwrap(),
            EmbreeParams::robust()
        );
        let json = serde_json::to_string(&EmbreeParams::medium_packet16()).unwrap();
        assert!(json.ends_with(r#""coherent_stream":false,"coherent_packet16":true}"#));
        assert_eq!(
            serde_json::from_str::<EmbreeParams>(&json).unwrap(),
            EmbreeParams::medium_packet16()
        );
    }

    #[test]
    fn isa_cannot_inject_options() {
        let bad = EmbreeParams {
            isa: Some("avx2,threads=64".into()),
            ..EmbreeParams::default()
        };
        assert!(bad.check_isa().is_err());
        let unknown = EmbreeParams {
            isa: Some("pentium".into()),
            ..EmbreeParams::default()
        };
        assert!(unknown.check_isa().is_err());
        assert!(EmbreeParams::default().check_isa().is_ok());
        let avx2 = EmbreeParams {
            isa: Some("AVX2".into()),
            ..EmbreeParams::default()
        };
        assert!(avx2.check_isa().is_ok());
    }
}
