//! Rendering a scene handle into an image handle: the options struct, its defaults, and
//! `ct_render` with its progress and texture callbacks.

use std::ffi::{c_void, CString};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::film::AovSelection;
use crate::footprint::LodStrategy;
use crate::integrator::selection::{IntegratorChoice, IntegratorKind};
use crate::render::{self, RenderControl, RenderOptions};
use crate::texture::{FilterMode, FilterOptions, WrapMode};

use super::callbacks::{
    CallbackTextures, CloseOnDrop, CtProgressFn, CtTextureFn, ProgressBoard, ProgressRelay,
    UserData,
};
use super::errors::{guard, CapiError, CtStatus};
use super::handles::{self, CtImage, CtScene, ImageObject, Object};
use super::{read_sized_or_earlier, require_out};

/// Level of detail: every lookup samples mip level 0.
pub const CT_LOD_MIP0: u32 = 0;
/// Level of detail from the camera's pixel spread times the path length.
pub const CT_LOD_DISTANCE: u32 = 1;
/// One ray cone.
pub const CT_LOD_CONE1: u32 = 2;
/// The two-cone envelope (the default).
pub const CT_LOD_CONE: u32 = 3;
/// Ray differentials.
pub const CT_LOD_DIFFERENTIAL: u32 = 4;

/// Nearest texel of level 0.
pub const CT_FILTER_CLOSEST: u32 = 0;
/// Bilinear on level 0.
pub const CT_FILTER_BILINEAR: u32 = 1;
/// Trilinear (OpenImageIO MipMode Trilinear).
pub const CT_FILTER_TRILINEAR: u32 = 2;
/// Anisotropic probes (OpenImageIO MipMode Aniso; the default).
pub const CT_FILTER_ANISO: u32 = 3;
/// Elliptical weighted average.
pub const CT_FILTER_EWA: u32 = 4;

/// The texture repeats.
pub const CT_WRAP_PERIODIC: u32 = 0;
/// Edge texels extend outward.
pub const CT_WRAP_CLAMP: u32 = 1;
/// Outside is black.
pub const CT_WRAP_BLACK: u32 = 2;
/// Mirrored repeat.
pub const CT_WRAP_MIRROR: u32 = 3;

/// AOV flag: add tex.s tex.t tex.dsdx tex.dtdx tex.dsdy tex.dtdy and texcolor.R/G/B/A.
pub const CT_AOV_FOOTPRINT: u32 = 1;
/// AOV flag: add `lod` and `footprint`.
pub const CT_AOV_LOD: u32 = 2;
/// AOV flag: leave out Z, N, albedo and uv (not computed then); colour and alpha remain.
pub const CT_AOV_NO_SURFACE: u32 = 4;

/// Integrator: the scene's `[render] integrator` (`auto` unless the scene names one); the
/// default, and what callers built before the `integrator` field get.
pub const CT_INTEGRATOR_SCENE: u32 = 0;
/// Integrator: the path tracer when the scene calls for global illumination (emissive
/// geometry, rough materials, `[render] gi`), Whitted otherwise.
pub const CT_INTEGRATOR_AUTO: u32 = 1;
/// Integrator: Whitted ray tracing.
pub const CT_INTEGRATOR_WHITTED: u32 = 2;
/// Integrator: the unidirectional path tracer.
pub const CT_INTEGRATOR_PATH: u32 = 3;
/// Integrator: voxel cone tracing.
pub const CT_INTEGRATOR_VCT: u32 = 4;

