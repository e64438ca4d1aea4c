//! The Embree device (`RTCDevice`): creation, its error and memory-monitor
//! callbacks, error checks, and the linked library's version and origin.

use super::sys;
use crate::accel::AccelError;
use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::sync::{Arc, Mutex};

/// Where the linked Embree came from (set by `build.rs`): `pkg-config …`,
/// `EMBREE_DIR …` or `wheel embreex==4.4.0.post1 at DIR`.
pub fn source() -> &'static str {
    env!("CAUSTIC_EMBREE_SOURCE")
}

/// Version of the linked library as `major.minor.patch` (from
/// `rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_VERSION)`, e.g. 40400 → 4.4.0),
/// or a description of why no device could be created.
pub fn version() -> String {
    match Device::new(None) {
        Ok(device) => version_string(device.version_number()),
        Err(e) => format!("unavailable ({e})"),
    }
}

/// 40400 → "4.4.0".
pub(super) fn version_string(v: i64) -> String {
    format!("{}.{}.{}", v / 10000, (v / 100) % 100, v % 100)
}

fn error_name(code: sys::RTCError) -> &'static str {
    match code {
        sys::RTC_ERROR_NONE => "no error",
        sys::RTC_ERROR_UNKNOWN => "unknown error",
        sys::RTC_ERROR_INVALID_ARGUMENT => "invalid argument",
        sys::RTC_ERROR_INVALID_OPERATION => "invalid operation",
        sys::RTC_ERROR_OUT_OF_MEMORY => "out of memory",
        sys::RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU",
        sys::RTC_ERROR_CANCELLED => "cancelled",
        _ => "unrecognised error code",
    }
}

/// State the device's callbacks write into. Boxed inside [`DeviceInner`], so
/// its address is stable for as long as the device exists.
#[derive(Default)]
struct DeviceShared {
    /// Messages from the error callback not yet reported.
    errors: Mutex<Vec<String>>,
    /// Bytes currently allocated by Embree for this device (memory monitor).
    bytes: AtomicIsize,
    /// High-water mark of `bytes`.
    peak: AtomicIsize,
}

/// `RTCErrorFunction`: queues the message; [`Device::check`] turns it into an
/// [`AccelError::Embree`] at the next check point.
unsafe extern "C" fn on_error(user_ptr: *mut c_void, code: sys::RTCError, message: *const c_char) {
    // SAFETY: `user_ptr` is the `DeviceShared` registered in `Device::new`; it
    // is boxed and outlives the device handle (released first in `Drop`).
    let shared = unsafe { &*(user_ptr as *const DeviceShared) };
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for this call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    let entry = format!("{} ({})", text.trim(), error_name(code));
    if let Ok(mut errors) = shared.errors.lock() {
        errors.push(entry);
    }
}

/// `RTCMemoryMonitorFunction`: counts the device's bytes; never refuses.
unsafe extern "C" fn on_memory(user_ptr: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: as in `on_error`, `user_ptr` is the live boxed `DeviceShared`.
    let shared = unsafe { &*(user_ptr as *const DeviceShared) };
    let now = shared.bytes.fetch_add(bytes, Ordering::Relaxed) + bytes;
    shared.peak.fetch_max(now, Ordering::Relaxed);
    true
}

