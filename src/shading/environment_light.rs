//! The environment as a light: radiance arriving from every direction at infinity.
//!
//! What the integrator needs besides looking up the radiance of a direction (done by the
//! render stage, which owns the filtered lookups): the environment's mean radiance over the
//! sphere, which Whitted uses as the ambient light of diffuse surfaces and light selection as
//! the environment's power, and a way to pick directions towards it.
//!
//! A constant colour is sampled uniformly over the sphere (density `1 / 4 pi`). A lat-long
//! map is importance sampled: a piecewise-constant 2D distribution
//! ([`Distribution2D`]) over its texels, proportional to each texel's luminance times
//! `sin theta` at the texel row's centre (the solid angle a texel covers shrinks towards the
//! poles), picks a point `(s, t)`; its direction is the lat-long mapping
//! `theta = pi t`, `phi = 2 pi s` (`crate::footprint::lat_long_to_direction`), and since
//! `d omega = sin theta d theta d phi = 2 pi^2 sin theta ds dt`, the density in solid angle
//! is `p(s, t) / (2 pi^2 sin theta)` (pbrt-v4, section 12.5.2).
//!
//! The distribution is built once, when a render is prepared, from the finest pyramid level
//! at most [`MAX_DISTRIBUTION_WIDTH`] texels wide: level 0 for maps up to that width, a
//! coarser (box-filtered, so mean-preserving) level for larger ones. The sampled radiance is
//! always read from level 0, so the estimate is of the full-resolution map whatever level the
//! density came from; a coarser density stays positive wherever level 0 is, and only loses
//! some of its peakedness.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::distribution_2d::Distribution2D;
use crate::footprint::{direction_to_lat_long, lat_long_to_direction};
use crate::texture::Texture;

/// The widest pyramid level the sampling distribution is built from: 1024 x 512 texels make a
/// distribution of 4 MiB (a value and a cumulative sum per texel) whose texels span 0.35
/// degrees, about the sun's apparent radius, and it is built in a few milliseconds.
pub const MAX_DISTRIBUTION_WIDTH: u32 = 1024;

/// Luminance of a linear Rec. 709 colour.
#[inline]
fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A lat-long environment map with its sampling distribution.
pub struct EnvironmentMap {
    /// The map; its level 0 gives the sampled radiance.
    texture: Arc<Texture>,
    intensity: f32,
    /// Over the (s, t) square, one cell per texel of the chosen level.
    distribution: Distribution2D,
    /// Which pyramid level the distribution was built from.
    level: usize,
}

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (nu, nv) = self.distribution.size();
        f.debug_struct("EnvironmentMap")
            .field("intensity", &self.intensity)
            .field("level", &self.level)
            .field("distribution", &format_args!("{nu}x{nv}"))
            .finish()
    }
}

impl EnvironmentMap {
    /// The sampling distribution of `texture` (a lat-long map) scaled by `intensity`.
    pub fn new(texture: Arc<Texture>, intensity: f32) -> EnvironmentMap {
        let levels = &texture.pyramid().levels;
        let level = levels
            .iter()
            .position(|l| l.width <= MAX_DISTRIBUTION_WIDTH)
            .unwrap_or(levels.len() - 1);
        let map = &levels[level];
        let (width, height) = (map.width as usize, map.height as usize);
        let mut values = Vec::with_capacity(width * height);
        for row in 0..height {
            let sin_theta = (PI * (row as f32 + 0.5) / height as f32).sin();
            for column in 0..width {
                let [r, g, b, _] = map.texel(column, row);
                values.push(luminance(Vec3::new(r, g, b)).max(0.0) * sin_theta);
            }
        }
        EnvironmentMap {
            distribution: Distribution2D::new(&values, width, height),
            texture,
            intensity,
            level,
        }
    }

    /// The pyramid level the distribution was built from.
    pub fn level(&self) -> usize {
        self.level
    }