/// How to render. Fill it with `ct_render_options_init`, then change fields.
///
/// Fields are only ever appended. A caller built against an older header passes its smaller
/// `struct_size`, and the fields it does not know keep their defaults.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CtRenderOptions {
    /// `sizeof(CtRenderOptions)`, set by `ct_render_options_init`.
    pub struct_size: u32,
    /// Image width in pixels; 0 = the scene's.
    pub width: u32,
    /// Image height in pixels; 0 = the scene's.
    pub height: u32,
    /// Samples per pixel; 0 = the scene's, or without one the integrator's default (16 for
    /// the path tracer, 1 for Whitted and vct).
    pub spp: u32,
    /// Maximum reflection/refraction depth; -1 = the scene's.
    pub max_depth: i32,
    /// Worker threads; 0 = one per core; at most 1024.
    pub threads: u32,
    /// Footprint strategy (`CT_LOD_*`).
    pub lod: u32,
    /// Texture filter (`CT_FILTER_*`).
    pub filter: u32,
    /// Anisotropy limit (>= 1) of the aniso and ewa filters.
    pub max_aniso: f32,
    /// AOV layers (`CT_AOV_*` flags); colour is always there, and Z, N, albedo and uv are
    /// unless `CT_AOV_NO_SURFACE` is set.
    pub aovs: u32,
    /// Optional progress callback (NULL: none).
    pub progress: CtProgressFn,
    /// Passed to `progress`.
    pub progress_user_data: *mut c_void,
    /// Optional texture callback serving the scene's base-colour and environment lookups
    /// (NULL: the built-in texture system). Textures it serves are not decoded by the library;
    /// alpha cut-out masks (and, with `CT_AOV_LOD`, every texture) still are.
    pub texture_callback: CtTextureFn,
    /// Passed to `texture_callback`.
    pub texture_user_data: *mut c_void,
    /// Most memory the render may need, in bytes, by `ct_render_memory_estimate`; a render
    /// estimated above it fails with `CT_ERROR_OUT_OF_MEMORY` before allocating anything
    /// large. 0 = the memory the system reports available (no limit where it reports none).
    pub max_memory: u64,
    /// Integrator (`CT_INTEGRATOR_*`). A caller whose `struct_size` ends before it gets
    /// `CT_INTEGRATOR_SCENE`. 4 bytes of padding follow it, so that `clamp` starts at an
    /// 8-byte boundary and every version of this header has its own `struct_size`.
    pub integrator: u32,
    /// The largest colour component a camera sample keeps: a brighter sample is scaled down
    /// to it, its hue kept (`--clamp` on the command line; it removes fireflies and darkens
    /// what it clamps). 0 = the scene's `[render] clamp` (none unless the scene sets one);
    /// otherwise a finite number above 0. A caller whose `struct_size` ends before it gets
    /// 0.
    pub clamp: f64,
    /// Cap, in bytes, on the memory of texture tiles read on demand from tiled, mip-mapped
    /// `.tx` files (`--texture-cache` on the command line): tiles beyond it are evicted and
    /// read again when touched, the image unchanged. Each render has its own cache. 0 = the
    /// default, 256 MiB. Textures decoded whole, and those read for a texture callback, do
    /// not count against it. Appended last: a caller whose `struct_size` ends before it
    /// gets 0. A field appended later starts after it, at an 8-byte boundary.
    pub texture_cache: u64,
}

/// `struct_size` of `CtRenderOptions` before `integrator` was appended: still accepted.
const OPTIONS_SIZE_BEFORE_INTEGRATOR: usize = std::mem::offset_of!(CtRenderOptions, integrator);
/// `struct_size` of `CtRenderOptions` before `clamp` was appended: still accepted.
const OPTIONS_SIZE_BEFORE_CLAMP: usize = std::mem::offset_of!(CtRenderOptions, clamp);
/// `struct_size` of `CtRenderOptions` before `texture_cache` was appended: still accepted.
const OPTIONS_SIZE_BEFORE_TEXTURE_CACHE: usize =
    std::mem::offset_of!(CtRenderOptions, texture_cache);
/// The `struct_size`s of earlier headers' `CtRenderOptions`, oldest first.
const EARLIER_OPTIONS_SIZES: [usize; 3] = [
    OPTIONS_SIZE_BEFORE_INTEGRATOR,
    OPTIONS_SIZE_BEFORE_CLAMP,
    OPTIONS_SIZE_BEFORE_TEXTURE_CACHE,
];

