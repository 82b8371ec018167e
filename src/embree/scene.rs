//! Scene building and the committed, immutable scene that rays are traced against.
//!
//! [`SceneBuilder`] owns an uncommitted Embree scene and its geometries; `commit` consumes it
//! and returns a [`CommittedScene`], which has no mutating methods, is `Send + Sync` (Embree's
//! trace calls are thread-safe on a committed scene) and is meant to be shared across rayon
//! threads in an `Arc`. Both hold a [`Device`] clone, so the device outlives them.
//!
//! Scenes are built in Embree's robust mode (`RTC_SCENE_FLAG_ROBUST`) unless
//! [`SceneBuilder::set_robust`] turns it off. Embree's default triangle test is not
//! watertight: a ray aimed at the edge two triangles share can slip between them (12 pixels
//! of a head-on, translated two-triangle quad; see `tests/watertight.rs`). Robust mode
//! selects Embree's watertight triangle test and conservative BVH traversal, so camera,
//! secondary and shadow rays hit one of the two triangles. What it costs in speed is
//! measured in docs/benchmarks.md ("Watertight traversal").

use std::ffi::c_void;

use glam::Vec3;

use super::context::TraceContext;
use super::device::Device;
use super::error::EmbreeError;
use super::ffi;
use super::geometry::GeometryRecord;

/// A geometry being built: Embree's handle and the user data it points to.
struct PendingGeometry {
    raw: ffi::RTCGeometry,
    record: Box<GeometryRecord>,
}

/// An Embree scene under construction.
pub struct SceneBuilder {
    pub(crate) device: Device,
    raw: ffi::RTCScene,
    geometries: Vec<PendingGeometry>,
    robust: bool,
}

// SAFETY: the builder exclusively owns its Embree scene and geometries (never shared before
// commit), so moving it to another thread moves that ownership; filters are Send + Sync.
unsafe impl Send for SceneBuilder {}

impl Drop for SceneBuilder {
    fn drop(&mut self) {
        // SAFETY: the builder holds one reference to each handle; `commit` empties
        // `geometries` and nulls `raw` when it hands them on.
        unsafe {
            for g in &self.geometries {
                ffi::rtcReleaseGeometry(g.raw);
            }
            if !self.raw.is_null() {
                ffi::rtcReleaseScene(self.raw);
            }
        }
    }
}

impl SceneBuilder {
    /// An empty scene on `device`, in robust (watertight) mode.
    pub fn new(device: &Device) -> Result<SceneBuilder, EmbreeError> {
        // SAFETY: the device is live (the builder keeps a clone).
        let raw = unsafe { ffi::rtcNewScene(device.raw()) };
        device.check("rtcNewScene")?;
        if raw.is_null() {
            return Err(EmbreeError::Embree {
                operation: "rtcNewScene",
                code: "RTC_ERROR_UNKNOWN",
                message: String::from("Embree returned no scene"),
            });
        }
        let mut builder = SceneBuilder {
            device: device.clone(),
            raw,
            geometries: Vec::new(),
            robust: false,
        };
        builder.set_robust(true)?;
        Ok(builder)
    }

    /// Robust mode on (the default: watertight triangle tests, no ray slips between
    /// triangles that share an edge) or off (Embree's faster, non-watertight default).
    pub fn set_robust(&mut self, robust: bool) -> Result<(), EmbreeError> {
        let flags = if robust {
            ffi::RTC_SCENE_FLAG_ROBUST
        } else {
            ffi::RTC_SCENE_FLAG_NONE
        };
        // SAFETY: the scene is live and not yet committed.
        unsafe { ffi::rtcSetSceneFlags(self.raw, flags) };
        self.device.check("rtcSetSceneFlags")?;
        self.robust = robust;
        Ok(())
    }

