//! Scene handles: load from a file, a TOML string or the built-in default; free; list the
//! scene's textures (name, source file, colour space) for pipelines that serve them.

use std::ffi::{c_char, CString};
use std::path::Path;
use std::sync::Arc;

use crate::scene::load::{default_scene, load_scene, load_toml_str};
use crate::scene::{SceneDescription, TextureSource};
use crate::texture::ColorSpace;

use super::errors::{guard, CapiError, CtStatus};
use super::handles::{self, CtScene, Object, SceneObject};
use super::{c_path, c_str, require_out, write_out};

/// 8-bit colour texels are sRGB-encoded and decoded to linear on load.
pub const CT_COLOR_SPACE_SRGB: u32 = 0;
/// Texels are used as stored (byte / 255 for 8-bit files).
pub const CT_COLOR_SPACE_LINEAR: u32 = 1;

fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).unwrap_or_default()
}

/// Registers a loaded scene and returns its handle.
fn register(scene: SceneDescription) -> CtScene {
    let texture_names = scene.textures.iter().map(|t| c_string(&t.name)).collect();
    let texture_paths = scene
        .textures
        .iter()
        .map(|t| match &t.source {
            TextureSource::File(path) => Some(
                CString::new(std::os::unix::ffi::OsStrExt::as_bytes(path.as_os_str()))
                    .unwrap_or_default(),
            ),
            TextureSource::Encoded { .. } => None,
        })
        .collect();
    let object = SceneObject {
        scene: Arc::new(scene),
        texture_names,
        texture_paths,
    };
    CtScene {
        id: handles::insert(Object::Scene(Arc::new(object))),
    }
}

