//! Curved patches in the Embree scene and back: the user geometry that traces a scene's
//! patches exactly, and the [`SurfaceHit`] of a hit on one.
//!
//! All patches of a scene form one Embree user geometry whose primitive `i` is
//! `SceneDescription::patches[i]`; its bounds are the box of the control points (which
//! contains the patch) and its intersections are `crate::scene::patch::intersect`'s. A scene
//! without patches has no user geometry at all, so triangle-only scenes pay nothing.
//!
//! Height patches (`crate::scene::patch::height`) form a second user geometry, traced by
//! marching; a hit on one is rebuilt from the same surface as a Bezier patch.
//!
//! A hit is rebuilt from the patch itself at the hit's (u, v): the position, the normal
//! `P_u x P_v` (from just inside a collapsed edge), and the exact first and second
//! derivatives that footprints use (`crate::footprint`, "Curved patches").

use glam::{DVec3, Vec2, Vec3};

use crate::embree::{Bounds, UserGeometry, UserHit, UserRay};
use crate::hit::{CurvedFrame, Patch, SurfaceHit};
use crate::render::tracer::TraceHit;
use crate::scene::patch::height::HeightPatch;
use crate::scene::patch::intersect::{geometric_normal, PatchIntersector, PatchRay};
use crate::scene::patch::{control_f64, evaluate, BezierPatch};
use crate::shading::ray_offset::SpawnPoint;

/// The scene's patches as Embree user primitives.
pub struct PatchGeometry {
    intersectors: Vec<PatchIntersector>,
    bounds: Vec<Bounds>,
}

impl PatchGeometry {
    pub fn new(patches: &[BezierPatch]) -> PatchGeometry {
        PatchGeometry {
            intersectors: patches
                .iter()
                .map(|p| PatchIntersector::new(&p.control))
                .collect(),
            bounds: patches
                .iter()
                .map(|p| {
                    let (lower, upper) = p.bounds();
                    Bounds { lower, upper }
                })
                .collect(),
        }
    }
}

impl UserGeometry for PatchGeometry {
    fn primitive_count(&self) -> u32 {
        self.intersectors.len() as u32
    }

    fn bounds(&self, primitive: u32) -> Bounds {
        self.bounds[primitive as usize]
    }

    fn intersect(&self, primitive: u32, ray: &UserRay, any_hit: bool) -> Option<UserHit> {
        self.intersect_accepting(primitive, ray, any_hit, &mut |_| true)
    }

    fn intersect_accepting(
        &self,
        primitive: u32,
        ray: &UserRay,
        any_hit: bool,
        accept: &mut dyn FnMut(&UserHit) -> bool,
    ) -> Option<UserHit> {
        let query = patch_ray(ray);
        let mut accept_root = |t: f64, u: f64, v: f64| accept(&candidate_hit(t, u, v));
        let hit = self.intersectors[primitive as usize].intersect_accepting(
            &query,
            any_hit,
            &mut accept_root,
        )?;
        reported_hit(ray, hit.t, hit.u, hit.v, hit.normal)
    }
}

/// An Embree user ray in the f64 form the patch intersectors take.
fn patch_ray(ray: &UserRay) -> PatchRay {
    PatchRay {
        origin: ray.origin.as_dvec3(),
        direction: ray.direction.as_dvec3(),
        tnear: f64::from(ray.tnear),
        tfar: f64::from(ray.tfar),
    }
}

/// A root as the alpha test sees it: the hit as it will be reported (f32), before its normal
/// is known.
fn candidate_hit(t: f64, u: f64, v: f64) -> UserHit {
    UserHit {
        t: t as f32,
        u: u as f32,
        v: v as f32,
        normal: Vec3::ZERO,
    }
}

/// The hit reported to Embree, or `None` when rounding t to f32 moved it out of the ray's
/// interval.
fn reported_hit(ray: &UserRay, t: f64, u: f64, v: f64, normal: DVec3) -> Option<UserHit> {
    let t = t as f32;
    (t > ray.tnear && t < ray.tfar).then_some(UserHit {
        t,
        u: u as f32,
        v: v as f32,
        normal: normal.as_vec3(),
    })
}

/// The scene's height patches as Embree user primitives, traced by ray marching
/// (`crate::scene::patch::height`); a hit's (u, v) are the patch's.
pub struct HeightPatchGeometry {
    pub patches: Vec<HeightPatch>,
}

impl UserGeometry for HeightPatchGeometry {
    fn primitive_count(&self) -> u32 {
        self.patches.len() as u32
    }

    fn bounds(&self, primitive: u32) -> Bounds {
        let (lower, upper) = self.patches[primitive as usize].bounds();
        Bounds { lower, upper }
    }

    fn intersect(&self, primitive: u32, ray: &UserRay, any_hit: bool) -> Option<UserHit> {
        self.intersect_accepting(primitive, ray, any_hit, &mut |_| true)
    }

