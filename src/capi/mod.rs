//! The C API: `libconetrace.so` / `libconetrace.a` and `include/conetrace.h`.
//!
//! Every exported function has the `ct_` prefix, returns a [`CtStatus`] (or a value that cannot
//! fail), runs inside [`errors::guard`] so no Rust panic crosses the boundary, checks every
//! pointer for NULL and every handle against the registry in [`handles`] before use, and
//! leaves its message for `ct_last_error_message` on failure. Option structs start with
//! `struct_size` so they can grow without breaking old callers.
//!
//! The header is generated from these declarations by cbindgen (`cbindgen.toml`);
//! `tests/c_api.rs` fails when the committed header differs from freshly generated text.
//! `docs/c-api.md` is the user's guide.
//!
//! This module must not contain rendering logic: it converts, validates and forwards to
//! [`crate::scene::load`], [`crate::render`], [`crate::film`] and [`crate::texture`].

pub mod callbacks;
pub mod errors;
pub mod handles;
pub mod image;
pub mod render;
pub mod scene;
pub mod texture;

use std::ffi::{c_char, CStr};
use std::os::unix::ffi::OsStrExt;
use std::path::PathBuf;

pub use callbacks::{CtProgressFn, CtTextureFn, CtTextureRequest};
pub use errors::{ct_last_error_message, ct_status_name, CtStatus};
pub use handles::{CtImage, CtScene, CtTexture};
pub use image::*;
pub use render::*;
pub use scene::*;
pub use texture::*;

use errors::CapiError;

/// The version of the C interface (bumped when a function or struct changes incompatibly).
pub const CT_ABI_VERSION: u32 = 2;

/// The library version, e.g. "0.1.0" (static string, never NULL).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn ct_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// The C interface version this library implements (`CT_ABI_VERSION` of its header).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn ct_abi_version() -> u32 {
    CT_ABI_VERSION
}

/// A NUL-terminated UTF-8 argument as `&str`.
///
/// # Safety
/// `ptr` is NULL or points to a NUL-terminated string that outlives the call.
pub(crate) unsafe fn c_str<'a>(ptr: *const c_char, argument: &str) -> Result<&'a str, CapiError> {
    if ptr.is_null() {
        return Err(CapiError::null(argument));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(ptr) }
        .to_str()
        .map_err(|_| CapiError::invalid(format!("{argument} is not valid UTF-8")))
}

/// A NUL-terminated file path argument (any bytes but NUL, as on Unix).
///
/// # Safety
/// As [`c_str`].
pub(crate) unsafe fn c_path(ptr: *const c_char, argument: &str) -> Result<PathBuf, CapiError> {
    if ptr.is_null() {
        return Err(CapiError::null(argument));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    let bytes = unsafe { CStr::from_ptr(ptr) }.to_bytes();
    if bytes.is_empty() {
        return Err(CapiError::invalid(format!("{argument} is an empty path")));
    }
    Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
}

/// Writes `value` through an out-pointer after checking it for NULL.
///
/// # Safety
/// `out` is NULL or valid for a write of `T`.
pub(crate) unsafe fn write_out<T>(out: *mut T, value: T, argument: &str) -> Result<(), CapiError> {
    if out.is_null() {
        return Err(CapiError::null(argument));
    }
    // SAFETY: non-null and writable by the caller's contract.
    unsafe { out.write(value) };
    Ok(())
}

/// [`read_sized`] for an options struct that has grown by appending fields: also accepts the
/// sizes of `earlier_sizes` (each a prefix of today's struct, as written by a caller built
/// against an older header), whose missing trailing fields keep their values in `defaults`.
///
/// # Safety
/// `ptr` is NULL or points to at least `struct_size` readable bytes (its first field).
pub(crate) unsafe fn read_sized_or_earlier<T: Copy>(
    ptr: *const T,
    argument: &str,
    earlier_sizes: &[usize],
    defaults: T,
) -> Result<T, CapiError> {
    if ptr.is_null() {
        return Err(CapiError::null(argument));
    }
    // SAFETY: as in `read_sized`, the first field is the u32 `struct_size`.
    let size = unsafe { ptr.cast::<u32>().read_unaligned() } as usize;
    if size == std::mem::size_of::<T>() || !earlier_sizes.contains(&size) {
        // SAFETY: the caller's contract; `read_sized` checks the size again.
        return unsafe { read_sized(ptr, argument) };
    }
    let mut value = defaults;
    // SAFETY: the caller says `size` bytes are readable; `size` is an earlier size, smaller
    // than `T`, so it fits in `value`.
    unsafe {
        std::ptr::copy_nonoverlapping(
            ptr.cast::<u8>(),
            (&mut value as *mut T).cast::<u8>(),
            size.min(std::mem::size_of::<T>()),
        )
    };
    Ok(value)
}

/// Checks an out-pointer for NULL before any work is done.
pub(crate) fn require_out<T>(out: *mut T, argument: &str) -> Result<(), CapiError> {
    if out.is_null() {
        Err(CapiError::null(argument))
    } else {
        Ok(())
    }
}

/// Reads an options struct that starts with `u32 struct_size`, accepting only the sizes this
/// library knows (today: exactly `size_of::<T>()`).
///
/// # Safety
/// `ptr` is NULL or points to at least `struct_size` readable bytes (its first field).
pub(crate) unsafe fn read_sized<T: Copy>(ptr: *const T, argument: &str) -> Result<T, CapiError> {
    if ptr.is_null() {
        return Err(CapiError::null(argument));
    }
    // SAFETY: every options struct starts with a u32 `struct_size`; reading it is valid for
    // any caller that followed the contract, whatever version of the struct it has.
    let size = unsafe { ptr.cast::<u32>().read_unaligned() };
    let expected = std::mem::size_of::<T>();
    if size as usize != expected {
        return Err(CapiError::new(
            CtStatus::CT_ERROR_STRUCT_SIZE,
            format!(
                "{argument}: struct_size is {size}, this library expects {expected} \
                 (set it to sizeof the struct, or call the _init function)"
            ),
        ));
    }
    // SAFETY: the caller says the struct is `size` bytes, which equals size_of::<T>().
    Ok(unsafe { ptr.read_unaligned() })
}