    /// The BVH build quality: `true` for Embree's high quality (SAH with spatial splits,
    /// `RTC_BUILD_QUALITY_HIGH`: a slower build that pays back on long renders of large
    /// triangle meshes), `false` for its default medium quality.
    pub fn set_high_build_quality(&mut self, high: bool) -> Result<(), EmbreeError> {
        let quality = if high {
            ffi::RTC_BUILD_QUALITY_HIGH
        } else {
            ffi::RTC_BUILD_QUALITY_MEDIUM
        };
        // SAFETY: the scene is live and not yet committed.
        unsafe { ffi::rtcSetSceneBuildQuality(self.raw, quality) };
        self.device.check("rtcSetSceneBuildQuality")
    }

    /// Number of geometries added so far (the next geometry id).
    pub fn geometry_count(&self) -> u32 {
        self.geometries.len() as u32
    }

    pub(crate) fn new_geometry(
        &mut self,
        kind: ffi::RTCGeometryType,
    ) -> Result<ffi::RTCGeometry, EmbreeError> {
        // SAFETY: the device is live; the returned handle is checked for null and, once
        // `attach`ed, owned by `self.geometries`.
        let raw = unsafe { ffi::rtcNewGeometry(self.device.raw(), kind) };
        self.device.check("rtcNewGeometry")?;
        if raw.is_null() {
            return Err(EmbreeError::Embree {
                operation: "rtcNewGeometry",
                code: "RTC_ERROR_UNKNOWN",
                message: String::from("Embree returned no geometry"),
            });
        }
        // Owned by the builder from here, so an early error return still releases it.
        self.geometries.push(PendingGeometry {
            raw,
            record: Box::new(GeometryRecord {
                index: u32::MAX,
                filter: None,
                user: None,
            }),
        });
        Ok(raw)
    }

    /// Releases the geometry most recently created by `new_geometry` (after a failed fill).
    pub(crate) fn discard_last_geometry(&mut self) {
        if let Some(g) = self.geometries.pop() {
            // SAFETY: the handle is live, not attached, and this was our only reference.
            unsafe { ffi::rtcReleaseGeometry(g.raw) };
        }
    }

    /// Attaches the geometry most recently created by `new_geometry` under the next id.
    pub(crate) fn attach(&mut self, raw: ffi::RTCGeometry) -> Result<u32, EmbreeError> {
        let id = (self.geometries.len() - 1) as u32;
        let Some(pending) = self.geometries.last_mut() else {
            return Err(EmbreeError::UnknownGeometry { geom_id: id });
        };
        pending.record.index = id;
        let user = &mut *pending.record as *mut GeometryRecord as *mut c_void;
        // SAFETY: scene and geometry are live; the record is boxed, so `user` stays valid
        // until the scene (which owns the records after commit) releases the Embree scene.
        unsafe {
            ffi::rtcSetGeometryUserData(raw, user);
            ffi::rtcAttachGeometryByID(self.raw, raw, id);
        }
        self.device.check("rtcAttachGeometryByID")?;
        Ok(id)
    }

    /// The Embree handle and record of geometry `geom_id`.
    pub(crate) fn geometry_mut(
        &mut self,
        geom_id: u32,
    ) -> Result<(ffi::RTCGeometry, &mut GeometryRecord), EmbreeError> {
        match self.geometries.get_mut(geom_id as usize) {
            Some(g) => Ok((g.raw, &mut g.record)),
            None => Err(EmbreeError::UnknownGeometry { geom_id }),
        }
    }

    /// Builds the acceleration structure. The result cannot be modified.
    pub fn commit(mut self) -> Result<CommittedScene, EmbreeError> {
        let geometries = std::mem::take(&mut self.geometries);
        let mut records = Vec::with_capacity(geometries.len());
        for g in geometries {
            // SAFETY: each handle is live and attached; after committing it we drop our
            // reference (the scene keeps its own).
            unsafe {
                ffi::rtcCommitGeometry(g.raw);
                ffi::rtcReleaseGeometry(g.raw);
            }
            records.push(g.record);
        }
        self.device.check("rtcCommitGeometry")?;
        // SAFETY: the scene is live and every attached geometry is committed.
        unsafe { ffi::rtcCommitScene(self.raw) };
        self.device.check("rtcCommitScene")?;
        let raw = std::mem::replace(&mut self.raw, std::ptr::null_mut());
        Ok(CommittedScene {
            device: self.device.clone(),
            raw,
            records,
            robust: self.robust,
        })
    }
}

