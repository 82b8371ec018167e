//! Status codes, the thread-local error message, and the guard every entry point runs in so
//! that no Rust panic crosses the C boundary.

use std::cell::RefCell;
use std::ffi::{c_char, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// What a `ct_` function reports. `CT_OK` is success; `CT_CANCELLED` means the render was
/// stopped by the progress callback and still produced a (partial) image; every other value is
/// an error. Every value but `CT_OK` leaves a message that `ct_last_error_message` returns on
/// the same thread.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CtStatus {
    /// Success.
    CT_OK = 0,
    /// The progress callback asked to stop; the image handle is valid and partial, and the
    /// message says how many tiles were finished.
    CT_CANCELLED = 1,
    /// A required pointer argument was NULL.
    CT_ERROR_NULL_POINTER = 2,
    /// A handle is null, was freed already, never existed, or is of another kind.
    CT_ERROR_INVALID_HANDLE = 3,
    /// An argument is out of range (unknown enum value, zero size, bad UTF-8, index too large).
    CT_ERROR_INVALID_ARGUMENT = 4,
    /// An options struct's `struct_size` is not one this library knows.
    CT_ERROR_STRUCT_SIZE = 5,
    /// A scene file or string could not be read, parsed or validated.
    CT_ERROR_SCENE = 6,
    /// A texture file could not be read or decoded.
    CT_ERROR_TEXTURE = 7,
    /// The scene could not be prepared for rendering (e.g. a texture it names is unreadable).
    CT_ERROR_RENDER = 8,
    /// An output file could not be written.
    CT_ERROR_IO = 9,
    /// The texture callback returned a non-zero code; the render was stopped.
    CT_ERROR_CALLBACK = 10,
    /// A bug inside the library (a caught Rust panic); the call had no effect on handles.
    CT_ERROR_INTERNAL = 11,
    /// The render's estimated memory (`ct_render_memory_estimate`) exceeds the options'
    /// `max_memory`, or the memory the system reports available; nothing large was allocated.
    CT_ERROR_OUT_OF_MEMORY = 12,
}

/// An error on its way out of an entry point: a status and a message for the caller.
#[derive(Debug)]
pub(crate) struct CapiError {
    pub status: CtStatus,
    pub message: String,
}

impl CapiError {
    pub fn new(status: CtStatus, message: impl Into<String>) -> CapiError {
        CapiError {
            status,
            message: message.into(),
        }
    }

    pub fn null(argument: &str) -> CapiError {
        CapiError::new(
            CtStatus::CT_ERROR_NULL_POINTER,
            format!("{argument} is NULL"),
        )
    }

    pub fn invalid(message: impl Into<String>) -> CapiError {
        CapiError::new(CtStatus::CT_ERROR_INVALID_ARGUMENT, message)
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    // Interior NULs cannot be represented in a C string: show them as spaces.
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|cell| *cell.borrow_mut() = text);
}

/// Runs an entry point's body: returns its status, records the message of an error, and turns a
/// panic into `CT_ERROR_INTERNAL`.
///
/// A body returns every status other than `CT_OK` as an `Err` with its message, `CT_CANCELLED`
/// included (its partial image is already in the caller's hands then): the message is what
/// `ct_last_error_message` promises for every status but `CT_OK`, and one left over from an
/// earlier call would describe another failure.
pub(crate) fn guard(body: impl FnOnce() -> Result<CtStatus, CapiError>) -> CtStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(status)) => {
            debug_assert_eq!(status, CtStatus::CT_OK, "a status without its message");
            status
        }
        Ok(Err(error)) => {
            set_last_error(&error.message);
            error.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            set_last_error(&format!(
                "internal error in conetrace (caught panic): {what}"
            ));
            CtStatus::CT_ERROR_INTERNAL
        }
    }
}

/// The message of the last `ct_` call on the calling thread that returned a status other than
/// `CT_OK` (an error, or `CT_CANCELLED`); "" if there was none yet.
///
/// Thread safety: per thread; the pointer stays valid until the next such call on this
/// thread. Never NULL.
#[no_mangle]
pub extern "C" fn ct_last_error_message() -> *const c_char {
    let result = catch_unwind(|| LAST_ERROR.with(|cell| cell.borrow().as_ptr()));
    result.unwrap_or(c"internal error reading the last error message".as_ptr())
}

/// A static, human-readable name for a status code (e.g. "CT_ERROR_SCENE"); never NULL.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn ct_status_name(status: i32) -> *const c_char {
    let name = match status {
        0 => c"CT_OK",
        1 => c"CT_CANCELLED",
        2 => c"CT_ERROR_NULL_POINTER",
        3 => c"CT_ERROR_INVALID_HANDLE",
        4 => c"CT_ERROR_INVALID_ARGUMENT",
        5 => c"CT_ERROR_STRUCT_SIZE",
        6 => c"CT_ERROR_SCENE",
        7 => c"CT_ERROR_TEXTURE",
        8 => c"CT_ERROR_RENDER",
        9 => c"CT_ERROR_IO",
        10 => c"CT_ERROR_CALLBACK",
        11 => c"CT_ERROR_INTERNAL",
        12 => c"CT_ERROR_OUT_OF_MEMORY",
        _ => c"unknown status",
    };
    name.as_ptr()
}
