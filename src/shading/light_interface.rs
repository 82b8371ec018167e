//! One interface for every light of a scene: punctual lights (point, spot, directional),
//! the environment, and the area lights of emissive triangles and spheres. Each answers
//! - [`SceneLights::sample_li`]: a direction from a shading point towards it, how far the
//!   light is along it, the light arriving, and the density of the direction;
//! - [`SceneLights::pdf_li`]: the solid-angle density with which `sample_li` would have
//!   picked the direction of a ray that found the light;
//! - [`SceneLights::le`]: the radiance a ray sees where it hits the light or escapes to it;
//! - [`SceneLights::is_delta`]: whether the light arrives from a single direction, so that
//!   no ray can find it and its samples are never weighted against BSDF sampling.
//!
//! This is the design of pbrt-v4's `Light` (Pharr, Jakob and Humphreys 2023, section 12.1:
//! `SampleLi`, `PDF_Li`, `L` and `Le`, and `LightType::DeltaPosition` / `DeltaDirection`).
//! As there, a delta light's sample carries a probability of 1 and, in place of radiance,
//! what arrives from its one direction (`I / r^2` for a point light); integrators branch on
//! the flag, never on the value of a density.
//!
//! Lights are named by [`LightRef`], a small copyable value, and every method is one
//! `match` over its kind: no dynamic dispatch and no allocation per call, so that lane
//! loops can carry a `LightRef` per lane. Emission that a texture modulates (lat-long
//! environments, emission textures) is read through an [`EmissionLookup`] the integrator
//! supplies, as the filtered texture lookups belong to the render stage.

use glam::{DVec3, Vec2, Vec3};

use super::area_lights::AreaLight;
use super::environment_light::EnvironmentLight;
use super::light_selection::{LightRef, SceneLights};
use super::lights;

/// What arrives at a shading point from one light, in one direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the light along `wi`; `f32::INFINITY` for lights at infinity.
    pub distance: f32,
    /// The point shadow rays stop short of, in f64, with the magnitude of the coordinates
    /// it was computed from (`shading::shadow_ray_towards`); `None` for lights at infinity.
    pub light_point: Option<(DVec3, f32)>,
    /// Radiance arriving along `wi`; for a delta light, the irradiance it delivers to a
    /// surface facing it (before the cosine).
    pub radiance: Vec3,
    /// Solid-angle density of `wi`; for a delta light, the probability 1 of its one
    /// direction.
    pub pdf: f32,
}

/// Where a ray met a light: escaping to a light at infinity, or hitting an emitter's
/// surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightHit {
    /// Unit direction of the ray, from the viewer towards the light.
    pub direction: Vec3,
    /// Where the ray hit the light's surface (unused for lights at infinity).
    pub point: Vec3,
    /// The surface's geometric normal there, as its winding or outward side gives it.
    pub normal: Vec3,
    /// The surface's texture coordinates there.
    pub st: Vec2,
}

impl LightHit {
    /// A ray along `direction` that left the scene.
    #[inline]
    pub fn escaping(direction: Vec3) -> LightHit {
        LightHit {
            direction,
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
            st: Vec2::ZERO,
        }
    }
}

/// Reads the emission of lights whose radiance varies over them.
pub trait EmissionLookup {
    /// Radiance of `environment` arriving along the unit direction `wi`.
    fn environment(&mut self, environment: &EnvironmentLight, wi: Vec3) -> Vec3;
    /// Radiance `light` emits at the texture coordinates `st` (its emission factor times
    /// its emission texture there).
    fn area(&mut self, light: &AreaLight, st: Vec2) -> Vec3;
}

/// The emission the lights hold themselves: emission factors without their textures, and
/// the environment map's nearest level-0 texel. What delta lights are sampled with (they
/// never read it), and what the lights' own tests measure.
#[derive(Clone, Copy, Debug, Default)]
pub struct OwnEmission;