impl CtRenderOptions {
    fn defaults() -> CtRenderOptions {
        CtRenderOptions {
            struct_size: std::mem::size_of::<CtRenderOptions>() as u32,
            width: 0,
            height: 0,
            spp: 0,
            max_depth: -1,
            max_memory: 0,
            threads: 0,
            lod: CT_LOD_CONE,
            filter: CT_FILTER_ANISO,
            max_aniso: 16.0,
            aovs: 0,
            progress: None,
            progress_user_data: std::ptr::null_mut(),
            texture_callback: None,
            texture_user_data: std::ptr::null_mut(),
            integrator: CT_INTEGRATOR_SCENE,
            clamp: 0.0,
            texture_cache: 0,
        }
    }
}

/// The integrator choice of `code` over the scene's `settings` (`CT_INTEGRATOR_SCENE`: the
/// scene's own).
fn integrator_from_code(
    code: u32,
    settings: &crate::scene::RenderSettings,
) -> Result<IntegratorChoice, CapiError> {
    Ok(match code {
        CT_INTEGRATOR_SCENE => settings.integrator,
        CT_INTEGRATOR_AUTO => IntegratorChoice::Auto,
        CT_INTEGRATOR_WHITTED => IntegratorChoice::Fixed(IntegratorKind::Whitted),
        CT_INTEGRATOR_PATH => IntegratorChoice::Fixed(IntegratorKind::Path),
        CT_INTEGRATOR_VCT => IntegratorChoice::Fixed(IntegratorKind::Vct),
        _ => {
            return Err(CapiError::invalid(format!(
                "unknown integrator {code} (CT_INTEGRATOR_*)"
            )))
        }
    })
}

pub(crate) fn filter_code(filter: FilterMode) -> u32 {
    match filter {
        FilterMode::Closest => CT_FILTER_CLOSEST,
        FilterMode::Bilinear => CT_FILTER_BILINEAR,
        FilterMode::Trilinear => CT_FILTER_TRILINEAR,
        FilterMode::Aniso => CT_FILTER_ANISO,
        FilterMode::Ewa => CT_FILTER_EWA,
    }
}

pub(crate) fn wrap_code(wrap: WrapMode) -> u32 {
    match wrap {
        WrapMode::Periodic => CT_WRAP_PERIODIC,
        WrapMode::Clamp => CT_WRAP_CLAMP,
        WrapMode::Black => CT_WRAP_BLACK,
        WrapMode::Mirror => CT_WRAP_MIRROR,
    }
}

pub(crate) fn filter_from_code(code: u32) -> Result<FilterMode, CapiError> {
    Ok(match code {
        CT_FILTER_CLOSEST => FilterMode::Closest,
        CT_FILTER_BILINEAR => FilterMode::Bilinear,
        CT_FILTER_TRILINEAR => FilterMode::Trilinear,
        CT_FILTER_ANISO => FilterMode::Aniso,
        CT_FILTER_EWA => FilterMode::Ewa,
        _ => {
            return Err(CapiError::invalid(format!(
                "unknown filter {code} (CT_FILTER_*)"
            )))
        }
    })
}

pub(crate) fn wrap_from_code(code: u32) -> Result<WrapMode, CapiError> {
    Ok(match code {
        CT_WRAP_PERIODIC => WrapMode::Periodic,
        CT_WRAP_CLAMP => WrapMode::Clamp,
        CT_WRAP_BLACK => WrapMode::Black,
        CT_WRAP_MIRROR => WrapMode::Mirror,
        _ => {
            return Err(CapiError::invalid(format!(
                "unknown wrap mode {code} (CT_WRAP_*)"
            )))
        }
    })
}

pub(crate) fn max_aniso_checked(max_aniso: f32) -> Result<f32, CapiError> {
    if max_aniso.is_finite() && max_aniso >= 1.0 {
        Ok(max_aniso)
    } else {
        Err(CapiError::invalid(format!(
            "max_aniso must be a finite number >= 1, got {max_aniso}"
        )))
    }
}

