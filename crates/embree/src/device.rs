//! [`Device`]: one `RTCDevice`, its error callback and its memory monitor.

use crate::error::{EmbreeError, error_name};
use crate::info::EmbreeInfo;
use raybench_embree_sys as sys;
use std::collections::HashMap;
use std::ffi::{CStr, CString, c_char, c_void};
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, PoisonError, Weak};

/// What Embree reports through callbacks. Boxed inside [`Device`] so its address, handed to
/// Embree as the callbacks' user pointer, stays fixed for the device's whole life.
#[derive(Debug)]
struct DeviceEvents {
    last_error: Mutex<Option<String>>,
    /// Bytes Embree has allocated minus bytes it has freed, as told by the memory monitor.
    allocated_bytes: AtomicI64,
    /// The most bytes Embree may allocate beyond `base_bytes`: an allocation past it is
    /// refused (`u64::MAX`: none).
    limit_bytes: AtomicU64,
    /// What Embree held when the limit was set: the scenes already on the device, which the
    /// limit leaves out.
    base_bytes: AtomicI64,
    /// The most bytes beyond `base_bytes` an allocation was refused at since
    /// [`Device::set_memory_limit`] (0: none refused).
    refused_at: AtomicU64,
}

impl Default for DeviceEvents {
    fn default() -> Self {
        DeviceEvents {
            last_error: Mutex::default(),
            allocated_bytes: AtomicI64::new(0),
            limit_bytes: AtomicU64::new(u64::MAX),
            base_bytes: AtomicI64::new(0),
            refused_at: AtomicU64::new(0),
        }
    }
}

impl DeviceEvents {
    fn record_error(&self, message: String) {
        *self
            .last_error
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some(message);
    }

    fn take_error(&self) -> Option<String> {
        self.last_error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
    }
}

/// An Embree device (`RTCDevice`), created from an explicit config string and released on
/// drop. Every scene built on it holds an `Arc<Device>`, so the device outlives its scenes.
///
/// Errors: an error callback records the last message Embree reports (it may be called from a
/// TBB worker thread); a check after each call reads the error code with `rtcGetDeviceError` (per
/// thread, returns and clears the first error) and attaches that message.
///
/// Memory: a memory-monitor callback keeps a running count of the bytes Embree holds
/// ([`Device::allocated_bytes`]). A scene's memory is the change of that count across its
/// build, which is only that scene's memory when builds on one device run one at a time — as
/// they do in the harness. The same callback enforces an optional limit on that count
/// ([`Device::set_memory_limit`]): Embree cancels the operation that would pass it with
/// `RTC_ERROR_OUT_OF_MEMORY`, frees what it had allocated, and stays usable, so a scene too
/// large for the machine is an error and not the kernel killing the process.
pub struct Device {
    raw: sys::RTCDevice,
    config: String,
    /// Dropped after `Drop::drop` has released `raw`, so no callback can see it freed.
    events: Box<DeviceEvents>,
}

// SAFETY: an RTCDevice is not tied to the thread that created it; Embree's device functions
// may be called from any thread (errors are even kept per thread). Moving the handle between
// threads is therefore sound.
unsafe impl Send for Device {}
// SAFETY: through `&Device` this type only reads properties, reads the calling thread's error
// code, and creates or commits *distinct* scenes, which Embree allows concurrently ("API calls
// to the same object are not thread safe ... rtcIntersect/rtcOccluded can be invoked from
// multiple threads", RenderKit/embree#207). The callbacks' state is a Mutex and an atomic.
unsafe impl Sync for Device {}

/// One device per config string while anyone holds it (see [`Device::shared`]).
static SHARED_DEVICES: LazyLock<Mutex<HashMap<String, Weak<Device>>>> =
    LazyLock::new(Default::default);

