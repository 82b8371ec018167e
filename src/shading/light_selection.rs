//! Which light to sample: the scene's lights (punctual lights, the environment and the
//! area lights of emissive geometry) and a choice of one of them per sample, through one
//! alias table over all of them ([`super::AliasTable`]).
//!
//! Lights at infinity (the environment and directional lights) and local lights (point,
//! spot and area lights) are weighed apart, as pbrt-v4's BVH light sampler does (section
//! 12.6.3): each light at infinity that gives any light is chosen with probability
//! `1 / (n_infinite + 1)`, and the local lights together take the remaining share, or
//! everything when nothing lies at infinity. Among themselves the local lights are chosen
//! in proportion to an estimate of their power (pbrt-v4's power light sampler, section
//! 12.6.2), by luminance (Rec. 709 weights): a point light's is `4 pi I`, a spot light's
//! `2 pi (1 - cos theta) I` with the mean of its inner and outer angles, an area light's
//! `pi A L` ([`super::AreaLight::power`]). A light with no power is never chosen.
//!
//! Why not weigh the lights at infinity by power too: their power is only defined over some
//! disk or sphere around the scene (`pi r^2 E` for a directional light, `4 pi^2 r^2 L` for
//! the environment, `r` the scene's bounding radius), which grows with the size of the
//! scene and not with what any one point receives. A large ground plane under a point light
//! and a dim sky then gave the sky 96 % of the samples, and with stratified samples each
//! pixel got either two or three of its 64 samples from the light: a blotchy image
//! (`tests/path_tracer.rs`, `a_point_light_over_a_large_ground_is_sampled_evenly`).

use std::f32::consts::PI;

use glam::Vec3;

use super::alias_table::AliasTable;
use super::area_lights::{luminance, AreaLights};
use super::environment_light::{EnvironmentLight, EnvironmentMap};
use crate::scene::Light;

/// Chooses one of `n` items with fixed probabilities, from one uniform number (an alias
/// table: constant time whatever the number of lights).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSelection {
    table: AliasTable,
}

impl LightSelection {
    /// Probabilities proportional to `weights` (negative and non-finite ones count as 0).
    pub fn from_weights(weights: &[f32]) -> LightSelection {
        LightSelection {
            table: AliasTable::new(weights),
        }
    }

    /// Probability of choosing item `index`.
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.table.pmf(index)
    }

    /// The item the uniform number `u` in [0, 1) chooses, with its probability; `None`
    /// when no item can be chosen.
    #[inline]
    pub fn select(&self, u: f32) -> Option<(usize, f32)> {
        self.table.sample(u)
    }
}

/// One of the scene's lights, as [`SceneLights`] numbers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightRef {
    /// `scene.lights[i]`.
    Punctual(usize),
    Environment,
    /// `SceneLights::area.lights[i]`.
    Area(usize),
}

/// The lights an integrator samples: the scene's punctual lights (indices `0..n`, in the
/// scene's order), then the environment (index `n`), then the area lights (`n + 1 + i`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneLights {
    pub environment: EnvironmentLight,
    /// Emissive triangles and spheres.
    pub area: AreaLights,
    /// One choice among the punctual lights, the environment and the area lights, by power.
    pub selection: LightSelection,
    /// The scene's punctual lights, in the scene's order (their selection indices).
    pub punctual: Vec<Light>,
    /// Radius of the scene's bounding sphere, over which lights at infinity deliver power.
    pub scene_radius: f32,
}

impl SceneLights {
    /// The lights of a scene with punctual `lights`, an environment of mean radiance
    /// `environment_mean` and geometry within a sphere of `scene_radius`.
    pub fn new(lights: &[Light], environment_mean: Vec3, scene_radius: f32) -> SceneLights {
        SceneLights::with_area_lights(
            lights,
            environment_mean,
            scene_radius,
            AreaLights::default(),
        )
    }

    /// [`SceneLights::new`] with the scene's emissive geometry as area lights too.
    pub fn with_area_lights(
        lights: &[Light],
        environment_mean: Vec3,
        scene_radius: f32,
        area: AreaLights,
    ) -> SceneLights {
        let environment = EnvironmentLight::constant(environment_mean);
        // (at infinity, weight): a luminance for a light at infinity (only whether it is
        // positive counts), the power for a local light.
        let usable = |w: f32| if w.is_finite() && w > 0.0 { w } else { 0.0 };
        let mut weights: Vec<(bool, f32)> = lights
            .iter()
            .map(|l| match l {
                Light::Directional {
                    color, intensity, ..
                } => (true, usable(intensity * luminance(*color))),
                _ => (false, usable(light_power(l))),
            })
            .collect();
        weights.push((true, usable(luminance(environment_mean))));
        weights.extend(area.lights.iter().map(|l| (false, usable(l.power()))));
        let infinite = weights.iter().filter(|&&(inf, w)| inf && w > 0.0).count();
        let local_power: f64 = weights
            .iter()
            .filter(|&&(inf, _)| !inf)
            .map(|&(_, w)| f64::from(w))
            .sum();
        let local_share = if local_power > 0.0 { 1.0 } else { 0.0 };
        let total_shares = infinite as f64 + local_share;
        let probabilities: Vec<f32> = weights
            .iter()
            .map(|&(inf, w)| {
                if w <= 0.0 {
                    0.0
                } else if inf {
                    (1.0 / total_shares) as f32
                } else {
                    (f64::from(w) / local_power / total_shares) as f32
                }
            })
            .collect();
        SceneLights {
            environment,
            area,
            selection: LightSelection::from_weights(&probabilities),
            punctual: lights.to_vec(),
            scene_radius,
        }
    }

