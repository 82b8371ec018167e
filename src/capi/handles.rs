//! Opaque handles and the registry that validates them.
//!
//! A handle is a small struct holding a 64-bit id. Ids come from a counter that never repeats,
//! and every live object sits in one global registry keyed by id, so a freed (dangling) handle,
//! a handle freed twice, a forged id, the null handle (id 0) and a handle of the wrong kind are
//! all detected by a map lookup and rejected with `CT_ERROR_INVALID_HANDLE`; nothing is ever
//! dereferenced through a stale id. The registry holds `Arc`s: a call that is using an object
//! keeps it alive even if another thread frees its handle meanwhile.

use std::collections::BTreeMap;
use std::ffi::CString;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use crate::film::Film;
use crate::scene::{SceneDescription, ToneMap};
use crate::texture::Texture;

use super::errors::{CapiError, CtStatus};

/// A loaded scene. `id == 0` is the null handle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CtScene {
    /// Registry id; treat as opaque.
    pub id: u64,
}

/// A rendered image (all channels, planar float). `id == 0` is the null handle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CtImage {
    /// Registry id; treat as opaque.
    pub id: u64,
}

/// A loaded texture with its mip pyramid. `id == 0` is the null handle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CtTexture {
    /// Registry id; treat as opaque.
    pub id: u64,
}

/// A scene and the C strings handed out about it.
pub(crate) struct SceneObject {
    pub scene: Arc<SceneDescription>,
    pub texture_names: Vec<CString>,
    /// `None` for textures embedded in a file (glTF buffers, the built-in scene).
    pub texture_paths: Vec<Option<CString>>,
}

/// A film, its channel names as C strings, and what PNG output needs.
pub(crate) struct ImageObject {
    pub film: Film,
    pub channel_names: Vec<CString>,
    pub complete: bool,
    pub finished_tiles: u32,
    pub tonemap: ToneMap,
    pub exposure: f32,
    /// The camera's standard OpenEXR matrices (see `camera::matrices`), when it had one.
    pub world_to_camera: Option<[[f32; 4]; 4]>,
    pub world_to_ndc: Option<[[f32; 4]; 4]>,
}

/// Everything a handle can name.
#[derive(Clone)]
pub(crate) enum Object {
    Scene(Arc<SceneObject>),
    Image(Arc<ImageObject>),
    Texture(Arc<Texture>),
}

impl Object {
    fn kind(&self) -> &'static str {
        match self {
            Object::Scene(_) => "scene",
            Object::Image(_) => "image",
            Object::Texture(_) => "texture",
        }
    }
}

/// "an image", "a scene": the kind with its indefinite article, for messages.
fn with_article(kind: &str) -> String {
    let article = if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {kind}")
}

static OBJECTS: Mutex<BTreeMap<u64, Object>> = Mutex::new(BTreeMap::new());
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

fn objects() -> MutexGuard<'static, BTreeMap<u64, Object>> {
    // A panic never happens while the lock is held, but stay usable if it ever did.
    OBJECTS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Adds an object and returns its new id.
pub(crate) fn insert(object: Object) -> u64 {
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    objects().insert(id, object);
    id
}

/// The object behind `id`, if it is live and of kind `kind`.
fn get(id: u64, kind: &'static str) -> Result<Object, CapiError> {
    if id == 0 {
        return Err(CapiError::new(
            CtStatus::CT_ERROR_INVALID_HANDLE,
            format!("the {kind} handle is null"),
        ));
    }
    match objects().get(&id) {
        Some(object) if object.kind() == kind => Ok(object.clone()),
        Some(object) => Err(CapiError::new(
            CtStatus::CT_ERROR_INVALID_HANDLE,
            format!(
                "handle {id} is {}, not {}",
                with_article(object.kind()),
                with_article(kind)
            ),
        )),
        None => Err(CapiError::new(
            CtStatus::CT_ERROR_INVALID_HANDLE,
            format!("{kind} handle {id} is not live (already freed, or never created)"),
        )),
    }
}

/// Removes `id` if it is a live object of kind `kind`. The null handle is a no-op.
pub(crate) fn remove(id: u64, kind: &'static str) -> Result<(), CapiError> {
    if id == 0 {
        return Ok(());
    }
    let mut objects = objects();
    match objects.get(&id) {
        Some(object) if object.kind() == kind => {
            objects.remove(&id);
            Ok(())
        }
        Some(object) => Err(CapiError::new(
            CtStatus::CT_ERROR_INVALID_HANDLE,
            format!(
                "handle {id} is {}, not {}",
                with_article(object.kind()),
                with_article(kind)
            ),
        )),
        None => Err(CapiError::new(
            CtStatus::CT_ERROR_INVALID_HANDLE,
            format!("{kind} handle {id} is not live (already freed, or never created)"),
        )),
    }
}

pub(crate) fn scene(handle: CtScene) -> Result<Arc<SceneObject>, CapiError> {
    match get(handle.id, "scene")? {
        Object::Scene(s) => Ok(s),
        _ => unreachable_kind(),
    }
}

pub(crate) fn image(handle: CtImage) -> Result<Arc<ImageObject>, CapiError> {
    match get(handle.id, "image")? {
        Object::Image(i) => Ok(i),
        _ => unreachable_kind(),
    }
}

pub(crate) fn texture(handle: CtTexture) -> Result<Arc<Texture>, CapiError> {
    match get(handle.id, "texture")? {
        Object::Texture(t) => Ok(t),
        _ => unreachable_kind(),
    }
}

fn unreachable_kind<T>() -> Result<T, CapiError> {
    Err(CapiError::new(
        CtStatus::CT_ERROR_INTERNAL,
        "registry returned an object of the wrong kind",
    ))
}