impl Device {
    /// Creates a device from `config` (Embree's `rtcNewDevice` syntax, e.g.
    /// `"threads=1,start_threads=1"`), with the error callback and memory monitor installed.
    pub fn new(config: &str) -> Result<Device, EmbreeError> {
        let c_config = CString::new(config).map_err(|_| EmbreeError::InvalidConfig {
            config: config.to_string(),
            reason: "contains a NUL byte".to_string(),
        })?;
        // SAFETY: `c_config` is NUL-terminated and outlives the call.
        let raw = unsafe { sys::rtcNewDevice(c_config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: with a null device, rtcGetDeviceError returns the thread's
            // device-creation error, as rtcNewDevice(3) documents.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(EmbreeError::DeviceCreation {
                config: config.to_string(),
                code: error_name(code),
            });
        }
        let device = Device {
            raw,
            config: config.to_string(),
            events: Box::default(),
        };
        device.install_callbacks();
        device.check("rtcNewDevice")?;
        Ok(device)
    }

    /// The process-wide device for `config`: created on first use, shared while any `Arc` to
    /// it lives. Lets the harness create the device (and Embree's thread pool, with
    /// `start_threads=1`) before it times any build; holding that `Arc` across builds is what
    /// keeps one device (otherwise each build creates and destroys its own).
    pub fn shared(config: &str) -> Result<Arc<Device>, EmbreeError> {
        let mut devices = SHARED_DEVICES
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(device) = devices.get(config).and_then(Weak::upgrade) {
            return Ok(device);
        }
        let device = Arc::new(Device::new(config)?);
        devices.retain(|_, weak| weak.strong_count() > 0);
        devices.insert(config.to_string(), Arc::downgrade(&device));
        Ok(device)
    }

    pub fn config(&self) -> &str {
        &self.config
    }

    /// Bytes Embree currently holds on this device, per its memory monitor.
    pub fn allocated_bytes(&self) -> i64 {
        self.events.allocated_bytes.load(Ordering::Relaxed)
    }

    /// Sets the most bytes Embree may allocate on this device from now on (`None`: no limit)
    /// and forgets any earlier refusal. What the device holds already (other scenes built on
    /// it) is left out, so the limit bounds the next build alone, as our builders' limits do;
    /// it is meant to be set just before a build when builds run one at a time.
    pub fn set_memory_limit(&self, limit_bytes: Option<u64>) {
        self.events
            .base_bytes
            .store(self.allocated_bytes(), Ordering::Relaxed);
        self.events
            .limit_bytes
            .store(limit_bytes.unwrap_or(u64::MAX), Ordering::Relaxed);
        self.events.refused_at.store(0, Ordering::Relaxed);
    }

    /// The bytes allocated since [`Device::set_memory_limit`], with the largest allocation
    /// the limit refused since then, if one was refused.
    pub fn refused_at(&self) -> Option<u64> {
        Some(self.events.refused_at.load(Ordering::Relaxed)).filter(|&b| b > 0)
    }

    /// The limit [`Device::set_memory_limit`] set, if any.
    pub fn memory_limit(&self) -> Option<u64> {
        Some(self.events.limit_bytes.load(Ordering::Relaxed)).filter(|&b| b != u64::MAX)
    }

    /// The last message Embree passed to the error callback, if not yet consumed by a check.
    pub fn last_error_message(&self) -> Option<String> {
        self.events
            .last_error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Version, build options and ISA of this device, for reports.
    pub fn info(&self) -> EmbreeInfo {
        EmbreeInfo::query(self)
    }

    pub(crate) fn raw(&self) -> sys::RTCDevice {
        self.raw
    }

    pub(crate) fn property(&self, property: sys::RTCDeviceProperty) -> isize {
        // SAFETY: `self.raw` is a live device; reading a property has no other precondition.
        unsafe { sys::rtcGetDeviceProperty(self.raw, property) }
    }

    /// Turns the calling thread's pending Embree error, if any, into an error naming
    /// `operation` and carrying the callback's message.
    pub(crate) fn check(&self, operation: &'static str) -> Result<(), EmbreeError> {
        // SAFETY: `self.raw` is a live device.
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        if code == sys::RTCError::RTC_ERROR_NONE {
            return Ok(());
        }
        Err(EmbreeError::Api {
            operation,
            code: error_name(code),
            message: self
                .events
                .take_error()
                .unwrap_or_else(|| "Embree gave no message".to_string()),
        })
    }

    fn install_callbacks(&self) {
        let events: *const DeviceEvents = &*self.events;
        // SAFETY: `events` points into the Box owned by this device, which is freed only after
        // rtcReleaseDevice (see `Drop`), so it is valid whenever Embree calls back. The
        // callbacks only take shared references to it.
        unsafe {
            sys::rtcSetDeviceErrorFunction(self.raw, Some(on_error), events as *mut c_void);
            sys::rtcSetDeviceMemoryMonitorFunction(
                self.raw,
                Some(on_memory),
                events as *mut c_void,
            );
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: this `Device` owns the one reference it created; every scene holds an
        // `Arc<Device>` and releases its own scene first, so nothing uses `raw` afterwards.
        unsafe { sys::rtcReleaseDevice(self.raw) };
    }
}

impl fmt::Debug for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Device")
            .field("config", &self.config)
            .field("allocated_bytes", &self.allocated_bytes())
            .finish_non_exhaustive()
    }
}