fn lod_from_code(code: u32) -> Result<LodStrategy, CapiError> {
    Ok(match code {
        CT_LOD_MIP0 => LodStrategy::Mip0,
        CT_LOD_DISTANCE => LodStrategy::Distance,
        CT_LOD_CONE1 => LodStrategy::Cone1,
        CT_LOD_CONE => LodStrategy::Cone,
        CT_LOD_DIFFERENTIAL => LodStrategy::Differential,
        _ => {
            return Err(CapiError::invalid(format!(
                "unknown LOD strategy {code} (CT_LOD_*)"
            )))
        }
    })
}

/// Fills `*options` with the defaults (the scene's size, spp and depth; cone footprints; aniso
/// filter, max_aniso 16; all cores; no callbacks; the scene's integrator). `struct_size` must
/// be `sizeof(CtRenderOptions)` of this header or of an earlier one (then only that many
/// bytes are written); any other size gets `CT_ERROR_STRUCT_SIZE` and nothing is written.
///
/// Thread safety: any thread.
///
/// # Safety
/// `options` points to at least `struct_size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn ct_render_options_init(
    options: *mut CtRenderOptions,
    struct_size: usize,
) -> CtStatus {
    guard(|| {
        require_out(options, "options")?;
        let expected = std::mem::size_of::<CtRenderOptions>();
        if struct_size == expected {
            // SAFETY: non-null and `expected` bytes writable by contract.
            unsafe { options.write_unaligned(CtRenderOptions::defaults()) };
            return Ok(CtStatus::CT_OK);
        }
        if !EARLIER_OPTIONS_SIZES.contains(&struct_size) {
            return Err(CapiError::new(
                CtStatus::CT_ERROR_STRUCT_SIZE,
                format!(
                    "options: struct_size is {struct_size}, this library expects {expected} \
                     (or {EARLIER_OPTIONS_SIZES:?} from earlier headers)"
                ),
            ));
        }
        // An earlier caller's struct: its own fields only.
        let defaults = CtRenderOptions {
            struct_size: struct_size as u32,
            ..CtRenderOptions::defaults()
        };
        // SAFETY: non-null and `struct_size` bytes writable by contract; `defaults` is a
        // whole struct, larger than `struct_size`.
        unsafe {
            std::ptr::copy_nonoverlapping(
                (&defaults as *const CtRenderOptions).cast::<u8>(),
                options.cast::<u8>(),
                struct_size,
            )
        };
        Ok(CtStatus::CT_OK)
    })
}

