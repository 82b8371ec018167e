//! Ray footprints: how much of a surface (or environment) one pixel's ray covers, tracked
//! along the ray so that every texture lookup can be filtered over it.
//!
//! Five strategies share one interface, [`Footprint`]:
//! - `mip0`: no footprint, point samples at mip level 0;
//! - `distance`: the camera's pixel spread times the total path length (the baseline);
//! - `cone1`: one ray cone (seed 000);
//! - `cone`: the two-cone envelope (seed 000, "Tracking Two Cones"), the default;
//! - `differential`: ray differentials (seed 002).
//!
//! A footprint is created by the camera (`crate::camera::Camera::initial_footprint`), moved
//! to each hit with [`Footprint::transfer`], turned into texture gradients there with
//! [`Footprint::texture_gradients`], and carried onto secondary rays with
//! [`Footprint::reflect`] or [`Footprint::refract`], or widened by a rough bounce with
//! [`Footprint::scatter`] (`bsdf_spread`). It knows nothing of textures or
//! Embree: it reads the hit record (`crate::hit::SurfaceHit`) and returns st derivatives.
//!
//! Robustness contract: for any finite input (grazing hits down to |D.N| = 1e-7, degenerate
//! or collinear triangles, zero-area st mappings, zero or NaN normals, total internal
//! reflection, eta = 1, cones passing through their apex) every function returns finite
//! values and widths are never negative. Degenerate surfaces fall back to a point sample
//! (zero gradients); zero normals count as a head-on hit; total internal reflection in
//! `refract` falls back to the reflected footprint.

mod bsdf_spread;
mod cone_envelope;
mod curvature;
mod distance;
mod environment;
mod gradients;
mod normal_derivatives;
mod packed_cone;
mod patch_surface;
mod ray_cone;
mod ray_differential;
pub(crate) mod robust;
mod strategy;

use glam::Vec3;

pub use bsdf_spread::{bsdf_spread_angle, DIFFUSE_SPREAD};
pub use cone_envelope::ConeEnvelope;
pub use curvature::{curvature_at, sphere_curvature, triangle_curvature};
pub use distance::DistanceFootprint;
pub use environment::{
    direction_to_lat_long, lat_long_cone_gradients, lat_long_frame, lat_long_offset,
    lat_long_to_direction,
};
pub use gradients::{
    barycentric_offsets, general_st_offset, project_cone_to_ellipse, surface_gradients,
    triangle_st_offset, TextureGradients,
};
pub use normal_derivatives::shading_normal_derivative;
pub use packed_cone::PackedCone;
pub use patch_surface::curved_st_offset;
pub use ray_cone::RayCone;
pub use ray_differential::{normalized_derivative, RayDifferential};
pub use strategy::{LodStrategy, UnknownLodStrategy};

use crate::hit::SurfaceHit;
use robust::unit_direction;

/// A ray's footprint under one of the [`LodStrategy`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Footprint {
    /// No footprint: point samples at mip level 0.
    #[default]
    Mip0,
    /// The distance metric.
    Distance(DistanceFootprint),
    /// A single ray cone.
    Cone1(RayCone),
    /// The two-cone envelope.
    Cone(ConeEnvelope),
    /// Ray differentials.
    Differential(RayDifferential),
}

impl Footprint {
    /// No footprint (point sampling); what rays carry when footprints are switched off.
    #[inline]
    pub fn none() -> Footprint {
        Footprint::Mip0
    }

    /// The strategy this footprint implements.
    #[inline]
    pub fn strategy(&self) -> LodStrategy {
        match self {
            Footprint::Mip0 => LodStrategy::Mip0,
            Footprint::Distance(_) => LodStrategy::Distance,
            Footprint::Cone1(_) => LodStrategy::Cone1,
            Footprint::Cone(_) => LodStrategy::Cone,
            Footprint::Differential(_) => LodStrategy::Differential,
        }
    }