    /// Marching finds crossings in order, so the first is also what a shadow ray needs.
    fn intersect_accepting(
        &self,
        primitive: u32,
        ray: &UserRay,
        _any_hit: bool,
        accept: &mut dyn FnMut(&UserHit) -> bool,
    ) -> Option<UserHit> {
        let query = patch_ray(ray);
        let mut accept_root = |t: f64, u: f64, v: f64| accept(&candidate_hit(t, u, v));
        let hit = self.patches[primitive as usize].march_accepting(&query, &mut accept_root)?;
        reported_hit(ray, hit.t, hit.u, hit.v, hit.normal)
    }
}

/// The surface at a hit on `patch` (the trace hit's u, v are the patch's).
pub fn patch_surface_hit(patch: &BezierPatch, hit: &TraceHit, texturing: bool) -> SurfaceHit {
    let point = patch_surface_point(patch, (hit.u, hit.v), texturing);
    SurfaceHit {
        t: hit.t,
        position: point.spawn.position,
        geometric_normal: point.normal,
        shading_normal: point.normal,
        barycentric: Vec2::new(hit.u, hit.v),
        st: point.st,
        dpds: point.dpds,
        dpdt: point.dpdt,
        material: patch.material as u32,
        patch: Patch::Curved {
            frame: point.frame,
            dstdu: point.dstdu,
            dstdv: point.dstdv,
            error: point.spawn.error,
        },
    }
}

/// What a patch gives at a hit's (u, v), field by field: the makings of its
/// [`SurfaceHit`], which the shading lanes store one array per field instead.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PatchSurfacePoint {
    /// The point and the bound on its rounding error.
    pub spawn: SpawnPoint,
    /// Unit normal `P_u x P_v` (geometric and shading).
    pub normal: Vec3,
    /// Texture coordinates and dP/ds, dP/dt (zero unless `texturing`).
    pub st: Vec2,
    pub dpds: Vec3,
    pub dpdt: Vec3,
    /// The exact derivatives footprints read (`Patch::Curved`).
    pub frame: CurvedFrame,
    pub dstdu: Vec2,
    pub dstdv: Vec2,
}

/// The surface of `patch` at `(u, v)` (a hit's, as the intersector reported them), with
/// texture coordinates and dP/ds, dP/dt when `texturing`.
///
/// The position is the patch evaluated in f64 at the f32 (u, v) the hit reports, so it lies
/// on the surface up to its rounding to f32; its error bound is that rounding plus the
/// intersector slack of `crate::shading::ray_offset`, on the magnitude of the control points.
#[inline]
pub(crate) fn patch_surface_point(
    patch: &BezierPatch,
    (u, v): (f32, f32),
    texturing: bool,
) -> PatchSurfacePoint {
    let control = control_f64(&patch.control);
    let point = evaluate(&control, f64::from(u), f64::from(v));
    let normal = geometric_normal(&control, f64::from(u), f64::from(v))
        .try_normalize()
        .unwrap_or(DVec3::Y)
        .as_vec3();
    let magnitude = patch.control.iter().fold(Vec3::ZERO, |m, p| m.max(p.abs()));
    let spawn = SpawnPoint::on_curved_patch(point.position, magnitude);
    let dpdu = point.dpdu.as_vec3();
    let dpdv = point.dpdv.as_vec3();
    let (st, dstdu, dstdv) = patch.st(u, v);
    let (st, dpds, dpdt) = if texturing {
        let (dpds, dpdt) = position_st_derivatives(dpdu, dpdv, dstdu, dstdv);
        (st, dpds, dpdt)
    } else {
        (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO)
    };
    PatchSurfacePoint {
        spawn,
        normal,
        st,
        dpds,
        dpdt,
        frame: CurvedFrame {
            dpdu,
            dpdv,
            d2pdu2: point.d2pdu2.as_vec3(),
            d2pdudv: point.d2pdudv.as_vec3(),
            d2pdv2: point.d2pdv2.as_vec3(),
        },
        dstdu,
        dstdv,
    }
}

/// dP/ds and dP/dt from dP/du, dP/dv and the st map's derivatives: `[P_u P_v] = [P_s P_t] J`
/// with `J = [st_u st_v]`, so `[P_s P_t] = [P_u P_v] J^-1` (zero where J is singular).
fn position_st_derivatives(dpdu: Vec3, dpdv: Vec3, dstdu: Vec2, dstdv: Vec2) -> (Vec3, Vec3) {
    let det = dstdu.x * dstdv.y - dstdv.x * dstdu.y;
    let inv = det.recip();
    if !(inv.is_finite()) {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let dpds = (dpdu * dstdv.y - dpdv * dstdu.y) * inv;
    let dpdt = (dpdv * dstdu.x - dpdu * dstdv.x) * inv;
    if dpds.is_finite() && dpdt.is_finite() {
        (dpds, dpdt)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn st_derivatives_invert_the_parameter_map() {
        let (dpdu, dpdv) = (Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.1, 1.5, 0.3));
        let (su, sv) = (Vec2::new(2.0, 0.5), Vec2::new(-0.25, 1.0));
        let (ps, pt) = position_st_derivatives(dpdu, dpdv, su, sv);
        // Chain rule back: P_u = P_s s_u + P_t t_u.
        assert!((ps * su.x + pt * su.y - dpdu).length() < 1e-6);
        assert!((ps * sv.x + pt * sv.y - dpdv).length() < 1e-6);
    }
}
