//! Texture handles: load a texture (with its mip pyramid) and filter batches of lookups with
//! the same filters as `conetrace sample-texture` and the renderer.

use std::ffi::c_char;
use std::sync::Arc;

use crate::texture::{ColorSpace, FilterOptions, Texture, TextureQuery};

use super::errors::{guard, CapiError, CtStatus};
use super::handles::{self, CtTexture, Object};
use super::render::{
    filter_from_code, max_aniso_checked, wrap_from_code, CT_FILTER_ANISO, CT_WRAP_PERIODIC,
};
use super::scene::{CT_COLOR_SPACE_LINEAR, CT_COLOR_SPACE_SRGB};
use super::{c_path, read_sized, require_out, write_out};

/// One lookup: coordinates (OpenImageIO convention) and derivatives along screen x and y.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CtTextureQuery {
    /// Horizontal coordinate, 0..1 across, growing to the right.
    pub s: f32,
    /// Vertical coordinate, 0..1 down, growing downwards.
    pub t: f32,
    /// ds/dx.
    pub dsdx: f32,
    /// dt/dx.
    pub dtdx: f32,
    /// ds/dy.
    pub dsdy: f32,
    /// dt/dy.
    pub dtdy: f32,
}

/// How `ct_texture_sample` filters. Fill it with `ct_sample_options_init`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CtSampleOptions {
    /// `sizeof(CtSampleOptions)`.
    pub struct_size: u32,
    /// `CT_FILTER_*` (default aniso).
    pub filter: u32,
    /// `CT_WRAP_*` along s (default periodic).
    pub wrap_s: u32,
    /// `CT_WRAP_*` along t (default periodic).
    pub wrap_t: u32,
    /// Anisotropy limit, >= 1 (default 16).
    pub max_aniso: f32,
}

/// Fills `*options` with the defaults; `struct_size` must be `sizeof(CtSampleOptions)`.
///
/// Thread safety: any thread.
///
/// # Safety
/// `options` points to at least `struct_size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn ct_sample_options_init(
    options: *mut CtSampleOptions,
    struct_size: usize,
) -> CtStatus {
    guard(|| {
        require_out(options, "options")?;
        let expected = std::mem::size_of::<CtSampleOptions>();
        if struct_size != expected {
            return Err(CapiError::new(
                CtStatus::CT_ERROR_STRUCT_SIZE,
                format!("options: struct_size is {struct_size}, this library expects {expected}"),
            ));
        }
        let defaults = CtSampleOptions {
            struct_size: expected as u32,
            filter: CT_FILTER_ANISO,
            wrap_s: CT_WRAP_PERIODIC,
            wrap_t: CT_WRAP_PERIODIC,
            max_aniso: 16.0,
        };
        unsafe { options.write_unaligned(defaults) };
        Ok(CtStatus::CT_OK)
    })
}