    /// The light the uniform number `u` chooses, with its probability.
    #[inline]
    pub fn choose(&self, u: f32) -> Option<(LightRef, f32)> {
        let (index, pmf) = self.selection.select(u)?;
        let n = self.punctual.len();
        let light = match index {
            i if i < n => LightRef::Punctual(i),
            i if i == n => LightRef::Environment,
            i => LightRef::Area(i - n - 1),
        };
        Some((light, pmf))
    }

    /// Probability that [`SceneLights::choose`] picks `light`.
    #[inline]
    pub fn pmf(&self, light: LightRef) -> f32 {
        let n = self.punctual.len();
        self.selection.pmf(match light {
            LightRef::Punctual(i) => i,
            LightRef::Environment => n,
            LightRef::Area(i) => n + 1 + i,
        })
    }

    /// These lights with the environment importance sampled by `map` (a lat-long map's
    /// distribution); its power and mean radiance stay as they were.
    pub fn with_environment_map(mut self, map: std::sync::Arc<EnvironmentMap>) -> SceneLights {
        self.environment = EnvironmentLight::lat_long(map, self.environment.mean_radiance);
        self
    }
}

/// The power estimate of a local punctual light (see the module docs); 0 for a
/// directional light, which lies at infinity.
fn light_power(light: &Light) -> f32 {
    match light {
        Light::Point {
            color, intensity, ..
        } => 4.0 * PI * intensity * luminance(*color),
        Light::Spot {
            color,
            intensity,
            inner_angle,
            outer_angle,
            ..
        } => {
            let half_angle = 0.5 * (inner_angle + outer_angle);
            2.0 * PI * (1.0 - half_angle.cos()) * intensity * luminance(*color)
        }
        Light::Directional { .. } => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    #[test]
    fn selection_frequencies_match_the_probabilities() {
        let selection = LightSelection::from_weights(&[1.0, 0.0, 3.0, 4.0]);
        let total: f32 = (0..4).map(|i| selection.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-6);
        assert_eq!(selection.pmf(1), 0.0);
        let mut u = Uniforms(31);
        let mut counts = [0usize; 4];
        let count = 80_000;
        for _ in 0..count {
            let (i, p) = selection.select(u.next()).expect("weights");
            assert_eq!(p, selection.pmf(i));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0, "a light without power was chosen");
        for (i, expected) in [(0, 0.125), (2, 0.375), (3, 0.5)] {
            let share = counts[i] as f32 / count as f32;
            assert!((share - expected).abs() < 0.01, "{i}: {share}");
        }
        // The edges of [0, 1) choose lights with power.
        for u in [0.0, 0.999_999, 1.0] {
            let (i, p) = selection.select(u).expect("weights");
            assert!(p > 0.0, "{u} chose {i}");
        }
    }

    #[test]
    fn nothing_to_choose_without_power() {
        let selection = LightSelection::from_weights(&[0.0, -1.0, f32::NAN]);
        assert_eq!(selection.select(0.5), None);
        assert_eq!(selection.pmf(0), 0.0);
    }

    #[test]
    fn local_lights_share_by_power_and_lights_at_infinity_by_count() {
        let point = |intensity: f32| Light::Point {
            position: Vec3::ZERO,
            color: Vec3::ONE,
            intensity,
        };
        let sun = Light::Directional {
            direction: -Vec3::Y,
            color: Vec3::ONE,
            intensity: 1.0,
        };
        // Two point lights alone: by power, 40 pi against 4 pi.
        let scene = SceneLights::new(&[point(10.0), point(1.0)], Vec3::ZERO, 2.0);
        let ratio = scene.selection.pmf(0) / scene.selection.pmf(1);
        assert!((ratio - 10.0).abs() < 1e-4, "{ratio}");
        assert_eq!(
            scene.selection.pmf(2),
            0.0,
            "a black environment is never chosen"
        );
        // With a sun and a sky: one third each for the sun, the sky and the two point
        // lights together, whatever the scene's size.
        for radius in [1.0, 1000.0] {
            let lit = SceneLights::new(
                &[point(10.0), point(1.0), sun.clone()],
                Vec3::splat(0.5),
                radius,
            );
            let pmf = |i| lit.selection.pmf(i);
            assert!((pmf(0) + pmf(1) - 1.0 / 3.0).abs() < 1e-5, "{}", pmf(0));
            assert!((pmf(0) / pmf(1) - 10.0).abs() < 1e-3);
            assert!((pmf(2) - 1.0 / 3.0).abs() < 1e-5, "sun {}", pmf(2));
            assert!((pmf(3) - 1.0 / 3.0).abs() < 1e-5, "sky {}", pmf(3));
            assert_eq!(lit.environment.mean_radiance, Vec3::splat(0.5));
        }
        // Only the sky: it takes every sample.
        let sky = SceneLights::new(&[], Vec3::splat(0.5), 3.0);
        assert_eq!(sky.selection.pmf(0), 1.0);
    }
}