/// Axis-aligned bounds of a committed scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Minimum corner.
    pub lower: Vec3,
    /// Maximum corner.
    pub upper: Vec3,
}

/// A committed, immutable Embree scene: trace rays against it from any thread.
pub struct CommittedScene {
    device: Device,
    raw: ffi::RTCScene,
    /// User data of the geometries; Embree points at these until `rtcReleaseScene`.
    /// Boxed so those addresses survive the move out of the builder.
    #[allow(clippy::vec_box)]
    records: Vec<Box<GeometryRecord>>,
    robust: bool,
}

// SAFETY: Embree's intersect/occluded calls and rtcGetSceneBounds are thread-safe on a
// committed scene (embree issue #207: only modification is not), and `CommittedScene` offers
// no modification. The records are immutable after commit and their filters are Send + Sync.
unsafe impl Send for CommittedScene {}
// SAFETY: as above.
unsafe impl Sync for CommittedScene {}

impl Drop for CommittedScene {
    fn drop(&mut self) {
        // SAFETY: our single reference to a live scene; the records and the device are
        // dropped after this body, i.e. after Embree stops using them.
        unsafe { ffi::rtcReleaseScene(self.raw) };
    }
}

impl std::fmt::Debug for CommittedScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommittedScene")
            .field("geometries", &self.records.len())
            .field("packet_width", &self.packet_width())
            .field("stream_supported", &self.stream_supported())
            .field("robust", &self.robust)
            .finish()
    }
}

impl CommittedScene {
    pub(crate) fn raw(&self) -> ffi::RTCScene {
        self.raw
    }

    /// The device this scene was built on.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The widest packet traces use (16, 8, 4, or 1 for single rays only; see
    /// [`Device::packet_width`]); packet traces dispatch on it.
    pub fn packet_width(&self) -> usize {
        self.device.packet_width()
    }

    /// Whether traces use Embree's ray streams; without them, streams are traced ray by ray.
    pub fn stream_supported(&self) -> bool {
        self.device.stream_supported()
    }

    /// Whether the scene was built in robust (watertight) mode.
    pub fn is_robust(&self) -> bool {
        self.robust
    }

    /// Number of geometries; ids run from 0 to `geometry_count() - 1`.
    pub fn geometry_count(&self) -> u32 {
        self.records.len() as u32
    }

    /// Whether geometry `geom_id` has an alpha filter.
    pub fn has_alpha_filter(&self, geom_id: u32) -> bool {
        self.records
            .get(geom_id as usize)
            .is_some_and(|r| r.filter.is_some())
    }

    /// Ends one trace call: an error Embree reported on this thread during the call (read
    /// with `rtcGetDeviceError`, so a failed traversal is never taken for misses) comes
    /// first, then a panic of a filter callback.
    pub(crate) fn finish_trace(
        &self,
        context: TraceContext,
        operation: &'static str,
    ) -> Result<(), EmbreeError> {
        let embree = self.device.check(operation);
        let filters = context.finish();
        embree.and(filters)
    }

    /// World-space bounds of everything in the scene (`rtcGetSceneBounds`).
    pub fn bounds(&self) -> Bounds {
        let mut b = ffi::RTCBounds::default();
        // SAFETY: the scene is committed and live; `b` is a writable RTCBounds.
        unsafe { ffi::rtcGetSceneBounds(self.raw, &mut b) };
        Bounds {
            lower: Vec3::new(b.lower_x, b.lower_y, b.lower_z),
            upper: Vec3::new(b.upper_x, b.upper_y, b.upper_z),
        }
    }
}