/// Renders `scene` into a new image, `*out_image`.
///
/// `options` may be NULL (defaults). Returns `CT_OK` with a complete image; `CT_CANCELLED`
/// when the progress callback asked to stop before every tile was done — `*out_image` is then
/// a valid partial image (unfinished 16x16 tiles are zero, `ct_image_is_complete` says 0) that
/// must be freed like any other, and `ct_last_error_message` says how many tiles were
/// finished; `CT_ERROR_CALLBACK` when the texture callback returned an
/// error (no image); other errors leave `*out_image` null.
///
/// Thread safety: any thread; several renders may run at once (each uses its own worker pool
/// of `threads` threads). The scene may be freed by another thread meanwhile: the render holds
/// its own reference. The texture callback runs on the worker threads (`CtTextureFn`), the
/// progress callback on the calling thread (`CtProgressFn`).
///
/// # Safety
/// `options` is NULL or a `CtRenderOptions` whose `struct_size` is correct; `out_image` is
/// writable; the callbacks and user data follow their contracts.
#[no_mangle]
pub unsafe extern "C" fn ct_render(
    scene: CtScene,
    options: *const CtRenderOptions,
    out_image: *mut CtImage,
) -> CtStatus {
    guard(|| {
        require_out(out_image, "out_image")?;
        // SAFETY: checked non-null above.
        unsafe { out_image.write(CtImage::default()) };
        let c_options = if options.is_null() {
            CtRenderOptions::defaults()
        } else {
            // SAFETY: caller's contract.
            unsafe {
                read_sized_or_earlier(
                    options,
                    "options",
                    &EARLIER_OPTIONS_SIZES,
                    CtRenderOptions::defaults(),
                )
            }?
        };
        let object = handles::scene(scene)?;
        let scene = object.scene.clone();
        let render_options = render_options(&c_options, &scene)?;
        let integrator = integrator_from_code(c_options.integrator, &scene.settings)?;
        let texture_cache_bytes = texture_cache_cap(&c_options);
        // Refused before the film or any texture is allocated. A texture whose header cannot
        // be read is left to the preparation below, which reports it with its role.
        if let Ok(estimate) = memory_estimate(&c_options, integrator, &scene, &render_options) {
            let limit = (c_options.max_memory > 0).then_some(c_options.max_memory);
            render::memory::check_against(&estimate, limit, "max_memory", &scene.source)
                .map_err(|message| CapiError::new(CtStatus::CT_ERROR_OUT_OF_MEMORY, message))?;
        }
        // The camera's matrices go into the image's EXR header.
        let camera = scene.camera.as_ref().map(|desc| {
            crate::camera::Camera::new(desc, render_options.width, render_options.height)
        });

        let cancel = Arc::new(AtomicBool::new(false));
        let textures = c_options.texture_callback.map(|callback| {
            Arc::new(CallbackTextures {
                callback,
                user_data: UserData(c_options.texture_user_data),
                names: object.texture_names.clone(),
                first_error: Mutex::new(None),
                cancel: cancel.clone(),
            })
        });
        let relay = c_options.progress.map(|callback| ProgressRelay {
            callback,
            user_data: UserData(c_options.progress_user_data),
            cancel: cancel.clone(),
            cancelled_by_callback: AtomicBool::new(false),
        });

        let mut pool = rayon::ThreadPoolBuilder::new()
            .start_handler(|_| crate::embree::enable_flush_denormals());
        if c_options.threads as usize > crate::render::MAX_WORKER_THREADS {
            return Err(CapiError::invalid(format!(
                "threads must be at most {}, got {}",
                crate::render::MAX_WORKER_THREADS,
                c_options.threads
            )));
        }
        if c_options.threads > 0 {
            pool = pool.num_threads(c_options.threads as usize);
        }
        let pool = pool.build().map_err(|e| {
            CapiError::new(
                CtStatus::CT_ERROR_RENDER,
                format!("cannot start worker threads: {e}"),
            )
        })?;
        // Workers publish finished tiles here; this thread calls the progress callback.
        let board = ProgressBoard::new(std::thread::current());
        let render_on_pool = || {
            pool.install(|| -> Result<render::RenderResult, CapiError> {
                let context = match &textures {
                    Some(textures) => render::external_textures::prepare_with_external(
                        scene.clone(),
                        render_options,
                        textures.clone(),
                    ),
                    None => render::prepare_in(
                        scene.clone(),
                        render_options,
                        &Arc::new(crate::texture::TileCache::new(texture_cache_bytes)),
                    ),
                }
                .map_err(|e| CapiError::new(CtStatus::CT_ERROR_RENDER, e.to_string()))?;
                let publish = |done: usize, total: usize| board.publish(done, total);
                let progress: Option<&(dyn Fn(usize, usize) + Sync)> = if relay.is_some() {
                    Some(&publish)
                } else {
                    None
                };
                let control = RenderControl {
                    progress,
                    cancel: Some(&cancel),
                    skip: None,
                    part: None,
                };
                crate::integrator::selection::render(&context, integrator, &control)
                    .map_err(|e| CapiError::new(CtStatus::CT_ERROR_RENDER, e.to_string()))
            })
        };
        let result = match &relay {
            // The render waits on a helper thread while this one reports its progress.
            Some(relay) => std::thread::scope(|scope| {
                let renderer = scope.spawn(|| {
                    let _close = CloseOnDrop(&board);
                    render_on_pool()
                });
                relay.run(&board);
                renderer
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            }),
            None => render_on_pool(),
        }?;

        if let Some(textures) = &textures {
            let first = textures
                .first_error
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take();
            if let Some(message) = first {
                return Err(CapiError::new(CtStatus::CT_ERROR_CALLBACK, message));
            }
        }
        let channel_names = result
            .film
            .channel_names()
            .iter()
            .map(|n| CString::new(n.as_str()).unwrap_or_default())
            .collect();
        let complete = result.stats.complete;
        let finished_tiles = result.finished_tiles.iter().filter(|&&f| f).count();
        let total_tiles = result.finished_tiles.len();
        let image = ImageObject {
            film: result.film,
            channel_names,
            complete,
            finished_tiles: finished_tiles as u32,
            tonemap: scene.settings.tonemap,
            exposure: scene.settings.exposure,
            world_to_camera: camera.map(|c| c.world_to_camera_matrix()),
            world_to_ndc: camera.map(|c| c.world_to_ndc_matrix()),
        };
        let handle = CtImage {
            id: handles::insert(Object::Image(Arc::new(image))),
        };
        // SAFETY: checked non-null above.
        unsafe { out_image.write(handle) };
        let cancelled = relay
            .as_ref()
            .is_some_and(|r| r.cancelled_by_callback.load(Ordering::Relaxed));
        if cancelled && !complete {
            // The image is handed out above; the error only carries the status and the
            // message that `ct_last_error_message` must give for it.
            return Err(CapiError::new(
                CtStatus::CT_CANCELLED,
                format!(
                    "the render was cancelled by the progress callback after \
                     {finished_tiles} of {total_tiles} tiles; the image is partial"
                ),
            ));
        }
        Ok(CtStatus::CT_OK)
    })
}