impl EmissionLookup for OwnEmission {
    #[inline]
    fn environment(&mut self, environment: &EnvironmentLight, wi: Vec3) -> Vec3 {
        environment.radiance_towards(wi)
    }

    #[inline]
    fn area(&mut self, light: &AreaLight, _st: Vec2) -> Vec3 {
        light.radiance
    }
}

impl SceneLights {
    /// Whether `light` arrives from a single direction: every punctual light.
    #[inline]
    pub fn is_delta(&self, light: LightRef) -> bool {
        match light {
            LightRef::Punctual(index) => lights::is_delta_light(&self.punctual[index]),
            LightRef::Environment | LightRef::Area(_) => false,
        }
    }

    /// The delta lights, in the scene's order: all a Whitted integrator samples.
    pub fn delta_lights(&self) -> impl Iterator<Item = LightRef> + '_ {
        (0..self.punctual.len())
            .map(LightRef::Punctual)
            .filter(|&light| self.is_delta(light))
    }

    /// A direction from `p` towards `light`, drawn with the uniform numbers `u` (unused by
    /// delta lights), with the light arriving along it; `None` when the light shows `p`
    /// nothing that way (the back of a one-sided emitter, a degenerate sample).
    #[inline]
    pub fn sample_li(
        &self,
        light: LightRef,
        p: Vec3,
        u: Vec2,
        emission: &mut impl EmissionLookup,
    ) -> Option<LiSample> {
        match light {
            LightRef::Punctual(index) => {
                let light = &self.punctual[index];
                let sample = lights::sample_li(light, p);
                Some(LiSample {
                    wi: sample.direction_to_light,
                    distance: sample.distance,
                    light_point: lights::light_position(light)
                        .map(|position| (position.as_dvec3(), 0.0)),
                    radiance: sample.radiance_scale,
                    pdf: sample.pdf,
                })
            }
            LightRef::Environment => {
                let sample = self.environment.sample_li(u);
                Some(LiSample {
                    wi: sample.wi,
                    distance: f32::INFINITY,
                    light_point: None,
                    radiance: emission.environment(&self.environment, sample.wi),
                    pdf: sample.pdf,
                })
            }
            LightRef::Area(index) => {
                let light = &self.area.lights[index];
                let sample = light.sample(p, u)?;
                Some(LiSample {
                    wi: sample.direction_to_light,
                    distance: sample.distance,
                    light_point: Some((sample.point, light.coordinate_scale())),
                    radiance: emission.area(light, sample.st),
                    pdf: sample.pdf,
                })
            }
        }
    }

    /// The solid-angle density with which [`SceneLights::sample_li`] from `from` picks the
    /// direction of a ray that met `light` at `hit`; zero for a delta light, which no ray
    /// meets.
    #[inline]
    pub fn pdf_li(&self, light: LightRef, from: Vec3, hit: &LightHit) -> f32 {
        match light {
            LightRef::Punctual(_) => 0.0,
            LightRef::Environment => self.environment.pdf_li(hit.direction),
            LightRef::Area(index) => self.area.lights[index].pdf(from, hit.point),
        }
    }

    /// The radiance a ray sees where it meets `light` at `hit`: zero for a delta light and
    /// from behind a one-sided emitter (whose front is the side its normal points to).
    #[inline]
    pub fn le(&self, light: LightRef, hit: &LightHit, emission: &mut impl EmissionLookup) -> Vec3 {
        match light {
            LightRef::Punctual(_) => Vec3::ZERO,
            LightRef::Environment => emission.environment(&self.environment, hit.direction),
            LightRef::Area(index) => {
                let light = &self.area.lights[index];
                if light.two_sided || hit.direction.dot(hit.normal) < 0.0 {
                    emission.area(light, hit.st)
                } else {
                    Vec3::ZERO
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;
    use std::sync::Arc;

    use super::*;
    use crate::scene::Light;
    use crate::shading::area_lights::{AreaLights, AreaShape};
    use crate::shading::bsdf::tests::Uniforms;
    use crate::shading::environment_light::EnvironmentMap;
    use crate::texture::Texture;

    fn triangle_light(p: [Vec3; 3], two_sided: bool) -> AreaLight {
        AreaLight {
            shape: AreaShape::triangle(p),
            two_sided,
            radiance: Vec3::splat(3.0),
            textured: None,
        }
    }

    fn sphere_light(center: Vec3, radius: f32, two_sided: bool) -> AreaLight {
        AreaLight {
            shape: AreaShape::Sphere { center, radius },
            two_sided,
            radiance: Vec3::splat(2.0),
            textured: None,
        }
    }

    /// The quad `[-a, a] x [-b, b]` at height `h`, facing down, as two triangles.
    fn quad_facing_down(a: f32, b: f32, h: f32) -> [AreaLight; 2] {
        let corner = |x: f32, z: f32| Vec3::new(x * a, h, z * b);
        // Clockwise seen from above: the normal points down.
        [
            triangle_light(
                [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0)],
                false,
            ),
            triangle_light(
                [corner(-1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)],
                false,
            ),
        ]
    }

    fn scene_lights(punctual: &[Light], environment: Vec3, area: &[AreaLight]) -> SceneLights {
        let mut emitters = AreaLights::default();
        emitters.lights = area.to_vec();
        SceneLights::with_area_lights(punctual, environment, 10.0, emitters)
    }

    fn point(position: Vec3, intensity: f32) -> Light {
        Light::Point {
            position,
            color: Vec3::ONE,
            intensity,
        }
    }

    /// Where the ray along a sample's direction meets the light: the sample's point, with
    /// the light's normal there.
    fn hit_of(light: &AreaLight, sample: &LiSample) -> LightHit {
        let point = sample
            .light_point
            .expect("an area light has a point")
            .0
            .as_vec3();
        let normal = match light.shape {
            AreaShape::Triangle { normal, .. } => normal,
            AreaShape::Sphere { center, .. } => (point - center).normalize(),
        };
        LightHit {
            direction: sample.wi,
            point,
            normal,
            st: Vec2::ZERO,
        }
    }

    #[test]
    fn punctual_lights_are_delta_and_the_rest_are_not() {
        let spot = Light::Spot {
            position: Vec3::Y,
            direction: -Vec3::Y,
            color: Vec3::ONE,
            intensity: 1.0,
            inner_angle: 0.2,
            outer_angle: 0.4,
        };
        let sun = Light::Directional {
            direction: -Vec3::Y,
            color: Vec3::ONE,
            intensity: 1.0,
        };
        let lights = scene_lights(
            &[point(Vec3::Y, 1.0), spot, sun],
            Vec3::splat(0.5),
            &[
                quad_facing_down(1.0, 1.0, 2.0)[0],
                sphere_light(Vec3::Y, 0.5, false),
            ],
        );
        for index in 0..3 {
            assert!(lights.is_delta(LightRef::Punctual(index)), "{index}");
        }
        assert!(!lights.is_delta(LightRef::Environment));
        assert!(!lights.is_delta(LightRef::Area(0)));
        assert!(!lights.is_delta(LightRef::Area(1)));
        let delta: Vec<_> = lights.delta_lights().collect();
        assert_eq!(delta, (0..3).map(LightRef::Punctual).collect::<Vec<_>>());
        // A delta light's sample is its one direction, with probability 1; no ray finds it.
        let sample = lights
            .sample_li(
                LightRef::Punctual(0),
                Vec3::ZERO,
                Vec2::ZERO,
                &mut OwnEmission,
            )
            .unwrap();
        assert_eq!(sample.pdf, 1.0);
        let hit = LightHit::escaping(sample.wi);
        assert_eq!(lights.pdf_li(LightRef::Punctual(0), Vec3::ZERO, &hit), 0.0);
        assert_eq!(
            lights.le(LightRef::Punctual(2), &hit, &mut OwnEmission),
            Vec3::ZERO
        );
    }

    /// A 32 x 16 sky whose radiance varies smoothly, with a bright band.
    fn sky_map() -> Arc<EnvironmentMap> {
        let (w, h) = (32u32, 16u32);
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let band = if y == 5 { 40.0 } else { 1.0 };
                [band * (1.0 + x as f32 / w as f32), band, 0.5, 1.0]
            })
            .collect();
        let texture = Texture::from_rgba_f32(w, h, texels).unwrap();
        Arc::new(EnvironmentMap::new(Arc::new(texture), 1.5))
    }

    #[test]
    fn pdf_li_of_a_sampled_direction_is_the_density_it_was_sampled_with() {
        let area = [
            // Near (sampled by solid angle) and far (by area) from the points below.
            quad_facing_down(1.0, 1.0, 2.0)[0],
            sphere_light(Vec3::new(0.0, 3.0, 0.0), 1.0, false),
            sphere_light(Vec3::new(0.2, 0.1, 0.0), 4.0, true),
        ];
        let constant = scene_lights(&[], Vec3::splat(0.5), &area);
        let mapped = constant.clone().with_environment_map(sky_map());
        let points = [Vec3::new(0.3, 1.4, -0.2), Vec3::new(0.1, -150.0, 0.3)];
        let mut u = Uniforms(7);
        for lights in [&constant, &mapped] {
            for light in [
                LightRef::Environment,
                LightRef::Area(0),
                LightRef::Area(1),
                LightRef::Area(2),
            ] {
                let (mut samples, mut disagreements) = (0, 0);
                for p in points {
                    for _ in 0..2000 {
                        let Some(s) = lights.sample_li(light, p, u.vec2(), &mut OwnEmission) else {
                            continue;
                        };
                        let hit = match light {
                            LightRef::Area(i) => hit_of(&lights.area.lights[i], &s),
                            _ => LightHit::escaping(s.wi),
                        };
                        assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{light:?}: {s:?}");
                        samples += 1;
                        let pdf = lights.pdf_li(light, p, &hit);
                        if (pdf - s.pdf).abs() > 2e-3 * s.pdf {
                            disagreements += 1;
                        }
                    }
                }
                assert!(samples > 1000, "{light:?}: {samples} samples");
                // A lat-long direction on a texel's edge may map back to its neighbour.
                assert!(
                    disagreements * 500 < samples,
                    "{light:?}: {disagreements} of {samples}"
                );
            }
        }
    }

    /// Irradiance at `p` on a surface of normal `n` from every light of `lights`, by light
    /// sampling: one light chosen per sample, then one direction on it.
    fn irradiance(lights: &SceneLights, p: Vec3, n: Vec3, count: usize, seed: u64) -> f64 {
        let mut u = Uniforms(seed);
        let mut sum = 0.0f64;
        for _ in 0..count {
            let (light, pmf) = lights.choose(u.next()).expect("a light with power");
            let u_point = u.vec2();
            let Some(s) = lights.sample_li(light, p, u_point, &mut OwnEmission) else {
                continue;
            };
            let cos = f64::from(s.wi.dot(n).max(0.0));
            let probability = f64::from(pmf) * f64::from(s.pdf);
            sum += f64::from(s.radiance.x) * cos / probability;
        }
        sum / count as f64
    }

    #[test]
    fn a_point_light_delivers_its_intensity_times_cos_over_r2() {
        let position = Vec3::new(1.0, 3.0, -2.0);
        let lights = scene_lights(&[point(position, 7.0)], Vec3::ZERO, &[]);
        let (p, n) = (
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.2, 1.0, -0.1).normalize(),
        );
        let to_light = position - p;
        let exact =
            7.0 * f64::from(to_light.normalize().dot(n)) / f64::from(to_light.length_squared());
        let e = irradiance(&lights, p, n, 4, 1);
        assert!((e - exact).abs() < 1e-6 * exact, "{e} vs {exact}");
    }

    /// Form factor from a point to a parallel rectangle of sides `a` and `b` at distance `c`
    /// above one of its corners (Howell's catalogue of configuration factors, factor B-3):
    /// `1 / 2 pi (X / sqrt(1 + X^2) atan(Y / sqrt(1 + X^2)) + (X and Y swapped))`, with
    /// `X = a / c`, `Y = b / c`.
    fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
    }

    #[test]
    fn a_quad_light_delivers_its_form_factor() {
        // A point under the centre of a 2a x 2b quad of radiance L: E = pi L F, with F four
        // times the corner factor of an a x b quarter. Near, the triangles are sampled by
        // solid angle; far, by area.
        let (a, b) = (1.0f32, 0.5f32);
        for height in [0.6f32, 12.0] {
            let quad = quad_facing_down(a, b, height);
            let lights = scene_lights(&[], Vec3::ZERO, &quad);
            let e = irradiance(&lights, Vec3::ZERO, Vec3::Y, 200_000, 11);
            let form_factor =
                4.0 * corner_form_factor(f64::from(a), f64::from(b), f64::from(height));
            let exact = PI * 3.0 * form_factor;
            assert!(
                (e / exact - 1.0).abs() < 5e-3,
                "height {height}: {e} against {exact}"
            );
        }
    }

    #[test]
    fn a_uniform_environment_delivers_pi_l() {
        // E = integral of L cos over the hemisphere = pi L, for any normal; the map holds
        // the same radiance in every texel.
        let radiance = 0.75f32;
        let constant = scene_lights(&[], Vec3::splat(radiance), &[]);
        let texture =
            Texture::from_rgba_f32(16, 8, vec![[radiance, radiance, radiance, 1.0]; 128]).unwrap();
        let map = Arc::new(EnvironmentMap::new(Arc::new(texture), 1.0));
        let mapped = constant.clone().with_environment_map(map);
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let exact = PI * f64::from(radiance);
        for (name, lights) in [("constant", &constant), ("map", &mapped)] {
            let e = irradiance(lights, Vec3::ZERO, n, 400_000, 5);
            assert!(
                (e / exact - 1.0).abs() < 1e-2,
                "{name}: {e} against {exact}"
            );
        }
    }

    #[test]
    fn le_is_zero_behind_a_one_sided_emitter() {
        let [front, _] = quad_facing_down(1.0, 1.0, 2.0);
        let both = AreaLight {
            two_sided: true,
            ..front
        };
        let ball = sphere_light(Vec3::ZERO, 1.0, false);
        let lights = scene_lights(&[], Vec3::splat(0.25), &[front, both, ball]);
        let on_quad = |direction: Vec3| LightHit {
            direction,
            point: Vec3::new(0.5, 2.0, 0.2),
            normal: -Vec3::Y,
            st: Vec2::ZERO,
        };
        let (from_below, from_above) = (on_quad(Vec3::Y), on_quad(-Vec3::Y));
        let le = |light, hit: &LightHit| lights.le(light, hit, &mut OwnEmission);
        assert_eq!(le(LightRef::Area(0), &from_below), Vec3::splat(3.0));
        assert_eq!(le(LightRef::Area(0), &from_above), Vec3::ZERO);
        assert_eq!(le(LightRef::Area(1), &from_above), Vec3::splat(3.0));
        // A sphere emits outwards: seen from inside, its wall is dark.
        let on_ball = |direction: Vec3| LightHit {
            direction,
            point: Vec3::X,
            normal: Vec3::X,
            st: Vec2::ZERO,
        };
        assert_eq!(le(LightRef::Area(2), &on_ball(-Vec3::X)), Vec3::splat(2.0));
        assert_eq!(le(LightRef::Area(2), &on_ball(Vec3::X)), Vec3::ZERO);
        assert_eq!(
            le(LightRef::Environment, &LightHit::escaping(Vec3::Z)),
            Vec3::splat(0.25)
        );
    }
}
