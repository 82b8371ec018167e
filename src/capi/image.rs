//! Image handles: size, channel names, planar float pixels, EXR/PNG output, free.
//!
//! Pixels are planar: one `width * height` float plane per channel, row-major, top row first,
//! owned by the image and valid until `ct_image_free`.

use std::ffi::c_char;
use std::path::Path;

use crate::film::{self, ExrAttributes};

use super::errors::{guard, CapiError, CtStatus};
use super::handles::{self, CtImage, ImageObject};
use super::{c_path, c_str, require_out, write_out};

fn channel(image: &ImageObject, index: u32) -> Result<usize, CapiError> {
    let count = image.channel_names.len();
    if (index as usize) < count {
        Ok(index as usize)
    } else {
        Err(CapiError::invalid(format!(
            "channel index {index} is out of range (the image has {count} channels)"
        )))
    }
}

/// The image's width and height in pixels (either out-pointer may be NULL).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// Non-NULL out-pointers are writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_size(
    image: CtImage,
    out_width: *mut u32,
    out_height: *mut u32,
) -> CtStatus {
    guard(|| {
        let object = handles::image(image)?;
        if !out_width.is_null() {
            unsafe { out_width.write(object.film.width()) };
        }
        if !out_height.is_null() {
            unsafe { out_height.write(object.film.height()) };
        }
        Ok(CtStatus::CT_OK)
    })
}

/// Number of channels (R G B A Z N.X N.Y N.Z albedo.R albedo.G albedo.B uv.U uv.V, plus the
/// AOVs asked for).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_count` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_channel_count(image: CtImage, out_count: *mut u32) -> CtStatus {
    guard(|| {
        require_out(out_count, "out_count")?;
        let object = handles::image(image)?;
        let count = object.channel_names.len() as u32;
        unsafe { write_out(out_count, count, "out_count") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// The name of channel `index` (e.g. "R", "albedo.G"; owned by the image, valid until
/// `ct_image_free`).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_name` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_channel_name(
    image: CtImage,
    index: u32,
    out_name: *mut *const c_char,
) -> CtStatus {
    guard(|| {
        require_out(out_name, "out_name")?;
        let object = handles::image(image)?;
        let c = channel(&object, index)?;
        unsafe { write_out(out_name, object.channel_names[c].as_ptr(), "out_name") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// The index of the channel called `name`; `CT_ERROR_INVALID_ARGUMENT` if there is none.
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `name` is NUL-terminated; `out_index` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_find_channel(
    image: CtImage,
    name: *const c_char,
    out_index: *mut u32,
) -> CtStatus {
    guard(|| {
        require_out(out_index, "out_index")?;
        let object = handles::image(image)?;
        let name = unsafe { c_str(name, "name") }?;
        let index = object
            .channel_names
            .iter()
            .position(|n| n.to_bytes() == name.as_bytes())
            .ok_or_else(|| CapiError::invalid(format!("the image has no channel '{name}'")))?;
        unsafe { write_out(out_index, index as u32, "out_index") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// A pointer to channel `index`'s plane: `width * height` floats, row-major, top row first,
/// owned by the image and valid (read-only) until `ct_image_free`. `out_count` (may be NULL)
/// receives `width * height`.
///
/// Thread safety: any thread, concurrently with any other call; the pixels never change.
///
/// # Safety
/// `out_pixels` is writable; `out_count` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_channel_pixels(
    image: CtImage,
    index: u32,
    out_pixels: *mut *const f32,
    out_count: *mut usize,
) -> CtStatus {
    guard(|| {
        require_out(out_pixels, "out_pixels")?;
        let object = handles::image(image)?;
        let c = channel(&object, index)?;
        let name = object.channel_names[c].to_str().unwrap_or_default();
        let plane = object.film.channel(name).ok_or_else(|| {
            CapiError::new(
                CtStatus::CT_ERROR_INTERNAL,
                format!("channel '{name}' has no plane"),
            )
        })?;
        unsafe { write_out(out_pixels, plane.as_ptr(), "out_pixels") }?;
        if !out_count.is_null() {
            unsafe { out_count.write(plane.len()) };
        }
        Ok(CtStatus::CT_OK)
    })
}

/// Refuses a `path` whose extension is not `extension` (any case), so that a writer never puts
/// its format into a file named for another, as `conetrace render` refuses `-o x.png`.
fn require_extension(path: &Path, extension: &str, writer: &str) -> Result<(), CapiError> {
    let matches = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(extension));
    if matches {
        Ok(())
    } else {
        Err(CapiError::invalid(format!(
            "{}: {writer} writes a .{extension} file; the path must end in .{extension}",
            path.display()
        )))
    }
}

/// 1 when every tile was rendered, 0 for the partial image of a cancelled render.
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_complete` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_image_is_complete(image: CtImage, out_complete: *mut i32) -> CtStatus {
    guard(|| {
        require_out(out_complete, "out_complete")?;
        let object = handles::image(image)?;
        unsafe { write_out(out_complete, object.complete as i32, "out_complete") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// Writes every channel as 32-bit float OpenEXR (atomically: a failure never leaves a partial
/// file). A partial image is marked with the header attribute `conetrace.incomplete`. A path
/// that does not end in `.exr` (any case) is `CT_ERROR_INVALID_ARGUMENT`, and nothing is
/// written.
///
/// Thread safety: any thread, concurrently with any other call (different paths).
///
/// # Safety
/// `path` is NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn ct_image_write_exr(image: CtImage, path: *const c_char) -> CtStatus {
    guard(|| {
        let object = handles::image(image)?;
        let path = unsafe { c_path(path, "path") }?;
        require_extension(&path, "exr", "ct_image_write_exr")?;
        let attributes = ExrAttributes {
            software: Some(format!("conetrace {}", env!("CARGO_PKG_VERSION"))),
            incomplete: !object.complete,
            finished_tiles: Some(object.finished_tiles),
            world_to_camera: object.world_to_camera,
            world_to_ndc: object.world_to_ndc,
            ..ExrAttributes::default()
        };
        film::write_exr(&object.film, &path, &attributes)
            .map_err(|e| CapiError::new(CtStatus::CT_ERROR_IO, e.to_string()))?;
        Ok(CtStatus::CT_OK)
    })
}

/// Writes the colour as 8-bit sRGB PNG with the scene's tone mapping and exposure (atomically).
/// A path that does not end in `.png` (any case) is `CT_ERROR_INVALID_ARGUMENT`, and nothing
/// is written.
///
/// Thread safety: any thread, concurrently with any other call (different paths).
///
/// # Safety
/// `path` is NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn ct_image_write_png(image: CtImage, path: *const c_char) -> CtStatus {
    guard(|| {
        let object = handles::image(image)?;
        let path = unsafe { c_path(path, "path") }?;
        require_extension(&path, "png", "ct_image_write_png")?;
        film::write_png(&object.film, &path, object.tonemap, object.exposure)
            .map_err(|e| CapiError::new(CtStatus::CT_ERROR_IO, e.to_string()))?;
        Ok(CtStatus::CT_OK)
    })
}

/// Frees an image; its channel names and pixel pointers become invalid. The null handle is a
/// no-op (`CT_OK`); a freed or unknown handle gives `CT_ERROR_INVALID_HANDLE`.
///
/// Thread safety: any thread, but no other thread may still read its pixels or names.
#[no_mangle]
pub extern "C" fn ct_image_free(image: CtImage) -> CtStatus {
    guard(|| {
        handles::remove(image.id, "image")?;
        Ok(CtStatus::CT_OK)
    })
}