/// Loads a scene from a `.toml`, `.obj`, `.gltf` or `.glb` file (a camera and lights are added
/// when missing) into `*out_scene`. On failure `*out_scene` is the null handle and the status
/// is `CT_ERROR_SCENE` with a message naming the file and the problem.
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `path` is a NUL-terminated string; `out_scene` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_load_file(
    path: *const c_char,
    out_scene: *mut CtScene,
) -> CtStatus {
    guard(|| {
        require_out(out_scene, "out_scene")?;
        // SAFETY: checked non-null above; writable by contract.
        unsafe { out_scene.write(CtScene::default()) };
        // SAFETY: caller's contract.
        let path = unsafe { c_path(path, "path") }?;
        let scene = load_scene(&path)
            .map_err(|e| CapiError::new(CtStatus::CT_ERROR_SCENE, e.to_string()))?;
        // SAFETY: as above.
        unsafe { write_out(out_scene, register(scene), "out_scene") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// Parses TOML scene text into `*out_scene`. Relative file names in it resolve against
/// `base_dir` (NULL: the current directory); messages name `source_label` (NULL: "<string>").
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `toml_text` is a NUL-terminated UTF-8 string; `base_dir` and `source_label` are NULL or
/// NUL-terminated; `out_scene` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_load_toml_string(
    toml_text: *const c_char,
    base_dir: *const c_char,
    source_label: *const c_char,
    out_scene: *mut CtScene,
) -> CtStatus {
    guard(|| {
        require_out(out_scene, "out_scene")?;
        // SAFETY: checked non-null above.
        unsafe { out_scene.write(CtScene::default()) };
        // SAFETY: caller's contract for all three strings.
        let text = unsafe { c_str(toml_text, "toml_text") }?;
        let base = if base_dir.is_null() {
            Path::new(".").to_path_buf()
        } else {
            unsafe { c_path(base_dir, "base_dir") }?
        };
        let label = if source_label.is_null() {
            "<string>"
        } else {
            unsafe { c_str(source_label, "source_label") }?
        };
        let scene = load_toml_str(text, &base, label)
            .map_err(|e| CapiError::new(CtStatus::CT_ERROR_SCENE, e.to_string()))?;
        unsafe { write_out(out_scene, register(scene), "out_scene") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// The built-in default scene (the one `conetrace render` renders without arguments).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_scene` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_default(out_scene: *mut CtScene) -> CtStatus {
    guard(|| {
        require_out(out_scene, "out_scene")?;
        unsafe { write_out(out_scene, register(default_scene()), "out_scene") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// Frees a scene. The null handle is a no-op (`CT_OK`); a handle already freed or never created
/// gives `CT_ERROR_INVALID_HANDLE`. Renders running on the scene keep their own reference and
/// finish normally. Strings returned by the `ct_scene_texture_*` functions become invalid.
///
/// Thread safety: any thread, but no other thread may still use strings obtained from it.
#[no_mangle]
pub extern "C" fn ct_scene_free(scene: CtScene) -> CtStatus {
    guard(|| {
        handles::remove(scene.id, "scene")?;
        Ok(CtStatus::CT_OK)
    })
}

/// Number of textures the scene declares (indices for the `ct_scene_texture_*` functions and
/// `CtTextureRequest::texture_index`).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_count` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_texture_count(scene: CtScene, out_count: *mut u32) -> CtStatus {
    guard(|| {
        require_out(out_count, "out_count")?;
        let object = handles::scene(scene)?;
        let count = object.scene.textures.len() as u32;
        unsafe { write_out(out_count, count, "out_count") }?;
        Ok(CtStatus::CT_OK)
    })
}

fn texture_index(object: &SceneObject, index: u32) -> Result<usize, CapiError> {
    let count = object.scene.textures.len();
    if (index as usize) < count {
        Ok(index as usize)
    } else {
        Err(CapiError::invalid(format!(
            "texture index {index} is out of range (the scene has {count} textures)"
        )))
    }
}

/// The name of texture `index` (NUL-terminated UTF-8, owned by the scene, valid until
/// `ct_scene_free`).
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_name` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_texture_name(
    scene: CtScene,
    index: u32,
    out_name: *mut *const c_char,
) -> CtStatus {
    guard(|| {
        require_out(out_name, "out_name")?;
        let object = handles::scene(scene)?;
        let i = texture_index(&object, index)?;
        unsafe { write_out(out_name, object.texture_names[i].as_ptr(), "out_name") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// The file texture `index` was loaded from, or NULL (with `CT_OK`) when the texture is
/// embedded (glTF buffers, the built-in default scene). Owned by the scene, valid until
/// `ct_scene_free`.
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_path` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_texture_path(
    scene: CtScene,
    index: u32,
    out_path: *mut *const c_char,
) -> CtStatus {
    guard(|| {
        require_out(out_path, "out_path")?;
        let object = handles::scene(scene)?;
        let i = texture_index(&object, index)?;
        let ptr = object.texture_paths[i]
            .as_ref()
            .map_or(std::ptr::null(), |p| p.as_ptr());
        unsafe { write_out(out_path, ptr, "out_path") }?;
        Ok(CtStatus::CT_OK)
    })
}

/// How texture `index`'s 8-bit colour is decoded: `CT_COLOR_SPACE_SRGB` (to linear) or
/// `CT_COLOR_SPACE_LINEAR`: as the scene states it, else as a `.tx` written by `conetrace
/// maketx` records it, else sRGB.
///
/// Thread safety: any thread, concurrently with any other call.
///
/// # Safety
/// `out_color_space` is writable.
#[no_mangle]
pub unsafe extern "C" fn ct_scene_texture_color_space(
    scene: CtScene,
    index: u32,
    out_color_space: *mut u32,
) -> CtStatus {
    guard(|| {
        require_out(out_color_space, "out_color_space")?;
        let object = handles::scene(scene)?;
        let i = texture_index(&object, index)?;
        let desc = &object.scene.textures[i];
        let recorded = || match &desc.source {
            crate::scene::TextureSource::File(path) => crate::texture::file_color_space(path),
            crate::scene::TextureSource::Encoded { .. } => None,
        };
        let stated = desc.color_space.or_else(recorded);
        let space = match stated.unwrap_or(ColorSpace::Srgb) {
            ColorSpace::Srgb => CT_COLOR_SPACE_SRGB,
            ColorSpace::Linear => CT_COLOR_SPACE_LINEAR,
        };
        unsafe { write_out(out_color_space, space, "out_color_space") }?;
        Ok(CtStatus::CT_OK)
    })
}
