//! A ray's hit, described by the surface around it: the one record shading and footprints read.
//!
//! `crate::render` builds a [`SurfaceHit`] from Embree's hit (geometry id, primitive id,
//! barycentrics, distance) and the scene's vertex data. Footprints (`crate::footprint`) read
//! the [`Patch`] to differentiate positions, normals and texture coordinates; shading reads
//! the normals, texture coordinates and material; rays leaving the hit start from its
//! [`SurfaceHit::spawn_point`].

use glam::{Vec2, Vec3};

use crate::shading::ray_offset::SpawnPoint;

/// The local surface a hit lies on, with what footprints need to differentiate it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Patch {
    /// A triangle with vertices `p`, optional per-vertex shading normals `n` (as stored,
    /// not necessarily unit length) and optional texture coordinates `st`.
    /// Barycentrics follow Embree: `P = (1-u-v) p[0] + u p[1] + v p[2]`.
    Triangle {
        p: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        st: Option<[Vec2; 3]>,
    },
    /// An analytic sphere; st is its lat-long parameterisation (see `crate::scene::Sphere`).
    Sphere { center: Vec3, radius: f32 },
    /// A point of a curved patch (`crate::scene::patch`) with its exact local differential
    /// geometry at the hit's (u, v): first and second partial derivatives of the position,
    /// the derivatives of the texture coordinates with respect to u and v, and the bound on
    /// the rounding error of the hit's position.
    Curved {
        frame: CurvedFrame,
        dstdu: Vec2,
        dstdv: Vec2,
        error: Vec3,
    },
}

/// The exact local geometry of a curved patch at a hit: first and second partial
/// derivatives of the position with respect to the patch's (u, v). Its differential
/// geometry (fundamental forms, normal derivatives, curvature) is in
/// `crate::footprint::patch_surface`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvedFrame {
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub d2pdu2: Vec3,
    pub d2pdudv: Vec3,
    pub d2pdv2: Vec3,
}

/// A hit on a surface, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Distance along the (unit-length) ray direction, as the intersector reported it.
    pub t: f32,
    /// The point on the surface, recomputed from the surface itself (barycentric
    /// interpolation of the triangle's vertices, projection onto the sphere), not from the
    /// ray: its rounding error does not grow with the ray's origin or length (see
    /// [`SurfaceHit::spawn_point`]).
    pub position: Vec3,
    /// Unit geometric normal, facing outward (as the geometry is wound / the sphere's outside).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated vertex normals, or the geometric normal),
    /// facing the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    /// Barycentric (u, v) on a triangle; (s, t) on a sphere; the patch's (u, v) on a curved
    /// patch.
    pub barycentric: Vec2,
    /// Texture coordinates in OpenImageIO convention (zero when the surface has none).
    pub st: Vec2,
    /// World-space partial derivatives of position with respect to s and t
    /// (zero vectors when the surface has no texture parameterisation).
    pub dpds: Vec3,
    pub dpdt: Vec3,
    /// Index into `SceneDescription::materials`.
    pub material: u32,
    pub patch: Patch,
}

impl SurfaceHit {
    /// True when the ray arrived from the side the geometric normal points to.
    pub fn is_front_face(&self, ray_direction: Vec3) -> bool {
        ray_direction.dot(self.geometric_normal) < 0.0
    }

    /// `position` with the bound on its rounding error, where rays leaving this hit start
    /// (`crate::shading::ray_offset`). The bound follows from the patch: a triangle point is
    /// `b0 p0 + b1 p1 + b2 p2` at `barycentric`, a sphere point the projection onto the
    /// sphere, exactly as `crate::render` computes `position`.
    #[inline]
    pub fn spawn_point(&self) -> SpawnPoint {
        match self.patch {
            Patch::Triangle { p, .. } => {
                SpawnPoint::on_triangle(p, self.barycentric.x, self.barycentric.y)
            }
            Patch::Sphere { center, radius } => {
                SpawnPoint::on_sphere(center, radius, self.position).0
            }
            Patch::Curved { error, .. } => SpawnPoint {
                position: self.position,
                error,
            },
        }
    }
}
