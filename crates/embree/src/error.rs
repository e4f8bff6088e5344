use raybench_accel::BuildError;
use raybench_embree_sys::RTCError;
use raybench_geom::RayError;

/// What went wrong talking to Embree.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EmbreeError {
    #[error("Embree config string {config:?} is unusable: {reason}")]
    InvalidConfig { config: String, reason: String },
    #[error("rtcNewDevice({config:?}) failed with {code}")]
    DeviceCreation { config: String, code: &'static str },
    /// An API call set the device's error code; `message` is what Embree passed to the error
    /// callback (the callback may run on another thread, see [`crate::Device`]).
    #[error("{operation} failed with {code}: {message}")]
    Api {
        operation: &'static str,
        code: &'static str,
        message: String,
    },
    /// The device's memory limit refused an allocation of the build: `reached_bytes` is what
    /// the build would have held with it (a lower bound on what the build needs).
    #[error("Embree was refused memory at {reached_bytes} bytes, past its limit of {limit_bytes}")]
    MemoryLimit {
        reached_bytes: u64,
        limit_bytes: u64,
    },
}

impl From<EmbreeError> for BuildError {
    fn from(e: EmbreeError) -> BuildError {
        match e {
            EmbreeError::MemoryLimit {
                reached_bytes,
                limit_bytes,
            } => BuildError::MemoryLimitReached {
                reached_bytes,
                limit_bytes,
            },
            e => BuildError::Backend(e.to_string()),
        }
    }
}

/// A ray that may not reach Embree, with its position in the batch it came from.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("ray {index}: {error}")]
pub struct InvalidRay {
    pub index: usize,
    pub error: RayError,
}

/// The header's name for an error code (codes outside the header's set are named too, since
/// `RTCError` is a newtype that can hold any value).
pub(crate) fn error_name(code: RTCError) -> &'static str {
    match code {
        RTCError::RTC_ERROR_NONE => "RTC_ERROR_NONE",
        RTCError::RTC_ERROR_UNKNOWN => "RTC_ERROR_UNKNOWN",
        RTCError::RTC_ERROR_INVALID_ARGUMENT => "RTC_ERROR_INVALID_ARGUMENT",
        RTCError::RTC_ERROR_INVALID_OPERATION => "RTC_ERROR_INVALID_OPERATION",
        RTCError::RTC_ERROR_OUT_OF_MEMORY => "RTC_ERROR_OUT_OF_MEMORY",
        RTCError::RTC_ERROR_UNSUPPORTED_CPU => "RTC_ERROR_UNSUPPORTED_CPU",
        RTCError::RTC_ERROR_CANCELLED => "RTC_ERROR_CANCELLED",
        _ => "an error code unknown to rtcore.h",
    }
}
