//! The environment as a light: radiance arriving from every direction at infinity.
//!
//! What the integrator needs besides looking up the radiance of a direction (done by the
//! render stage, which owns the textures): the environment's mean radiance over the sphere,
//! which Whitted uses as the ambient light of diffuse surfaces and light selection as the
//! environment's power, and a way to pick directions towards it. Directions are drawn
//! uniformly over the sphere (density `1 / 4 pi`), which is exact for a constant colour and
//! unbiased for a map.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// The environment seen as a light.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvironmentLight {
    /// Mean radiance over the sphere of directions, by solid angle.
    pub mean_radiance: Vec3,
}

/// A direction towards the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentSample {
    /// Unit direction the light arrives from.
    pub wi: Vec3,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
}

impl EnvironmentLight {
    /// Draws a direction towards the environment from the uniform numbers `u`, uniformly
    /// over the sphere (pbrt-v4, section A.5.3: `z = 1 - 2 u0`, `phi = 2 pi u1`).
    #[inline]
    pub fn sample_li(&self, u: Vec2) -> EnvironmentSample {
        let z = 1.0 - 2.0 * u.x;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        EnvironmentSample {
            wi: Vec3::new(r * phi.cos(), r * phi.sin(), z),
            pdf: self.pdf_li(Vec3::Z),
        }
    }

    /// Density with which [`EnvironmentLight::sample_li`] picks `wi`: `1 / 4 pi` for every
    /// direction.
    #[inline]
    pub fn pdf_li(&self, _wi: Vec3) -> f32 {
        1.0 / (4.0 * PI)
    }

    /// True when the environment delivers no light at all.
    #[inline]
    pub fn is_black(&self) -> bool {
        self.mean_radiance.max_element() <= 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    #[test]
    fn samples_cover_the_sphere_uniformly() {
        let light = EnvironmentLight {
            mean_radiance: Vec3::ONE,
        };
        let mut u = Uniforms(29);
        let count = 100_000;
        let (mut mean, mut upper) = (Vec3::ZERO, 0usize);
        for _ in 0..count {
            let s = light.sample_li(u.vec2());
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            assert_eq!(s.pdf, light.pdf_li(s.wi));
            mean += s.wi;
            upper += (s.wi.y > 0.0) as usize;
        }
        mean /= count as f32;
        assert!(mean.length() < 0.01, "mean direction {mean}");
        let share = upper as f32 / count as f32;
        assert!((share - 0.5).abs() < 0.01, "{share}");
        // The density integrates to one over the sphere.
        assert!((light.pdf_li(Vec3::X) * 4.0 * PI - 1.0).abs() < 1e-6);
    }
}