    /// Move the footprint along the ray (unit direction `dir`) to `hit`: cones propagate by
    /// `hit.t` with the sign flip (seed 000, w' = w + alpha d); differentials are transferred
    /// onto the hit's tangent plane (seed 002, eqs. 10-12).
    #[inline]
    pub fn transfer(&mut self, dir: Vec3, hit: &SurfaceHit) {
        match self {
            Footprint::Mip0 => {}
            Footprint::Distance(f) => *f = f.propagate(hit.t),
            Footprint::Cone1(c) => *c = c.propagate(hit.t),
            Footprint::Cone(e) => *e = e.propagate(hit.t),
            Footprint::Differential(d) => *d = d.transfer(dir, hit),
        }
    }

    /// [`Self::transfer`] to a hit at distance `t` for the footprints that read nothing else
    /// of the hit (every one but ray differentials, which give `None`): what the shading
    /// lanes carry a path's footprint with, without a hit record.
    #[inline]
    pub fn propagated(&self, t: f32) -> Option<Footprint> {
        match self {
            Footprint::Mip0 => Some(Footprint::Mip0),
            Footprint::Distance(f) => Some(Footprint::Distance(f.propagate(t))),
            Footprint::Cone1(c) => Some(Footprint::Cone1(c.propagate(t))),
            Footprint::Cone(e) => Some(Footprint::Cone(e.propagate(t))),
            Footprint::Differential(_) => None,
        }
    }

    /// After [`Self::transfer`]: the footprint of the mirror-reflected ray `reflected`.
    /// Cones: alpha' = alpha + 2 k |w| with the curvature seen from the arriving side
    /// (seed 000). Differentials: seed 002, eqs. 13-15 with the shading normal's derivative.
    /// The distance metric is unchanged.
    #[inline]
    pub fn reflect(&self, dir: Vec3, hit: &SurfaceHit, reflected: Vec3) -> Footprint {
        self.reflect_with(dir, reflected, || curvature_at(hit, dir), || hit)
    }