/// Owns the `RTCDevice` handle and its callback state.
pub(super) struct DeviceInner {
    pub(super) raw: sys::RTCDevice,
    shared: Box<DeviceShared>,
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` came from `rtcNewDevice` and is released exactly once;
        // every scene and geometry holds an `Arc<DeviceInner>`, so none outlives it.
        unsafe { sys::rtcReleaseDevice(self.raw) };
    }
}

// SAFETY: Embree devices may be used from any thread (its API is thread-safe
// for distinct objects, and the callbacks' shared state is a Mutex/atomics).
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send`; `&DeviceInner` only exposes thread-safe calls.
unsafe impl Sync for DeviceInner {}

impl DeviceInner {
    /// Reads the device error and the queued callback messages.
    pub(super) fn check(&self, what: &str) -> Result<(), AccelError> {
        // SAFETY: `raw` is a live device.
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        let messages: Vec<String> = self
            .shared
            .errors
            .lock()
            .map(|mut e| std::mem::take(&mut *e))
            .unwrap_or_default();
        if code == sys::RTC_ERROR_NONE && messages.is_empty() {
            return Ok(());
        }
        let detail = if messages.is_empty() {
            error_name(code).to_string()
        } else {
            messages.join("; ")
        };
        Err(AccelError::Embree(format!("{what}: {detail}")))
    }
}

/// An Embree device (`RTCDevice`): owns the handle, releases it when the last
/// scene or geometry made from it is gone. Not `Clone`.
pub struct Device {
    pub(super) inner: Arc<DeviceInner>,
}

impl Device {
    /// Creates a device. `config` is Embree's configuration string (e.g.
    /// `"threads=2"`); `None` takes the defaults. An invalid configuration is
    /// an [`AccelError::Embree`].
    pub fn new(config: Option<&str>) -> Result<Self, AccelError> {
        let config_c = match config {
            Some(c) => Some(
                CString::new(c).map_err(|_| AccelError::Embree(format!("device config {c:?} contains a NUL byte")))?,
            ),
            None => None,
        };
        let ptr = config_c.as_ref().map_or(std::ptr::null(), |c| c.as_ptr());
        // SAFETY: `ptr` is null or a NUL-terminated string alive for the call.
        let raw = unsafe { sys::rtcNewDevice(ptr) };
        if raw.is_null() {
            // SAFETY: with a null device, rtcGetDeviceError reads the
            // thread-local error of the failed rtcNewDevice.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(AccelError::Embree(format!(
                "rtcNewDevice({:?}) failed: {}",
                config.unwrap_or(""),
                error_name(code)
            )));
        }
        let shared = Box::new(DeviceShared::default());
        let user_ptr = &*shared as *const DeviceShared as *mut c_void;
        // SAFETY: `raw` is live; `user_ptr` points into a Box that lives in
        // `DeviceInner` until after `rtcReleaseDevice`, so the callbacks never
        // see a dangling pointer.
        unsafe {
            sys::rtcSetDeviceErrorFunction(raw, Some(on_error), user_ptr);
            sys::rtcSetDeviceMemoryMonitorFunction(raw, Some(on_memory), user_ptr);
        }
        let device = Self {
            inner: Arc::new(DeviceInner { raw, shared }),
        };
        device.check("rtcNewDevice")?;
        Ok(device)
    }

    /// `RTC_DEVICE_PROPERTY_VERSION` (e.g. 40400).
    pub fn version_number(&self) -> i64 {
        // SAFETY: live device; reading a property has no other precondition.
        unsafe { sys::rtcGetDeviceProperty(self.inner.raw, sys::RTC_DEVICE_PROPERTY_VERSION) as i64 }
    }

    /// Turns a pending device error (code or callback message) into an error
    /// naming `what` was being done.
    pub fn check(&self, what: &str) -> Result<(), AccelError> {
        self.inner.check(what)
    }

    /// Bytes Embree currently holds for this device, and the peak
    /// (from the memory-monitor callback).
    pub fn memory_bytes(&self) -> (usize, usize) {
        let now = self.inner.shared.bytes.load(Ordering::Relaxed).max(0) as usize;
        let peak = self.inner.shared.peak.load(Ordering::Relaxed).max(0) as usize;
        (now, peak)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn version_is_embree_4() {
        let device = Device::new(None).unwrap();
        let v = device.version_number();
        assert!((40000..50000).contains(&v), "{v}");
        assert!(version().starts_with("4."), "{}", version());
        assert!(!source().is_empty());
    }

    #[test]
    fn bad_device_config_is_an_error() {
        let err = Device::new(Some("verbose=abc"))
            .err()
            .expect("Embree rejects verbose=abc");
        assert!(err.to_string().contains("verbose=abc"), "{err}");
        assert!(Device::new(Some("threads=1")).is_ok());
    }
}