/// Loads a PNG, JPEG or OpenEXR texture and builds its mip pyramid (box filter, like
/// `maketx --filter box`; mip-mapped EXRs keep their levels). `color_space` is
/// `CT_COLOR_SPACE_SRGB` or `CT_COLOR_SPACE_LINEAR` (for 8-bit colour).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `path` is NUL-terminated; `out_texture` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_texture_load(
    path: *const c_char,
    color_space: u32,
    out_texture: *mut CtTexture,
) -> CtStatus {
    guard(|| {
        require_out(out_texture, "out_texture")?;
        unsafe { out_texture.write(CtTexture::default()) };
        let path = unsafe { c_path(path, "path") }?;
        let space = match color_space {
            CT_COLOR_SPACE_SRGB => ColorSpace::Srgb,
            CT_COLOR_SPACE_LINEAR => ColorSpace::Linear,
            other => {
                return Err(CapiError::invalid(format!(
                    "unknown colour space {other} (CT_COLOR_SPACE_*)"
                )))
            }
        };
        let texture = Texture::from_file(&path, space)
            .map_err(|e| CapiError::new(CtStatus::CT_ERROR_TEXTURE, e.to_string()))?;
        let handle = CtTexture {
            id: handles::insert(Object::Texture(Arc::new(texture))),
        };
        unsafe { write_out(out_texture, handle, "out_texture") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// The texture's width and height (level 0; either out-pointer may be NULL).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// Non-NULL out-pointers are writable.
#[no_mangle]
pub unsafe extern "C" fn ct_texture_size(
    texture: CtTexture,
    out_width: *mut u32,
    out_height: *mut u32,
) -> CtStatus {
    guard(|| {
        let texture = handles::texture(texture)?;
        if !out_width.is_null() {
            unsafe { out_width.write(texture.width()) };
        }
        if !out_height.is_null() {
            unsafe { out_height.write(texture.height()) };
        }
        Ok(CtStatus::CT_OK)
    })
}

/// Filters `count` lookups: `rgba_out[4*i .. 4*i+4]` receives the linear RGBA of `queries[i]`.
/// `options` may be NULL (defaults). A query whose `s` or `t` is NaN or infinite is refused
/// (`CT_ERROR_INVALID_ARGUMENT`, naming its index). A tile of a `.tx` read on demand that
/// cannot be read is `CT_ERROR_TEXTURE`, naming the file, the level and the tile. Nothing
/// is written on error.
///
/// Thread safety: any thread; any number of threads may sample the same texture at once.
///
/// # Safety
/// `queries` points to `count` queries and `rgba_out` to `4 * count` writable floats (both may
/// be NULL when `count` is 0); `options` is NULL or a valid `CtSampleOptions`.
#[no_mangle]
pub unsafe extern "C" fn ct_texture_sample(
    texture: CtTexture,
    options: *const CtSampleOptions,
    queries: *const CtTextureQuery,
    count: usize,
    rgba_out: *mut f32,
) -> CtStatus {
    guard(|| {
        let texture = handles::texture(texture)?;
        let filter = if options.is_null() {
            FilterOptions::default()
        } else {
            let o = unsafe { read_sized(options, "options") }?;
            FilterOptions {
                filter: filter_from_code(o.filter)?,
                wrap_s: wrap_from_code(o.wrap_s)?,
                wrap_t: wrap_from_code(o.wrap_t)?,
                max_aniso: max_aniso_checked(o.max_aniso)?,
            }
        };
        if count == 0 {
            return Ok(CtStatus::CT_OK);
        }
        if queries.is_null() {
            return Err(CapiError::null("queries"));
        }
        if rgba_out.is_null() {
            return Err(CapiError::null("rgba_out"));
        }
        if count > isize::MAX as usize / 16 {
            return Err(CapiError::invalid(format!("count {count} is too large")));
        }
        // SAFETY: the caller provides `count` queries and `4 * count` output floats.
        let queries = unsafe { std::slice::from_raw_parts(queries, count) };
        if let Some(i) = queries
            .iter()
            .position(|q| !(q.s.is_finite() && q.t.is_finite()))
        {
            return Err(CapiError::invalid(format!(
                "queries[{i}] has texture coordinates ({}, {}): s and t must be finite",
                queries[i].s, queries[i].t
            )));
        }
        let sample = |q: &CtTextureQuery| {
            let query = TextureQuery {
                s: q.s,
                t: q.t,
                dsdx: q.dsdx,
                dtdx: q.dtdx,
                dsdy: q.dsdy,
                dtdy: q.dtdy,
            };
            texture.sample(&query, &filter).to_array()
        };
        let out = unsafe { std::slice::from_raw_parts_mut(rgba_out, 4 * count) };
        if texture.is_demand_loaded() {
            // A tile that cannot be read gives zeros: filter into a buffer first, so that
            // nothing is written when one failed.
            let results: Vec<[f32; 4]> = queries.iter().map(sample).collect();
            if let Some(failure) = texture.tile_failure() {
                return Err(CapiError::new(CtStatus::CT_ERROR_TEXTURE, failure));
            }
            out.copy_from_slice(results.as_flattened());
        } else {
            for (q, rgba) in queries.iter().zip(out.chunks_exact_mut(4)) {
                rgba.copy_from_slice(&sample(q));
            }
        }
        Ok(CtStatus::CT_OK)
    })
}

/// Frees a texture. The null handle is a no-op (`CT_OK`); a freed or unknown handle gives
/// `CT_ERROR_INVALID_HANDLE`.
///
/// Thread safety: any thread; samples already running on other threads finish safely.
#[no_mangle]
pub extern "C" fn ct_texture_free(texture: CtTexture) -> CtStatus {
    guard(|| {
        handles::remove(texture.id, "texture")?;
        Ok(CtStatus::CT_OK)
    })
}