    /// [`Self::reflect`] reading of the hit only what the strategy needs: cones ask
    /// `curvature` for [`curvature_at`]'s value, differentials `hit` for the record, the
    /// others nothing (the shading lanes know a cone's curvature without a record).
    #[inline]
    pub fn reflect_with<'a>(
        &self,
        dir: Vec3,
        reflected: Vec3,
        curvature: impl FnOnce() -> f32,
        hit: impl FnOnce() -> &'a SurfaceHit,
    ) -> Footprint {
        match self {
            Footprint::Mip0 | Footprint::Distance(_) => *self,
            Footprint::Cone1(c) => Footprint::Cone1(c.reflect(curvature())),
            Footprint::Cone(e) => Footprint::Cone(e.reflect(curvature())),
            Footprint::Differential(d) => Footprint::Differential(d.reflect(dir, hit(), reflected)),
        }
    }

    /// After [`Self::transfer`]: the footprint of the refracted ray `refracted`, with
    /// `eta` = n_incident / n_transmitted. Cones: alpha' = eta (alpha + k|w|) - k|w|
    /// (seed 000). Differentials: seed 002, eqs. 16-19 (reflected footprint under total
    /// internal reflection). The distance metric is unchanged.
    #[inline]
    pub fn refract(&self, dir: Vec3, hit: &SurfaceHit, eta: f32, refracted: Vec3) -> Footprint {
        self.refract_with(dir, eta, refracted, || curvature_at(hit, dir), || hit)
    }

    /// [`Self::refract`] reading of the hit only what the strategy needs, as
    /// [`Self::reflect_with`].
    #[inline]
    pub fn refract_with<'a>(
        &self,
        dir: Vec3,
        eta: f32,
        refracted: Vec3,
        curvature: impl FnOnce() -> f32,
        hit: impl FnOnce() -> &'a SurfaceHit,
    ) -> Footprint {
        match self {
            Footprint::Mip0 | Footprint::Distance(_) => *self,
            Footprint::Cone1(c) => Footprint::Cone1(c.refract(curvature(), eta)),
            Footprint::Cone(e) => Footprint::Cone(e.refract(curvature(), eta)),
            Footprint::Differential(d) => {
                Footprint::Differential(d.refract(dir, hit(), eta, refracted))
            }
        }
    }

    /// After [`Self::transfer`]: texture gradients in st units at `hit` for a ray along `dir`.
    /// Cones and the distance metric project their circle onto the surface's tangent plane
    /// as an ellipse, clamping the stretch to `max_aniso` (seed 000), then map it to st
    /// barycentrically on triangles or through dP/ds, dP/dt on spheres. Differentials map
    /// dP/dx, dP/dy the same way (seed 002, section 4); the texture filter clamps their
    /// anisotropy.
    #[inline]
    pub fn texture_gradients(
        &self,
        dir: Vec3,
        hit: &SurfaceHit,
        max_aniso: f32,
    ) -> TextureGradients {
        let width = match self {
            Footprint::Mip0 => return TextureGradients::ZERO,
            Footprint::Differential(d) => return d.texture_gradients(hit),
            Footprint::Distance(f) => f.width(),
            Footprint::Cone1(c) => c.abs_width(),
            Footprint::Cone(e) => e.width(),
        };
        let d = unit_direction(dir);
        let n = robust::unit_normal(hit.geometric_normal, d);
        let (dpdx, dpdy) = project_cone_to_ellipse(width, d, n, max_aniso);
        surface_gradients(hit, dpdx, dpdy)
    }

    /// Gradients for a lat-long environment lookup in direction `dir` (convention of
    /// [`direction_to_lat_long`]). Cones: seed 000's (alpha / 2pi, 0), (0, alpha / pi) with
    /// the s axis widened by 1 / sin(theta) towards the poles ([`lat_long_cone_gradients`]);
    /// differentials: the derivative of the mapping along dD/dx, dD/dy, which holds the
    /// same 1 / sin(theta).
    #[inline]
    pub fn environment_gradients(&self, dir: Vec3) -> TextureGradients {
        match self {
            Footprint::Differential(diff) => {
                let d = unit_direction(dir);
                TextureGradients::from_axes(
                    lat_long_offset(d, diff.dddx),
                    lat_long_offset(d, diff.dddy),
                )
            }
            _ => lat_long_cone_gradients(self.spread_angle(), dir),
        }
    }

    /// World-space footprint width at the current position: the cone (envelope) width, the
    /// distance metric's width, or for differentials sqrt |dPdx x dPdy|. Never negative.
    #[inline]
    pub fn width(&self) -> f32 {
        match self {
            Footprint::Mip0 => 0.0,
            Footprint::Distance(f) => f.width(),
            Footprint::Cone1(c) => c.abs_width(),
            Footprint::Cone(e) => e.width(),
            Footprint::Differential(d) => d.width(),
        }
    }

    /// Cone width and spread angle at the ray's origin, for callbacks (alpha cut-outs) that
    /// need the footprint at a distance t as `width + spread * t`. Differentials report an
    /// equivalent isotropic cone; `mip0` reports (0, 0).
    #[inline]
    pub fn cone_at_origin(&self) -> (f32, f32) {
        match self {
            Footprint::Mip0 => (0.0, 0.0),
            Footprint::Distance(f) => (f.width(), f.angle),
            Footprint::Cone1(c) => (c.abs_width(), c.angle),
            Footprint::Cone(e) => (e.width(), e.angle()),
            Footprint::Differential(d) => d.equivalent_cone(),
        }
    }

    /// The spread angle of cone-like footprints (0 for mip0 and differentials).
    #[inline]
    fn spread_angle(&self) -> f32 {
        match self {
            Footprint::Mip0 | Footprint::Differential(_) => 0.0,
            Footprint::Distance(f) => f.angle,
            Footprint::Cone1(c) => c.angle,
            Footprint::Cone(e) => e.angle(),
        }
    }
}

#[cfg(test)]
mod tests;