    /// The radiance of the level-0 texel containing `st`, times the intensity.
    #[inline]
    pub fn radiance(&self, st: Vec2) -> Vec3 {
        let map = &self.texture.pyramid().levels[0];
        let (w, h) = (map.width as usize, map.height as usize);
        let x = ((st.x * w as f32) as usize).min(w - 1);
        let y = ((st.y * h as f32) as usize).min(h - 1);
        let [r, g, b, _] = map.texel(x, y);
        Vec3::new(r, g, b) * self.intensity
    }

    /// Solid-angle density of `st` from its density over the square.
    #[inline]
    fn solid_angle_pdf(pdf_st: f32, st: Vec2) -> f32 {
        let sin_theta = (PI * st.y).sin();
        if sin_theta <= 0.0 || pdf_st <= 0.0 {
            0.0
        } else {
            pdf_st / (2.0 * PI * PI * sin_theta)
        }
    }
}

/// The environment seen as a light.
#[derive(Clone, Debug, Default)]
pub struct EnvironmentLight {
    /// Mean radiance over the sphere of directions, by solid angle.
    pub mean_radiance: Vec3,
    /// The lat-long map and its sampling distribution; `None` for a constant colour (and for
    /// renders whose environment an external texture system serves), sampled uniformly with
    /// `mean_radiance`.
    pub map: Option<Arc<EnvironmentMap>>,
}

impl PartialEq for EnvironmentLight {
    /// Equal means and the same map (by identity).
    fn eq(&self, other: &Self) -> bool {
        self.mean_radiance == other.mean_radiance
            && match (&self.map, &other.map) {
                (None, None) => true,
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                _ => false,
            }
    }
}

/// A direction towards the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentSample {
    /// Unit direction the light arrives from.
    pub wi: Vec3,
    /// Radiance arriving along `wi` (the map's level-0 texel, or the constant colour).
    pub radiance: Vec3,
    /// Solid-angle density of `wi` (0: the sample carries nothing and must be skipped).
    pub pdf: f32,
}

impl EnvironmentLight {
    /// A constant environment of radiance `color`.
    pub fn constant(color: Vec3) -> EnvironmentLight {
        EnvironmentLight {
            mean_radiance: color,
            map: None,
        }
    }

    /// A lat-long map environment with mean radiance `mean_radiance`.
    pub fn lat_long(map: Arc<EnvironmentMap>, mean_radiance: Vec3) -> EnvironmentLight {
        EnvironmentLight {
            mean_radiance,
            map: Some(map),
        }
    }

    /// Draws a direction towards the environment from the uniform numbers `u`: by the map's
    /// distribution (see the module docs), or uniformly over the sphere for a constant
    /// colour (pbrt-v4, section A.5.3: `z = 1 - 2 u0`, `phi = 2 pi u1`).
    #[inline]
    pub fn sample_li(&self, u: Vec2) -> EnvironmentSample {
        match &self.map {
            Some(map) => {
                let (st, pdf_st) = map.distribution.sample(u);
                EnvironmentSample {
                    wi: lat_long_to_direction(st),
                    radiance: map.radiance(st),
                    pdf: EnvironmentMap::solid_angle_pdf(pdf_st, st),
                }
            }
            None => {
                let z = 1.0 - 2.0 * u.x;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                EnvironmentSample {
                    wi: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                    radiance: self.mean_radiance,
                    pdf: 1.0 / (4.0 * PI),
                }
            }
        }
    }