/// Writes to `*out_bytes` the memory, in bytes, that `ct_render` of `scene` with `options`
/// (NULL: defaults) is estimated to need at its peak: the film and its copies for the
/// outputs, and every texture the library decodes with its mip levels, in the precision it
/// is stored in (from the file headers; nothing is decoded), and the voxel pyramid when the
/// integrator is the voxel cone tracer. Textures a texture callback serves are not decoded
/// and not counted. `ct_render` refuses a render whose estimate
/// exceeds `max_memory` with `CT_ERROR_OUT_OF_MEMORY`.
///
/// Returns `CT_ERROR_TEXTURE` when a texture's header cannot be read.
///
/// Thread safety: any thread.
///
/// # Safety
/// `options` is NULL or a `CtRenderOptions` whose `struct_size` is correct; `out_bytes` is
/// writable.
#[no_mangle]
pub unsafe extern "C" fn ct_render_memory_estimate(
    scene: CtScene,
    options: *const CtRenderOptions,
    out_bytes: *mut u64,
) -> CtStatus {
    guard(|| {
        require_out(out_bytes, "out_bytes")?;
        let c_options = if options.is_null() {
            CtRenderOptions::defaults()
        } else {
            // SAFETY: caller's contract.
            unsafe {
                read_sized_or_earlier(
                    options,
                    "options",
                    &EARLIER_OPTIONS_SIZES,
                    CtRenderOptions::defaults(),
                )
            }?
        };
        let object = handles::scene(scene)?;
        // The same checks as `ct_render`: an unknown integrator is an error here too.
        let integrator = integrator_from_code(c_options.integrator, &object.scene.settings)?;
        let render_options = render_options(&c_options, &object.scene)?;
        let estimate = memory_estimate(&c_options, integrator, &object.scene, &render_options)?;
        // SAFETY: checked non-null above.
        unsafe { out_bytes.write(estimate.total()) };
        Ok(CtStatus::CT_OK)
    })
}

/// The cap of a render's texture cache: `texture_cache`, 0 meaning the default.
fn texture_cache_cap(c: &CtRenderOptions) -> u64 {
    match c.texture_cache {
        0 => crate::texture::DEFAULT_TEXTURE_CACHE_BYTES,
        bytes => bytes,
    }
}

