//! The Embree device: creation from a configuration string (with the worker-thread count
//! Embree's BVH builders may use), Embree's error callback turned into `Result`s carrying
//! Embree's message, device properties (native packet widths, ray-stream support) and memory
//! accounting.
//!
//! A [`Device`] is a cheap handle (`Arc`); scenes keep a clone, so the device outlives every
//! scene built on it. The traversal paths a handle uses (packet width, streams) can be
//! narrowed with [`Device::with_traversal_limits`], which is how the single-ray fallbacks of
//! devices built without packet or stream support are exercised on any machine.

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex};

use super::error::{error_code_name, EmbreeError};
use super::ffi;

/// What Embree's callbacks write into; boxed so its address stays fixed while Embree holds it.
struct CallbackState {
    /// The most recent error message Embree reported (code, text).
    last_error: Mutex<Option<(ffi::RTCError, String)>>,
    /// Bytes Embree currently has allocated, as reported to the memory monitor.
    allocated_bytes: AtomicI64,
}

struct DeviceInner {
    raw: ffi::RTCDevice,
    /// Read by Embree through the user pointer of the error and memory callbacks; dropped
    /// only after `rtcReleaseDevice` (see `Drop`).
    callbacks: Box<CallbackState>,
    /// The configuration string the device was created with.
    config: String,
}

