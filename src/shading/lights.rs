//! What a shading point needs to know about each punctual light: where to send the shadow
//! ray, how far it may go, and the irradiance the light delivers before the cosine.
//!
//! Seed 001, "Shadow Rays": the shadow-ray direction is `s = (l - q) / |l - q|` for a light
//! at `l` and a hit at `q`. Point and spot lights fall off with the inverse square of the
//! distance (`I / r^2`); a directional light delivers constant irradiance from infinitely far
//! away; a spot light is additionally scaled by a smoothstep from its outer to its inner cone
//! angle (the `crate::scene::Light::Spot` contract).
//!
//! For integrators these are delta lights (pbrt-v4, section 12.1): [`sample_li`] returns the
//! one direction each light arrives from, with probability 1, and [`pdf_li`] is zero for any
//! direction a BSDF sample might pick. Integrators reach them, as every other light, through
//! [`super::light_interface`]; the choice of one light per sample is
//! [`super::LightSelection`].

use glam::Vec3;

use crate::scene::Light;

/// The light as seen from one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light (the shadow-ray direction).
    pub direction_to_light: Vec3,
    /// Distance to the light along `direction_to_light`; `f32::INFINITY` for a directional
    /// light. Shadow rays test occluders in `(0, distance)`.
    pub distance: f32,
    /// Irradiance arriving at the point on a surface facing the light (before the cosine
    /// and the BRDF): `color * intensity / r^2` for point and spot lights (times the spot
    /// falloff), `color * intensity` for directional lights. Zero when the light cannot
    /// reach the point (degenerate position or direction, outside the spot cone).
    pub radiance_scale: Vec3,
    /// Probability of this direction: 1, as punctual lights are delta lights.
    pub pdf: f32,
}

impl LightSample {
    /// True when this light contributes nothing here, so no shadow ray is needed.
    #[inline]
    pub fn is_black(&self) -> bool {
        self.radiance_scale.max_element() <= 0.0
    }
}

/// Hermite smoothstep from 0 at `edge0` to 1 at `edge1` (`3t^2 - 2t^3`); a step at
/// `edge1` when the edges coincide.
#[inline]
fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    if edge1 <= edge0 {
        return if x >= edge1 { 1.0 } else { 0.0 };
    }
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Spot cone attenuation: 1 inside `inner_angle`, 0 beyond `outer_angle`, smoothstep in the
/// cosine between them. `cos_angle` is the cosine between the spot axis and the direction
/// from the light to the point.
#[inline]
pub fn spot_falloff(cos_angle: f32, inner_angle: f32, outer_angle: f32) -> f32 {
    let outer = outer_angle.max(0.0);
    let inner = inner_angle.clamp(0.0, outer);
    smoothstep(outer.cos(), inner.cos(), cos_angle)
}

/// Direction, distance and irradiance scale of `light` as seen from the point `p`: the one
/// direction the light arrives from (a delta light, `pdf` 1).
#[inline]
pub fn sample_li(light: &Light, p: Vec3) -> LightSample {
    match light {
        Light::Point {
            position,
            color,
            intensity,
        } => point_sample(*position, p, *color * *intensity),
        Light::Directional {
            direction,
            color,
            intensity,
        } => {
            let to_light = -direction.normalize_or_zero();
            LightSample {
                direction_to_light: if to_light == Vec3::ZERO {
                    Vec3::Z
                } else {
                    to_light
                },
                distance: f32::INFINITY,
                radiance_scale: if to_light == Vec3::ZERO {
                    Vec3::ZERO
                } else {
                    *color * *intensity
                },
                pdf: 1.0,
            }
        }
        Light::Spot {
            position,
            direction,
            color,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            let mut sample = point_sample(*position, p, *color * *intensity);
            let axis = direction.normalize_or_zero();
            let cos_angle = (-sample.direction_to_light).dot(axis);
            let falloff = if axis == Vec3::ZERO {
                0.0
            } else {
                spot_falloff(cos_angle, *inner_angle, *outer_angle)
            };
            sample.radiance_scale *= falloff;
            sample
        }
    }
}

/// Density with which [`sample_li`] picks the direction `wi` from `p`: zero, as a punctual
/// light occupies no solid angle (a BSDF-sampled ray never hits it).
#[inline]
pub fn pdf_li(_light: &Light, _p: Vec3, _wi: Vec3) -> f32 {
    0.0
}

/// True for lights that [`sample_li`] reaches in a single direction: all punctual lights.
#[inline]
pub fn is_delta_light(_light: &Light) -> bool {
    true
}

/// Where a point or spot light sits (`None` for a directional light, which is infinitely
/// far away): the end shadow rays stop short of.
#[inline]
pub fn light_position(light: &Light) -> Option<Vec3> {
    match light {
        Light::Point { position, .. } | Light::Spot { position, .. } => Some(*position),
        Light::Directional { .. } => None,
    }
}