/// The memory estimate of a render: with a texture callback, only the textures the library
/// still decodes (alpha cut-out masks; all of them for the `lod` AOV) are counted; the
/// voxel pyramid when `integrator` resolves to vct.
fn memory_estimate(
    c: &CtRenderOptions,
    integrator: IntegratorChoice,
    scene: &crate::scene::SceneDescription,
    options: &RenderOptions,
) -> Result<render::memory::MemoryEstimate, CapiError> {
    let mut decoded = vec![c.texture_callback.is_none() || options.aovs.lod; scene.textures.len()];
    for material in &scene.materials {
        if let (Some(_), Some(binding)) = (material.alpha_cutoff, &material.alpha_texture) {
            if let Some(flag) = decoded.get_mut(binding.texture) {
                *flag = true;
            }
        }
    }
    let mut estimate =
        render::memory::estimate_decoding(scene, options, texture_cache_cap(c), |i| {
            decoded.get(i) == Some(&true)
        })
        .map_err(|e| CapiError::new(CtStatus::CT_ERROR_TEXTURE, e.to_string()))?;
    estimate.voxels = crate::integrator::selection::integrator_memory(integrator, scene)
        .map_err(|e| CapiError::invalid(format!("{}: {e}", scene.source)))?;
    Ok(estimate)
}

/// The renderer's options from the C options over the scene's settings, validated.
fn render_options(
    c: &CtRenderOptions,
    scene: &crate::scene::SceneDescription,
) -> Result<RenderOptions, CapiError> {
    let width = if c.width == 0 {
        scene.settings.width
    } else {
        c.width
    };
    let height = if c.height == 0 {
        scene.settings.height
    } else {
        c.height
    };
    if width == 0 || height == 0 || width > 65_536 || height > 65_536 {
        return Err(CapiError::invalid(format!(
            "image size {width}x{height} must be between 1 and 65536 on each side"
        )));
    }
    let spp = if c.spp == 0 {
        scene.settings.spp.unwrap_or_else(|| {
            let choice = integrator_from_code(c.integrator, &scene.settings);
            let kind = crate::integrator::selection::resolve(
                choice.unwrap_or(scene.settings.integrator),
                scene,
            )
            .kind;
            crate::integrator::selection::default_spp(kind)
        })
    } else {
        c.spp
    };
    let max_depth = match c.max_depth {
        -1 => scene.settings.max_depth,
        d if d >= 0 => d as u32,
        d => {
            return Err(CapiError::invalid(format!(
                "max_depth must be >= 0 (or -1 for the scene's), got {d}"
            )))
        }
    };
    let sample_clamp = if c.clamp == 0.0 {
        scene.settings.sample_clamp
    } else {
        Some(
            crate::render::context::parse_sample_clamp(c.clamp)
                .map_err(|problem| CapiError::invalid(format!("clamp {problem}")))?,
        )
    };
    if c.aovs & !(CT_AOV_FOOTPRINT | CT_AOV_LOD | CT_AOV_NO_SURFACE) != 0 {
        return Err(CapiError::invalid(format!(
            "aovs has unknown flags {:#x} (CT_AOV_*)",
            c.aovs
        )));
    }
    Ok(RenderOptions {
        width,
        height,
        spp: spp.max(1),
        max_depth,
        min_throughput: scene.settings.min_throughput,
        lod: lod_from_code(c.lod)?,
        filter: FilterOptions {
            filter: filter_from_code(c.filter)?,
            max_aniso: max_aniso_checked(c.max_aniso)?,
            ..FilterOptions::default()
        },
        fresnel: scene.settings.fresnel,
        aovs: AovSelection {
            surface: c.aovs & CT_AOV_NO_SURFACE == 0,
            texture_footprint: c.aovs & CT_AOV_FOOTPRINT != 0,
            lod: c.aovs & CT_AOV_LOD != 0,
        },
        count_texture_tiles: false,
        all_effects: false,
        seed: 0,
        sample_clamp,
    })
}
