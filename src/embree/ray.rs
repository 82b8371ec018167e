//! Single rays and hit records: [`Ray`] (what to trace), [`Hit`] (what Embree found, as Embree
//! reports it) and [`RayHit`] (Embree's `RTCRayHit` layout, the element of ray streams).

use glam::Vec3;

use super::ffi;

/// Embree's `RTC_INVALID_GEOMETRY_ID`: the geometry id of a miss.
/// (The macro is a cast bindgen cannot emit; `tests::invalid_id_matches_the_c_macro` checks
/// this value against the C shim.)
pub const INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// A ray segment `origin + t * direction`, `t` in `[tnear, tfar]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start of the ray.
    pub origin: Vec3,
    /// Need not be unit length; hit distances `t` are in units of this vector.
    pub direction: Vec3,
    /// Hits closer than this are ignored.
    pub tnear: f32,
    /// Hits farther than this are ignored (`f32::INFINITY` for an unbounded ray).
    pub tfar: f32,
}

impl Ray {
    /// A ray from `tnear = 0` to `tfar = +inf`.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Ray {
        Ray {
            origin,
            direction,
            tnear: 0.0,
            tfar: f32::INFINITY,
        }
    }

    /// A ray restricted to `t` in `[tnear, tfar]`.
    #[inline]
    pub fn segment(origin: Vec3, direction: Vec3, tnear: f32, tfar: f32) -> Ray {
        Ray {
            origin,
            direction,
            tnear,
            tfar,
        }
    }
}

/// The closest hit Embree found for one ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Hit distance (Embree's `tfar` after the trace).
    pub t: f32,
    /// Geometry id (the order in which the geometry was added to the scene).
    pub geom_id: u32,
    /// Primitive within the geometry (triangle index, or sphere index for sphere sets).
    pub prim_id: u32,
    /// Barycentric u (`P = (1-u-v) p0 + u p1 + v p2` on triangles).
    pub u: f32,
    /// Barycentric v.
    pub v: f32,
    /// Geometric normal exactly as Embree returns it: not normalised; for triangles
    /// `(p1 - p0) x (p2 - p0)`, for spheres the outward direction from the centre.
    pub ng: Vec3,
}

/// One ray and its hit in Embree's `RTCRayHit` layout: the element type of ray streams.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct RayHit(pub(crate) ffi::RTCRayHit);

impl RayHit {
    /// A ray ready to be traced (mask all ones, no hit yet).
    #[inline]
    pub fn new(ray: &Ray) -> RayHit {
        RayHit(ffi::RTCRayHit {
            ray: ffi::RTCRay {
                org_x: ray.origin.x,
                org_y: ray.origin.y,
                org_z: ray.origin.z,
                tnear: ray.tnear,
                dir_x: ray.direction.x,
                dir_y: ray.direction.y,
                dir_z: ray.direction.z,
                time: 0.0,
                tfar: ray.tfar,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: ffi::RTCHit {
                geomID: INVALID_GEOMETRY_ID,
                primID: INVALID_GEOMETRY_ID,
                instID: [INVALID_GEOMETRY_ID; ffi::RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
                ..Default::default()
            },
        })
    }

    /// The ray (its `tfar` is the hit distance after an intersect, `-inf` after an
    /// occluded trace that found a blocker).
    #[inline]
    pub fn ray(&self) -> Ray {
        let r = &self.0.ray;
        Ray {
            origin: Vec3::new(r.org_x, r.org_y, r.org_z),
            direction: Vec3::new(r.dir_x, r.dir_y, r.dir_z),
            tnear: r.tnear,
            tfar: r.tfar,
        }
    }

    /// The geometry id of the hit, [`INVALID_GEOMETRY_ID`] for a miss.
    #[inline]
    pub fn geom_id(&self) -> u32 {
        self.0.hit.geomID
    }

    /// The hit after an intersect trace, `None` for a miss.
    #[inline]
    pub fn hit(&self) -> Option<Hit> {
        let h = &self.0.hit;
        if h.geomID == INVALID_GEOMETRY_ID {
            return None;
        }
        Some(Hit {
            t: self.0.ray.tfar,
            geom_id: h.geomID,
            prim_id: h.primID,
            u: h.u,
            v: h.v,
            ng: Vec3::new(h.Ng_x, h.Ng_y, h.Ng_z),
        })
    }

    /// After an occluded trace: whether something blocked the segment
    /// (Embree sets `tfar` to `-inf`).
    #[inline]
    pub fn is_occluded(&self) -> bool {
        self.0.ray.tfar == f32::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_id_matches_the_c_macro() {
        // SAFETY: a shim function with no arguments that returns a constant.
        let from_c = unsafe { ffi::conetrace_rtc_invalid_geometry_id() };
        assert_eq!(INVALID_GEOMETRY_ID, from_c);
        // SAFETY: as above.
        let levels = unsafe { ffi::conetrace_rtc_max_instance_level_count() };
        assert_eq!(levels, ffi::RTC_MAX_INSTANCE_LEVEL_COUNT);
    }

    #[test]
    fn new_ray_hit_is_a_miss_with_the_ray_it_was_given() {
        let ray = Ray::segment(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, 0.5, 7.0);
        let rh = RayHit::new(&ray);
        assert_eq!(rh.ray(), ray);
        assert!(rh.hit().is_none());
        assert_eq!(rh.geom_id(), INVALID_GEOMETRY_ID);
        assert!(!rh.is_occluded());
    }
}