    /// Density with which [`EnvironmentLight::sample_li`] picks the unit direction `wi`.
    #[inline]
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        match &self.map {
            Some(map) => {
                let st = direction_to_lat_long(wi);
                EnvironmentMap::solid_angle_pdf(map.distribution.pdf(st), st)
            }
            None => 1.0 / (4.0 * PI),
        }
    }

    /// The radiance arriving along the unit direction `wi` as this light holds it: the
    /// map's level-0 texel there, or the constant colour (for an environment an external
    /// texture system serves, its mean: the map itself is not held here).
    #[inline]
    pub fn radiance_towards(&self, wi: Vec3) -> Vec3 {
        match &self.map {
            Some(map) => map.radiance(direction_to_lat_long(wi)),
            None => self.mean_radiance,
        }
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
        let light = EnvironmentLight::constant(Vec3::ONE);
        let mut u = Uniforms(29);
        let count = 100_000;
        let (mut mean, mut upper) = (Vec3::ZERO, 0usize);
        for _ in 0..count {
            let s = light.sample_li(u.vec2());
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            assert_eq!(s.pdf, light.pdf_li(s.wi));
            assert_eq!(s.radiance, Vec3::ONE);
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

    /// A 64 x 32 sky: a dim gradient, brighter towards +Y, with a 2 x 1-texel sun 10^4 times
    /// brighter than the sky.
    fn sun_sky() -> (Arc<Texture>, impl Fn(usize, usize) -> Vec3) {
        let (w, h) = (64usize, 32usize);
        let texel = move |x: usize, y: usize| {
            if (40..42).contains(&x) && y == 9 {
                Vec3::new(5000.0, 4500.0, 4000.0)
            } else {
                Vec3::new(0.2, 0.3, 0.5) * (1.5 - y as f32 / h as f32)
            }
        };
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| texel(x, y).extend(1.0).to_array())
            .collect();
        let texture = Texture::from_rgba_f32(w as u32, h as u32, texels).unwrap();
        (Arc::new(texture), texel)
    }

    fn sun_sky_light() -> EnvironmentLight {
        let (texture, _) = sun_sky();
        let map = Arc::new(EnvironmentMap::new(texture, 2.0));
        assert_eq!(map.level(), 0);
        EnvironmentLight::lat_long(map, Vec3::ONE)
    }

    /// Midpoint quadrature over (theta, phi) of `f(direction) sin theta`.
    fn integrate_sphere(f: impl Fn(Vec3) -> f64) -> f64 {
        let (n_theta, n_phi) = (1024, 2048);
        let (d_theta, d_phi) = (
            std::f64::consts::PI / n_theta as f64,
            std::f64::consts::TAU / n_phi as f64,
        );
        let mut sum = 0.0;
        for i in 0..n_theta {
            let theta = (i as f64 + 0.5) * d_theta;
            for j in 0..n_phi {
                let phi = (j as f64 + 0.5) * d_phi;
                let st = Vec2::new(
                    (phi / std::f64::consts::TAU) as f32,
                    (theta / std::f64::consts::PI) as f32,
                );
                sum += f(lat_long_to_direction(st)) * theta.sin() * d_theta * d_phi;
            }
        }
        sum
    }

    #[test]
    fn the_map_pdf_integrates_to_one() {
        let light = sun_sky_light();
        let total = integrate_sphere(|wi| f64::from(light.pdf_li(wi)));
        eprintln!("integral of the pdf over the sphere: {total}");
        assert!((total - 1.0).abs() < 2e-3, "{total}");
    }

    #[test]
    fn sampled_directions_follow_the_pdf_and_agree_with_pdf_li() {
        let light = sun_sky_light();
        let (w, h) = (64usize, 32usize);
        let mut counts = vec![0usize; w * h];
        let mut rng = Uniforms(41);
        let count = 400_000;
        let mut disagreements = 0;
        for _ in 0..count {
            let s = light.sample_li(rng.vec2());
            assert!(s.pdf > 0.0 && (s.wi.length() - 1.0).abs() < 1e-5);
            let again = light.pdf_li(s.wi);
            // Directions on a texel boundary may map back to the neighbouring texel.
            if (again - s.pdf).abs() > 1e-3 * s.pdf {
                disagreements += 1;
            }
            let st = direction_to_lat_long(s.wi);
            let x = ((st.x * w as f32) as usize).min(w - 1);
            let y = ((st.y * h as f32) as usize).min(h - 1);
            counts[y * w + x] += 1;
        }
        eprintln!("{disagreements} of {count} samples disagree with pdf_li");
        assert!(disagreements * 1000 < count, "{disagreements}");
        // Each texel's share of samples is the integral of the pdf over it: its cell of the
        // distribution, value / sum.
        let map = light.map.as_ref().unwrap();
        let mut worst = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let centre = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let expected = f64::from(map.distribution.pdf(centre)) / (w * h) as f64;
                let got = counts[y * w + x] as f64 / count as f64;
                let sigma = (expected * (1.0 - expected) / count as f64).sqrt();
                worst = worst.max((got - expected).abs() / sigma.max(1e-12));
            }
        }
        eprintln!("largest texel-share deviation: {worst:.2} sigma");
        assert!(worst < 5.0, "{worst}");
    }

    #[test]
    fn importance_sampling_lowers_the_variance_of_irradiance() {
        let light = sun_sky_light();
        let map = light.map.clone().unwrap();
        let n = Vec3::new(0.3, 0.8, 0.2).normalize();
        // Irradiance of the plane with normal n: integral of L cos+ over the sphere.
        let radiance = |wi: Vec3| map.radiance(direction_to_lat_long(wi));
        let reference =
            integrate_sphere(|wi| f64::from(luminance(radiance(wi)) * n.dot(wi).max(0.0)));
        let uniform = EnvironmentLight::constant(Vec3::ONE);
        let estimate = |sampler: &EnvironmentLight, seed: u64| {
            let mut rng = Uniforms(seed);
            let count = 200_000;
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..count {
                let s = sampler.sample_li(rng.vec2());
                let value = if s.pdf > 0.0 {
                    f64::from(luminance(radiance(s.wi)) * n.dot(s.wi).max(0.0) / s.pdf)
                } else {
                    0.0
                };
                sum += value;
                sum2 += value * value;
            }
            let mean = sum / count as f64;
            let variance = sum2 / count as f64 - mean * mean;
            (mean, variance, (variance / count as f64).sqrt())
        };
        let (mean_is, var_is, err_is) = estimate(&light, 3);
        let (mean_u, var_u, err_u) = estimate(&uniform, 4);
        eprintln!(
            "irradiance (luminance): reference {reference:.4}, importance {mean_is:.4} +- {err_is:.4}, \
             uniform {mean_u:.4} +- {err_u:.4}; variance ratio uniform / importance = {:.1}",
            var_u / var_is
        );
        assert!((mean_is - reference).abs() < 4.0 * err_is + 1e-3 * reference);
        assert!((mean_u - reference).abs() < 5.0 * err_u);
        assert!(var_u > 50.0 * var_is, "ratio {}", var_u / var_is);
    }

    #[test]
    fn a_large_map_is_sampled_from_a_coarser_level() {
        let (w, h) = (2 * MAX_DISTRIBUTION_WIDTH, MAX_DISTRIBUTION_WIDTH);
        let texels = vec![[1.0, 1.0, 1.0, 1.0]; (w * h) as usize];
        let texture = Arc::new(Texture::from_rgba_f32(w, h, texels).unwrap());
        let map = EnvironmentMap::new(texture, 1.0);
        assert_eq!(map.level(), 1);
        assert_eq!(
            map.distribution.size(),
            (MAX_DISTRIBUTION_WIDTH as usize, h as usize / 2)
        );
        // A uniform map: the density is about uniform over the sphere.
        let light = EnvironmentLight::lat_long(Arc::new(map), Vec3::ONE);
        let pdf = light.pdf_li(Vec3::new(0.6, 0.0, 0.8));
        assert!((pdf * 4.0 * PI - 1.0).abs() < 1e-3, "{}", pdf * 4.0 * PI);
    }
}