/// Error callback. Must never unwind into C: everything runs inside `catch_unwind`, and a
/// panic there is dropped (the error code is still set and checked by [`Device::check`]).
unsafe extern "C" fn on_error(user: *mut c_void, _code: sys::RTCError, message: *const c_char) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: Embree passes a NUL-terminated string valid for the callback's duration.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        // SAFETY: `user` is the `DeviceEvents` registered in `install_callbacks`, alive until
        // the device is released.
        let events = unsafe { &*(user as *const DeviceEvents) };
        events.record_error(text);
    }));
}

/// Memory-monitor callback: may run on several threads at once, hence the atomics. An
/// allocation that takes the count past the limit is refused (false): Embree then cancels the
/// operation. Per rtcSetDeviceMemoryMonitorFunction(3), a refused allocation reported before
/// it happens (`post == false`) never happens, so it is taken back out of the count; one
/// reported after it happened stays counted, as Embree frees it later. Frees cannot be
/// refused. The body is atomic arithmetic and cannot panic.
unsafe extern "C" fn on_memory(user: *mut c_void, bytes: isize, post: bool) -> bool {
    // SAFETY: as in `on_error`.
    let events = unsafe { &*(user as *const DeviceEvents) };
    let bytes = bytes as i64;
    let total = events.allocated_bytes.fetch_add(bytes, Ordering::Relaxed) + bytes;
    let added = (total - events.base_bytes.load(Ordering::Relaxed)).max(0) as u64;
    if bytes <= 0 || added <= events.limit_bytes.load(Ordering::Relaxed) {
        return true;
    }
    if !post {
        events.allocated_bytes.fetch_sub(bytes, Ordering::Relaxed);
    }
    events.refused_at.fetch_max(added, Ordering::Relaxed);
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_devices_are_cached_per_config_while_alive() {
        let a = Device::shared("threads=1,verbose=0").unwrap();
        let b = Device::shared("threads=1,verbose=0").unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        let other = Device::shared("threads=1,verbose=0,start_threads=1").unwrap();
        assert!(!Arc::ptr_eq(&a, &other));
        let weak = Arc::downgrade(&a);
        drop((a, b));
        assert!(
            weak.upgrade().is_none(),
            "the cache must not keep devices alive"
        );
        let again = Device::shared("threads=1,verbose=0").unwrap();
        assert_eq!(again.config(), "threads=1,verbose=0");
    }

    #[test]
    fn nul_in_config_is_rejected_before_embree() {
        assert!(matches!(
            Device::new("threads=1\0"),
            Err(EmbreeError::InvalidConfig { .. })
        ));
    }

    /// The error callback records Embree's message and `check` reports it: REFIT is not a
    /// valid scene build quality, which Embree reports as an error.
    #[test]
    fn api_errors_carry_the_callback_message() {
        let device = Device::new("threads=1").unwrap();
        // SAFETY: a live device; the scene is released below and not used otherwise.
        let scene = unsafe { sys::rtcNewScene(device.raw()) };
        assert!(!scene.is_null());
        // SAFETY: `scene` is live; an invalid quality only sets the device error.
        unsafe {
            sys::rtcSetSceneBuildQuality(scene, sys::RTCBuildQuality::RTC_BUILD_QUALITY_REFIT)
        };
        let err = device.check("rtcSetSceneBuildQuality").unwrap_err();
        // SAFETY: releases the one reference created above.
        unsafe { sys::rtcReleaseScene(scene) };
        let text = err.to_string();
        assert!(text.contains("rtcSetSceneBuildQuality"), "{text}");
        assert!(text.contains("RTC_ERROR_"), "{text}");
        println!("Embree said: {text}");
        assert_eq!(
            device.check("nothing"),
            Ok(()),
            "errors are cleared once read"
        );
    }
}
