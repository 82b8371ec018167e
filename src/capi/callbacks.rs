//! The two C callbacks a render can call: progress (which can cancel) and the texture
//! callback that serves the scene's texture lookups ("bring your own texture system").

use std::ffi::{c_void, CString};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::Thread;

use glam::Vec4;

use crate::render::ExternalTextures;
use crate::texture::{FilterOptions, TextureQuery};

use super::render::{filter_code, wrap_code};

/// Progress of a render: `finished_tiles` of `total_tiles` are done. Return 0 to continue, any
/// other value to cancel (tiles in flight finish; the result is a valid partial image and
/// `ct_render` returns `CT_CANCELLED`).
///
/// Called on the thread that called `ct_render`, never on a worker thread and never after
/// `ct_render` returns; the workers go on rendering while it runs, so a slow callback does
/// not slow the render down. `finished_tiles` grows from call to call; when several tiles
/// finish during one call, the next call reports them together. Unless the callback cancelled,
/// the last call reports every tile finished. Must not throw C++ exceptions or call
/// `ct_render`.
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

/// Where the render's workers publish progress without waiting for anyone: the count of
/// finished tiles, and whether the render is over. The thread that waits for the render reads
/// it and calls the C progress callback ([`ProgressRelay::run`]); workers only store atomics
/// and wake that thread, so a slow callback never blocks a worker.
pub(crate) struct ProgressBoard {
    finished_tiles: AtomicUsize,
    total_tiles: AtomicUsize,
    render_over: AtomicBool,
    /// The thread running [`ProgressRelay::run`].
    reporter: Thread,
}

impl ProgressBoard {
    /// A board whose news wake `reporter`.
    pub fn new(reporter: Thread) -> ProgressBoard {
        ProgressBoard {
            finished_tiles: AtomicUsize::new(0),
            total_tiles: AtomicUsize::new(0),
            render_over: AtomicBool::new(false),
            reporter,
        }
    }

    /// A worker finished a tile: `finished` of `total` are done.
    pub fn publish(&self, finished: usize, total: usize) {
        self.total_tiles.store(total, Ordering::Release);
        self.finished_tiles.fetch_max(finished, Ordering::AcqRel);
        self.reporter.unpark();
    }

    /// The render returned (or unwound): the reporter makes its last call and stops.
    pub fn close(&self) {
        self.render_over.store(true, Ordering::Release);
        self.reporter.unpark();
    }
}

/// Closes a [`ProgressBoard`] when dropped, so the reporter stops even if the render panics.
pub(crate) struct CloseOnDrop<'a>(pub &'a ProgressBoard);

impl Drop for CloseOnDrop<'_> {
    fn drop(&mut self) {
        self.0.close();
    }
}

/// The C progress callback, called from one thread only, and the cancel flag it can raise.
pub(crate) struct ProgressRelay {
    pub callback: unsafe extern "C" fn(u32, u32, *mut c_void) -> i32,
    pub user_data: UserData,
    pub cancel: Arc<AtomicBool>,
    pub cancelled_by_callback: AtomicBool,
}

impl ProgressRelay {
    /// Reports `board`'s progress to the callback until the render is over: one call per
    /// change of the finished-tile count seen (changes during a call are reported together
    /// by the next one), then a last call with the final count if it was not reported yet.
    /// Stops calling once the callback asked to cancel. Must run on `board`'s reporter thread.
    pub fn run(&self, board: &ProgressBoard) {
        let mut reported = 0;
        loop {
            // Read "over" before the count: a count published before the render ended is
            // then seen by this pass.
            let over = board.render_over.load(Ordering::Acquire);
            let finished = board.finished_tiles.load(Ordering::Acquire);
            if finished != reported && !self.cancelled_by_callback.load(Ordering::Relaxed) {
                reported = finished;
                let total = board.total_tiles.load(Ordering::Acquire);
                // SAFETY: a C function pointer the caller supplied, with its own user data.
                let answer =
                    unsafe { (self.callback)(finished as u32, total as u32, self.user_data.0) };
                if answer != 0 {
                    self.cancelled_by_callback.store(true, Ordering::Relaxed);
                    self.cancel.store(true, Ordering::Relaxed);
                }
                continue;
            }
            if over {
                return;
            }
            // Woken by every publish and by close (an unpark before this park is kept).
            std::thread::park();
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
