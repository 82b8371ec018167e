//! Per-trace options and the extended intersect context that carries them to filter callbacks.
//!
//! Embree hands the context pointer given to a trace call to every filter callback it runs.
//! [`TraceContext`] begins with `RTCIntersectContext` (so Embree can use it as one) and adds
//! the caller's per-ray [`RayPayload`]s and a record of filter panics.

use std::cell::{Cell, RefCell};

use super::error::EmbreeError;
use super::ffi;

/// How coherent the rays of one trace call are (Embree's intersect-context flag).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coherence {
    /// Camera rays of a pixel tile: similar origins and directions.
    Coherent,
    /// Secondary rays after a bounce: unrelated directions.
    Incoherent,
}

/// Per-ray data a filter callback may need besides the ray itself: the ray cone's footprint
/// (seed 002) at the origin and its spread angle, so alpha tests can filter the mask texture.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct RayPayload {
    /// Width of the ray cone at the ray origin (world units).
    pub cone_width: f32,
    /// Spread angle of the cone (radians), so width at distance t is about
    /// `cone_width + t * cone_spread`.
    pub cone_spread: f32,
}

/// Options of one trace call.
#[derive(Clone, Copy, Debug)]
pub struct TraceOptions<'a> {
    /// Embree's coherence hint for the rays of this call.
    pub coherence: Coherence,
    /// Per-ray payloads, indexed by lane (packets), 0 (single rays) or stream index
    /// (streams). Rays without an entry get `RayPayload::default()`.
    pub payload: Option<&'a [RayPayload]>,
}

impl<'a> TraceOptions<'a> {
    /// Coherent rays (camera tiles), no payload.
    pub fn coherent() -> TraceOptions<'static> {
        TraceOptions {
            coherence: Coherence::Coherent,
            payload: None,
        }
    }

    /// Incoherent rays (secondary bounces), no payload.
    pub fn incoherent() -> TraceOptions<'static> {
        TraceOptions {
            coherence: Coherence::Incoherent,
            payload: None,
        }
    }

    /// The same options with per-ray payloads for filter callbacks.
    pub fn with_payload<'b>(self, payload: &'b [RayPayload]) -> TraceOptions<'b> {
        TraceOptions {
            coherence: self.coherence,
            payload: Some(payload),
        }
    }
}

/// What went wrong inside filter callbacks during one trace.
#[derive(Default)]
pub(crate) struct FilterFailure {
    pub geom_id: u32,
    pub message: String,
}

/// The context passed to Embree: `RTCIntersectContext` first, so a pointer to this struct is
/// a valid `RTCIntersectContext*`, and filter callbacks can cast back.
#[repr(C)]
pub(crate) struct TraceContext<'a> {
    base: ffi::RTCIntersectContext,
    payload: &'a [RayPayload],
    failure: RefCell<Option<FilterFailure>>,
    panics: Cell<u32>,
}

impl<'a> TraceContext<'a> {
    #[inline]
    pub fn new(options: &TraceOptions<'a>) -> TraceContext<'a> {
        let mut base = ffi::RTCIntersectContext::default();
        // SAFETY: the shim only writes the fields of the struct it is given, which is a live
        // local of the type bindgen generated from the same header.
        unsafe { ffi::conetrace_rtc_init_intersect_context(&mut base) };
        base.flags = match options.coherence {
            Coherence::Coherent => ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
            Coherence::Incoherent => ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
        };
        TraceContext {
            base,
            payload: options.payload.unwrap_or(&[]),
            failure: RefCell::new(None),
            panics: Cell::new(0),
        }
    }

    /// The pointer handed to Embree. Embree only reads `base` and passes the pointer on to
    /// filter callbacks, which use it through a shared reference.
    #[inline]
    pub fn as_raw(&mut self) -> *mut ffi::RTCIntersectContext {
        self as *mut TraceContext as *mut ffi::RTCIntersectContext
    }

    /// The payload of the ray with this id (lane or stream index).
    #[inline]
    pub fn payload(&self, id: u32) -> RayPayload {
        self.payload.get(id as usize).copied().unwrap_or_default()
    }

    /// Records that a filter callback of `geom_id` panicked with `message`.
    pub fn record_panic(&self, geom_id: u32, message: String) {
        self.panics.set(self.panics.get().saturating_add(1));
        if let Ok(mut slot) = self.failure.try_borrow_mut() {
            if slot.is_none() {
                *slot = Some(FilterFailure { geom_id, message });
            }
        }
    }

    /// `Err` if any filter callback panicked during the trace.
    #[inline]
    pub fn finish(self) -> Result<(), EmbreeError> {
        let count = self.panics.get();
        if count == 0 {
            return Ok(());
        }
        let failure = self.failure.into_inner().unwrap_or_default();
        Err(EmbreeError::FilterPanicked {
            geom_id: failure.geom_id,
            count,
            message: failure.message,
        })
    }
}
