//! The two C callbacks a render can call: progress (which can cancel) and the texture
//! callback that serves the scene's texture lookups ("bring your own texture system").

use std::ffi::{c_void, CString};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use glam::Vec4;

use crate::render::ExternalTextures;
use crate::texture::{FilterOptions, TextureQuery};

use super::render::{filter_code, wrap_code};

/// Progress of a render: `finished_tiles` of `total_tiles` are done. Return 0 to continue, any
/// other value to cancel (tiles in flight finish; the result is a valid partial image and
/// `ct_render` returns `CT_CANCELLED`).
///
/// Called from the render's worker threads, one call at a time (calls are serialised by the
/// library), never after `ct_render` returns. Must not throw C++ exceptions or call `ct_render`.
pub type CtProgressFn = Option<
    unsafe extern "C" fn(finished_tiles: u32, total_tiles: u32, user_data: *mut c_void) -> i32,
>;

/// One texture lookup the renderer asks the texture callback to answer.
///
/// Coordinates follow OpenImageIO: `s` grows to the right, `t` downwards, (0,0) is the outer
/// corner of the first texel; derivatives are per pixel along screen x and y, in normalised
/// texture units, produced by the render's footprint (ray cone or ray differential) after the
/// material's texture transform. For the lat-long environment, `s`/`t` are the direction's
/// longitude/latitude in [0,1].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CtTextureRequest {
    /// `sizeof(CtTextureRequest)` of the library that filled it.
    pub struct_size: u32,
    /// Index into the scene's textures (see `ct_scene_texture_name`).
    pub texture_index: u32,
    /// The texture's name (NUL-terminated UTF-8), valid during the call.
    pub texture_name: *const std::ffi::c_char,
    /// Horizontal coordinate.
    pub s: f32,
    /// Vertical coordinate.
    pub t: f32,
    /// ds/dx.
    pub dsdx: f32,
    /// dt/dx.
    pub dtdx: f32,
    /// ds/dy.
    pub dsdy: f32,
    /// dt/dy.
    pub dtdy: f32,
    /// The filter the built-in texture system would use (`CT_FILTER_*`).
    pub filter: u32,
    /// Wrap mode along s (`CT_WRAP_*`).
    pub wrap_s: u32,
    /// Wrap mode along t (`CT_WRAP_*`).
    pub wrap_t: u32,
    /// Anisotropy limit of the aniso and ewa filters.
    pub max_aniso: f32,
}

/// Answers one texture lookup: write the filtered, linear RGBA into `rgba_out[0..4]` and return
/// 0, or return a non-zero code to report an error (the render stops and `ct_render` returns
/// `CT_ERROR_CALLBACK` with a message holding the code and the texture name).
///
/// Runs on the render's worker threads and MAY BE CALLED CONCURRENTLY from several threads
/// with the same `user_data`: it must be thread-safe. `request` and `rgba_out` are valid only
/// during the call. Must not throw C++ exceptions, unwind, or call `ct_render`.
pub type CtTextureFn = Option<
    unsafe extern "C" fn(
        request: *const CtTextureRequest,
        rgba_out: *mut f32,
        user_data: *mut c_void,
    ) -> i32,
>;

/// A user-data pointer the caller promised may be used from any thread.
#[derive(Clone, Copy)]
pub(crate) struct UserData(pub *mut c_void);
// SAFETY: the callback contracts above make thread-safety of user_data the caller's promise.
unsafe impl Send for UserData {}
// SAFETY: as above.
unsafe impl Sync for UserData {}

/// Calls the progress callback, one call at a time, and raises `cancel` when it asks to stop.
pub(crate) struct ProgressRelay {
    pub callback: unsafe extern "C" fn(u32, u32, *mut c_void) -> i32,
    pub user_data: UserData,
    pub cancel: Arc<AtomicBool>,
    pub cancelled_by_callback: AtomicBool,
    pub serial: Mutex<()>,
}

impl ProgressRelay {
    pub fn report(&self, done: usize, total: usize) {
        let _one_at_a_time = self.serial.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: a C function pointer the caller supplied, with its own user data.
        let answer = unsafe { (self.callback)(done as u32, total as u32, self.user_data.0) };
        if answer != 0 {
            self.cancelled_by_callback.store(true, Ordering::Relaxed);
            self.cancel.store(true, Ordering::Relaxed);
        }
    }
}

/// The texture callback as the renderer's [`ExternalTextures`] hook.
pub(crate) struct CallbackTextures {
    pub callback: unsafe extern "C" fn(*const CtTextureRequest, *mut f32, *mut c_void) -> i32,
    pub user_data: UserData,
    pub names: Vec<CString>,
    /// The first error a callback reported (later ones are dropped).
    pub first_error: Mutex<Option<String>>,
    /// Raised on the first error, to stop the render.
    pub cancel: Arc<AtomicBool>,
}

impl ExternalTextures for CallbackTextures {
    fn sample(
        &self,
        texture_index: usize,
        query: &TextureQuery,
        options: &FilterOptions,
    ) -> Result<Vec4, String> {
        let name = self
            .names
            .get(texture_index)
            .ok_or_else(|| format!("texture index {texture_index} is out of range"))?;
        let request = CtTextureRequest {
            struct_size: std::mem::size_of::<CtTextureRequest>() as u32,
            texture_index: texture_index as u32,
            texture_name: name.as_ptr(),
            s: query.s,
            t: query.t,
            dsdx: query.dsdx,
            dtdx: query.dtdx,
            dsdy: query.dsdy,
            dtdy: query.dtdy,
            filter: filter_code(options.filter),
            wrap_s: wrap_code(options.wrap_s),
            wrap_t: wrap_code(options.wrap_t),
            max_aniso: options.max_aniso,
        };
        let mut rgba = [0.0f32; 4];
        // SAFETY: a C function pointer the caller supplied; request and rgba outlive the call.
        let code = unsafe { (self.callback)(&request, rgba.as_mut_ptr(), self.user_data.0) };
        if code == 0 {
            return Ok(Vec4::from_array(rgba));
        }
        let message = format!(
            "the texture callback returned {code} for texture '{}' (s {}, t {})",
            name.to_string_lossy(),
            query.s,
            query.t
        );
        let mut first = self.first_error.lock().unwrap_or_else(|e| e.into_inner());
        if first.is_none() {
            *first = Some(message.clone());
        }
        self.cancel.store(true, Ordering::Relaxed);
        Err(message)
    }
}
