//! Geometry creation: indexed triangle meshes and sphere sets (Embree's
//! `RTC_GEOMETRY_TYPE_SPHERE_POINT`), copied into Embree-owned buffers.
//!
//! Each geometry carries a [`GeometryRecord`] as Embree user data: its geometry index (the
//! id the scene builder handed out) and the optional alpha filter its filter callbacks run.

use glam::Vec3;

use super::error::EmbreeError;
use super::ffi;
use super::filter::AlphaFilter;
use super::scene::SceneBuilder;

/// Per-geometry user data, boxed so Embree's pointer to it stays valid while it is moved
/// from the builder to the committed scene.
pub(crate) struct GeometryRecord {
    /// Our geometry index (equal to Embree's geometry id in this scene).
    pub index: u32,
    pub filter: Option<AlphaFilter>,
    /// The Rust intersector of a user geometry (`super::user_geometry`).
    pub user: Option<std::sync::Arc<dyn super::user_geometry::UserGeometry>>,
}

impl SceneBuilder {
    /// Adds an indexed triangle mesh; returns its geometry id (0, 1, 2, ... in add order).
    /// Every index must be below `vertices.len()`.
    pub fn add_triangle_mesh(
        &mut self,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<u32, EmbreeError> {
        check_count("triangle mesh", triangles.len())?;
        check_count("triangle mesh vertex buffer", vertices.len())?;
        for (triangle, corners) in triangles.iter().enumerate() {
            if let Some(&index) = corners.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(EmbreeError::IndexOutOfRange {
                    triangle,
                    index,
                    vertex_count: vertices.len(),
                });
            }
        }
        let geometry = self.new_geometry(ffi::RTC_GEOMETRY_TYPE_TRIANGLE)?;
        if let Err(err) = self.fill_triangle_buffers(geometry, vertices, triangles) {
            self.discard_last_geometry();
            return Err(err);
        }
        self.attach(geometry)
    }

    fn fill_triangle_buffers(
        &self,
        geometry: ffi::RTCGeometry,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<(), EmbreeError> {
        // SAFETY: `geometry` is a live geometry owned by this builder. rtcSetNewGeometryBuffer
        // returns a buffer of `count * stride` bytes (Embree adds the padding its SIMD loads
        // need), or null on error; we write exactly `count` items of the declared format.
        unsafe {
            let dst = ffi::rtcSetNewGeometryBuffer(
                geometry,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT3,
                12,
                vertices.len(),
            ) as *mut [f32; 3];
            self.device.check("rtcSetNewGeometryBuffer (vertices)")?;
            if dst.is_null() {
                return Err(null_buffer("triangle vertices"));
            }
            for (i, p) in vertices.iter().enumerate() {
                dst.add(i).write([p.x, p.y, p.z]);
            }
            let dst = ffi::rtcSetNewGeometryBuffer(
                geometry,
                ffi::RTC_BUFFER_TYPE_INDEX,
                0,
                ffi::RTC_FORMAT_UINT3,
                12,
                triangles.len(),
            ) as *mut [u32; 3];
            self.device.check("rtcSetNewGeometryBuffer (indices)")?;
            if dst.is_null() {
                return Err(null_buffer("triangle indices"));
            }
            std::ptr::copy_nonoverlapping(triangles.as_ptr(), dst, triangles.len());
        }
        Ok(())
    }

    /// Adds a set of spheres `(centre, radius)` as one geometry; returns its geometry id.
    /// A hit's `prim_id` is the sphere's index in `spheres`.
    pub fn add_spheres(&mut self, spheres: &[(Vec3, f32)]) -> Result<u32, EmbreeError> {
        check_count("sphere set", spheres.len())?;
        for (index, (center, radius)) in spheres.iter().enumerate() {
            if !(center.is_finite() && radius.is_finite() && *radius >= 0.0) {
                return Err(EmbreeError::InvalidSphere {
                    index,
                    radius: *radius,
                });
            }
        }
        let geometry = self.new_geometry(ffi::RTC_GEOMETRY_TYPE_SPHERE_POINT)?;
        if let Err(err) = self.fill_sphere_buffer(geometry, spheres) {
            self.discard_last_geometry();
            return Err(err);
        }
        self.attach(geometry)
    }

    fn fill_sphere_buffer(
        &self,
        geometry: ffi::RTCGeometry,
        spheres: &[(Vec3, f32)],
    ) -> Result<(), EmbreeError> {
        // SAFETY: as in `fill_triangle_buffers`; FLOAT4 items are (x, y, z, radius).
        unsafe {
            let dst = ffi::rtcSetNewGeometryBuffer(
                geometry,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT4,
                16,
                spheres.len(),
            ) as *mut [f32; 4];
            self.device.check("rtcSetNewGeometryBuffer (spheres)")?;
            if dst.is_null() {
                return Err(null_buffer("sphere vertices"));
            }
            for (i, (c, r)) in spheres.iter().enumerate() {
                dst.add(i).write([c.x, c.y, c.z, *r]);
            }
        }
        Ok(())
    }
}

fn check_count(kind: &'static str, count: usize) -> Result<(), EmbreeError> {
    if count == 0 || count >= u32::MAX as usize {
        return Err(EmbreeError::BadPrimitiveCount { kind, count });
    }
    Ok(())
}

fn null_buffer(what: &'static str) -> EmbreeError {
    EmbreeError::Embree {
        operation: "rtcSetNewGeometryBuffer",
        code: "RTC_ERROR_OUT_OF_MEMORY",
        message: format!("no buffer for {what}"),
    }
}