// SAFETY: an RTCDevice may be used from any thread; Embree synchronises its own state, and
// the callback state is a Mutex and an atomic.
unsafe impl Send for DeviceInner {}
// SAFETY: as above; `&DeviceInner` only exposes Embree calls that are thread-safe
// (object creation, property queries, error queries).
unsafe impl Sync for DeviceInner {}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` came from a successful rtcNewDevice and this is the only release of
        // our reference. Every scene holds a `Device` clone, so no scene outlives this.
        unsafe { ffi::rtcReleaseDevice(self.raw) };
    }
}

/// An Embree device (a handle; clones share the device).
#[derive(Clone)]
pub struct Device {
    inner: Arc<DeviceInner>,
    /// The widest packet traces through this handle use: the device's native width, or
    /// less after [`Device::with_traversal_limits`]; 1 means single rays only.
    packet_width: usize,
    /// Whether traces through this handle use Embree's ray streams (`rtcIntersect1M`).
    stream_supported: bool,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device")
            .field("packet_width", &self.packet_width)
            .field("stream_supported", &self.stream_supported)
            .finish()
    }
}

/// The Embree configuration string that limits a device to `threads` worker threads
/// (Embree's `threads=N` option), so BVH builds use no more threads than the render's
/// worker pool.
pub fn thread_config(threads: usize) -> String {
    format!("threads={}", threads.max(1))
}

/// Embree's error callback: records the message for the failing call to return.
unsafe extern "C" fn record_error(
    user_ptr: *mut c_void,
    code: ffi::RTCError,
    message: *const c_char,
) {
    // No panic may unwind into Embree.
    let _ = std::panic::catch_unwind(|| {
        if user_ptr.is_null() {
            return;
        }
        // SAFETY: `user_ptr` is the `Box<CallbackState>` registered in `Device::with_config`,
        // alive until after rtcReleaseDevice.
        let state = unsafe { &*(user_ptr as *const CallbackState) };
        let text = if message.is_null() {
            String::from("(Embree gave no message)")
        } else {
            // SAFETY: Embree passes a NUL-terminated string valid for this call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        let mut slot = state.last_error.lock().unwrap_or_else(|p| p.into_inner());
        *slot = Some((code, text));
    });
}

/// Embree's memory monitor: keeps a running total of allocated bytes; never vetoes.
unsafe extern "C" fn track_memory(user_ptr: *mut c_void, bytes: isize, _post: bool) -> bool {
    if !user_ptr.is_null() {
        // SAFETY: as in `record_error`, the pointer is the device's live `CallbackState`.
        let state = unsafe { &*(user_ptr as *const CallbackState) };
        state
            .allocated_bytes
            .fetch_add(bytes as i64, Ordering::Relaxed);
    }
    true
}

impl Device {
    /// Creates a device with Embree's default configuration.
    pub fn new() -> Result<Device, EmbreeError> {
        Device::with_config("")
    }

    /// Creates a device whose BVH builds use at most `threads` threads ([`thread_config`]).
    pub fn with_threads(threads: usize) -> Result<Device, EmbreeError> {
        Device::with_config(&thread_config(threads))
    }

    /// Creates a device from an Embree configuration string (e.g. `"threads=2,isa=avx2"`).
    pub fn with_config(config: &str) -> Result<Device, EmbreeError> {
        let c_config = CString::new(config).map_err(|_| EmbreeError::InvalidConfig {
            config: config.to_owned(),
        })?;
        // SAFETY: `c_config` is a valid NUL-terminated string for the duration of the call.
        let raw = unsafe { ffi::rtcNewDevice(c_config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: with a null device, rtcGetDeviceError reads the thread-local code that
            // the failed rtcNewDevice stored.
            let code = unsafe { ffi::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(EmbreeError::DeviceCreation {
                config: config.to_owned(),
                code: error_code_name(code),
                message: String::from(
                    "Embree rejected the configuration (Embree 3 keeps no message text for a device that failed to start)",
                ),
            });
        }
        let callbacks = Box::new(CallbackState {
            last_error: Mutex::new(None),
            allocated_bytes: AtomicI64::new(0),
        });
        let user_ptr = &*callbacks as *const CallbackState as *mut c_void;
        // SAFETY: `raw` is a live device; `user_ptr` points into a Box that `DeviceInner` owns
        // and drops only after rtcReleaseDevice; both callbacks catch or cannot panic.
        unsafe {
            ffi::rtcSetDeviceErrorFunction(raw, Some(record_error), user_ptr);
            ffi::rtcSetDeviceMemoryMonitorFunction(raw, Some(track_memory), user_ptr);
        }
        let property = |p: ffi::RTCDeviceProperty| {
            // SAFETY: `raw` is live and `p` is one of Embree's readable property ids.
            unsafe { ffi::rtcGetDeviceProperty(raw, p) != 0 }
        };
        let packet_width = if property(ffi::RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) {
            16
        } else if property(ffi::RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) {
            8
        } else if property(ffi::RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) {
            4
        } else {
            1
        };
        let stream_supported = property(ffi::RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED);
        let device = Device {
            inner: Arc::new(DeviceInner {
                raw,
                callbacks,
                config: config.to_owned(),
            }),
            packet_width,
            stream_supported,
        };
        device.check("rtcNewDevice")?;
        Ok(device)
    }

    /// The widest packet (16, 8, 4, or 1 if none) this device traverses natively
    /// (`RTC_DEVICE_PROPERTY_NATIVE_RAY*_SUPPORTED`), or the limit set with
    /// [`Device::with_traversal_limits`]. Packet traces wider than this are split; with 1,
    /// every packet trace becomes single-ray traces.
    pub fn packet_width(&self) -> usize {
        self.packet_width
    }

    /// Whether ray streams (`rtcIntersect1M`) are used: the device was built with stream
    /// support and no limit switched them off. Without them, streams are traced ray by ray.
    pub fn stream_supported(&self) -> bool {
        self.stream_supported
    }

    /// A handle to the same device whose traces use packets at most `max_packet_width` wide
    /// (rounded down to 16, 8, 4 or 1) and streams only if `streams` is true (and the device
    /// supports them): the paths a device built without wide packets or streams takes.
    /// Limits only narrow what the device supports; scenes built on the returned handle
    /// trace with these limits.
    pub fn with_traversal_limits(&self, max_packet_width: usize, streams: bool) -> Device {
        let limit = match max_packet_width {
            16.. => 16,
            8..=15 => 8,
            4..=7 => 4,
            _ => 1,
        };
        Device {
            inner: Arc::clone(&self.inner),
            packet_width: self.packet_width.min(limit),
            stream_supported: self.stream_supported && streams,
        }
    }

    /// The configuration string the device was created with (e.g. `"threads=4"`).
    pub fn config(&self) -> &str {
        &self.inner.config
    }

    /// Bytes Embree currently holds for this device's scenes and geometries.
    pub fn memory_usage(&self) -> i64 {
        self.inner.callbacks.allocated_bytes.load(Ordering::Relaxed)
    }

    pub(crate) fn raw(&self) -> ffi::RTCDevice {
        self.inner.raw
    }

    /// Turns an error Embree recorded on this thread since the last check into `Err`,
    /// with the message from the error callback.
    pub(crate) fn check(&self, operation: &'static str) -> Result<(), EmbreeError> {
        // SAFETY: the device is live; rtcGetDeviceError returns and clears this thread's code.
        let code = unsafe { ffi::rtcGetDeviceError(self.inner.raw) };
        if code == ffi::RTC_ERROR_NONE {
            return Ok(());
        }
        let recorded = self
            .inner
            .callbacks
            .last_error
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        let message = match recorded {
            Some((_, text)) => text,
            None => String::from("(no message from Embree)"),
        };
        Err(EmbreeError::Embree {
            operation,
            code: error_code_name(code),
            message,
        })
    }

    /// Reads a device property by raw id; used by tests to provoke Embree errors.
    #[cfg(test)]
    pub(crate) fn raw_property(&self, property: u32) -> isize {
        // SAFETY: the device is live; an unknown id makes Embree report an error through
        // the callback, never undefined behaviour.
        unsafe { ffi::rtcGetDeviceProperty(self.inner.raw, property) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_device_reports_a_packet_width() {
        let device = Device::new().expect("default Embree device");
        assert!([1, 4, 8, 16].contains(&device.packet_width()));
    }

    #[test]
    fn embree_errors_carry_embree_message() {
        let device = Device::new().expect("default Embree device");
        assert_eq!(device.raw_property(9999), 0);
        let err = device.check("rtcGetDeviceProperty").unwrap_err();
        match &err {
            EmbreeError::Embree { code, message, .. } => {
                assert_eq!(*code, "RTC_ERROR_INVALID_ARGUMENT");
                assert!(message.contains("property"), "message was {message:?}");
            }
            other => panic!("unexpected error {other:?}"),
        }
        // The error was consumed: the next check succeeds.
        assert!(device.check("nothing").is_ok());
    }

    #[test]
    fn bad_config_is_an_error() {
        let err = Device::with_config("threads=abc").unwrap_err();
        let text = err.to_string();
        assert!(text.contains("threads=abc"), "{text}");
        assert!(text.contains("RTC_ERROR_"), "{text}");
        assert!(matches!(
            Device::with_config("a\0b"),
            Err(EmbreeError::InvalidConfig { .. })
        ));
    }

    #[test]
    fn thread_config_is_embree_threads_option() {
        assert_eq!(thread_config(3), "threads=3");
        // Zero threads would mean "all cores" to Embree; the pool never has fewer than one.
        assert_eq!(thread_config(0), "threads=1");
        let device = Device::with_threads(2).expect("a two-thread device");
        assert_eq!(device.config(), "threads=2");
        assert!([1, 4, 8, 16].contains(&device.packet_width()));
    }

    #[test]
    fn traversal_limits_only_narrow() {
        let device = Device::new().expect("default Embree device");
        let single = device.with_traversal_limits(1, false);
        assert_eq!(single.packet_width(), 1);
        assert!(!single.stream_supported());
        let four = device.with_traversal_limits(7, true);
        assert_eq!(four.packet_width(), 4.min(device.packet_width()));
        assert_eq!(four.stream_supported(), device.stream_supported());
        let wide = device.with_traversal_limits(64, true);
        assert_eq!(wide.packet_width(), device.packet_width());
    }

    #[test]
    fn sse_only_device_reports_four_wide_packets() {
        let device = Device::with_config("isa=sse4.2").expect("SSE4.2 device");
        assert_eq!(device.packet_width(), 4);
    }
}