/// Inverse-square sample of a point source of radiant intensity `intensity_rgb` at
/// `position`, seen from `p` ([`sample_li`] of a point light, for callers that take the
/// light apart once for many points).
#[inline]
pub fn point_sample(position: Vec3, p: Vec3, intensity_rgb: Vec3) -> LightSample {
    let to_light = position - p;
    let distance2 = to_light.length_squared();
    let distance = distance2.sqrt();
    if !distance2.is_finite() || distance2 <= 0.0 {
        // The point coincides with the light (or is not finite): no defined direction.
        return LightSample {
            direction_to_light: Vec3::Z,
            distance: 0.0,
            radiance_scale: Vec3::ZERO,
            pdf: 1.0,
        };
    }
    LightSample {
        direction_to_light: to_light / distance,
        distance,
        radiance_scale: intensity_rgb / distance2,
        pdf: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_light_falls_off_with_inverse_square() {
        let light = Light::Point {
            position: Vec3::new(0.0, 4.0, 0.0),
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity: 32.0,
        };
        let s = sample_li(&light, Vec3::ZERO);
        assert!((s.direction_to_light - Vec3::Y).length() < 1e-7);
        assert_eq!(s.distance, 4.0);
        assert!(
            (s.radiance_scale - Vec3::new(2.0, 1.0, 0.5))
                .abs()
                .max_element()
                < 1e-6
        );
        let far = sample_li(&light, Vec3::new(0.0, -4.0, 0.0));
        assert!(
            (far.radiance_scale * 4.0 - s.radiance_scale)
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn directional_light_is_infinitely_far_and_constant() {
        let light = Light::Directional {
            direction: Vec3::new(0.0, -2.0, 0.0),
            color: Vec3::ONE,
            intensity: 3.0,
        };
        let s = sample_li(&light, Vec3::new(100.0, -5.0, 7.0));
        assert!((s.direction_to_light - Vec3::Y).length() < 1e-7);
        assert_eq!(s.distance, f32::INFINITY);
        assert_eq!(s.radiance_scale, Vec3::splat(3.0));
    }

    #[test]
    fn spot_light_cone_is_full_inside_smooth_between_and_dark_outside() {
        let inner = 20f32.to_radians();
        let outer = 30f32.to_radians();
        let light = Light::Spot {
            position: Vec3::new(0.0, 1.0, 0.0),
            direction: -Vec3::Y,
            color: Vec3::ONE,
            intensity: 1.0,
            inner_angle: inner,
            outer_angle: outer,
        };
        let at_angle = |deg: f32| {
            let a = deg.to_radians();
            sample_li(&light, Vec3::new(a.tan(), 0.0, 0.0))
                .radiance_scale
                .x
                * (1.0 / a.cos()).powi(2)
        };
        assert!((at_angle(0.0) - 1.0).abs() < 1e-5);
        assert!((at_angle(19.0) - 1.0).abs() < 1e-5);
        let mid = at_angle(25.0);
        assert!(mid > 0.05 && mid < 0.95, "{mid}");
        assert!(at_angle(24.0) > at_angle(26.0));
        assert_eq!(at_angle(31.0), 0.0);
        // Behind the light.
        assert_eq!(
            sample_li(&light, Vec3::new(0.0, 2.0, 0.0)).radiance_scale,
            Vec3::ZERO
        );
    }

    #[test]
    fn hard_edged_spot_when_inner_equals_outer() {
        assert_eq!(spot_falloff(0.999, 0.1, 0.1), 1.0);
        assert_eq!(spot_falloff(0.9, 0.1, 0.1), 0.0);
    }

    #[test]
    fn punctual_lights_are_delta_lights() {
        let light = Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            color: Vec3::ONE,
            intensity: 5.0,
        };
        let s = sample_li(&light, Vec3::ZERO);
        assert_eq!(s.pdf, 1.0);
        assert!(is_delta_light(&light));
        assert_eq!(pdf_li(&light, Vec3::ZERO, s.direction_to_light), 0.0);
    }

    #[test]
    fn degenerate_lights_contribute_nothing() {
        let light = Light::Point {
            position: Vec3::ONE,
            color: Vec3::ONE,
            intensity: 1.0,
        };
        let s = sample_li(&light, Vec3::ONE);
        assert!(s.is_black());
        assert!(s.direction_to_light.is_finite());
        let light = Light::Directional {
            direction: Vec3::ZERO,
            color: Vec3::ONE,
            intensity: 1.0,
        };
        assert!(sample_li(&light, Vec3::ZERO).is_black());
    }
}
