//! Errors of the Embree layer: Embree's own error codes and messages, invalid geometry input,
//! and failures inside Rust filter callbacks reported by the tracing call that hit them.

use thiserror::Error;

use super::ffi;

/// Everything that can go wrong in `crate::embree`.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EmbreeError {
    /// `rtcNewDevice` failed. Embree 3 keeps no message for a device that was never created,
    /// so this carries Embree's error code and the configuration that was rejected.
    #[error("embree: rtcNewDevice(\"{config}\") failed with {code}: {message}")]
    DeviceCreation {
        config: String,
        code: &'static str,
        message: String,
    },
    /// An Embree call reported an error through the device's error callback.
    #[error("embree: {operation} failed with {code}: {message}")]
    Embree {
        operation: &'static str,
        code: &'static str,
        message: String,
    },
    /// The device configuration string contains a NUL byte.
    #[error("embree: device configuration {config:?} contains a NUL byte")]
    InvalidConfig { config: String },
    /// A triangle refers to a vertex that does not exist.
    #[error("embree: triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    /// A geometry with no primitives (or more than Embree can index) was added.
    #[error("embree: {kind} has {count} primitives; Embree needs between 1 and 2^32-1")]
    BadPrimitiveCount { kind: &'static str, count: usize },
    /// A sphere with a negative or non-finite radius or centre.
    #[error("embree: sphere {index} has an invalid centre or radius ({radius})")]
    InvalidSphere { index: usize, radius: f32 },
    /// A geometry id that this scene builder did not hand out.
    #[error("embree: no geometry with id {geom_id} in this scene")]
    UnknownGeometry { geom_id: u32 },
    /// A Rust filter callback panicked during a trace. The candidate hits it was asked about
    /// were rejected (deterministically), so the trace results are complete but may miss
    /// surfaces of that geometry.
    #[error("embree: alpha filter of geometry {geom_id} panicked {count} time(s) during tracing (hits rejected): {message}")]
    FilterPanicked {
        geom_id: u32,
        count: u32,
        message: String,
    },
}

/// Embree's name for an error code.
pub(crate) fn error_code_name(code: ffi::RTCError) -> &'static str {
    match code {
        ffi::RTC_ERROR_NONE => "RTC_ERROR_NONE",
        ffi::RTC_ERROR_UNKNOWN => "RTC_ERROR_UNKNOWN",
        ffi::RTC_ERROR_INVALID_ARGUMENT => "RTC_ERROR_INVALID_ARGUMENT",
        ffi::RTC_ERROR_INVALID_OPERATION => "RTC_ERROR_INVALID_OPERATION",
        ffi::RTC_ERROR_OUT_OF_MEMORY => "RTC_ERROR_OUT_OF_MEMORY",
        ffi::RTC_ERROR_UNSUPPORTED_CPU => "RTC_ERROR_UNSUPPORTED_CPU",
        ffi::RTC_ERROR_CANCELLED => "RTC_ERROR_CANCELLED",
        _ => "an unknown Embree error code",
    }
}
