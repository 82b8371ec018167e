//! The GGX (Trowbridge-Reitz) microfacet distribution of the rough lobes: its normal
//! distribution `D`, Smith's masking-shadowing with the height-correlated `G2`, and the
//! sampling of visible normals.
//!
//! Everything is in a local frame whose `+z` is the macro-surface normal
//! ([`super::frame::ShadingFrame`]). With `alpha` the width (glTF: perceptual roughness
//! squared) and `theta` a microfacet normal's angle to `z`:
//! - `D(h) = 1 / (pi alpha^2 cos^4(theta) (1 + tan^2(theta) / alpha^2)^2)` (Walter et al.
//!   2007, eq. 33), normalised over projected area: `integral D(h) cos(theta_h) dw = 1`;
//! - `Lambda(w) = (sqrt(1 + alpha^2 tan^2(theta_w)) - 1) / 2` (Heitz 2014, "Understanding
//!   the Masking-Shadowing Function", eq. 72), `G1(w) = 1 / (1 + Lambda(w))` and the
//!   height-correlated `G2(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi))` (Heitz 2014, eq. 99);
//! - the distribution of normals visible from `w`,
//!   `D_w(h) = G1(w) max(0, w . h) D(h) / cos(theta_w)` (Heitz 2014, eq. 38), sampled
//!   exactly by Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)):
//!   stretch the view to the `alpha = 1` configuration, sample the projected hemisphere
//!   there (a disk whose far half is squashed by the view's tilt), unstretch.
//!
//! `w` below the surface (`z < 0`) is treated as seen from its mirror image above, so the
//! visible normals always face `+z` (what transmission from the inside needs).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// The smallest `alpha` the rough lobes use: below it `D`'s peak (`1 / (pi alpha^2)`)
/// and the pdfs grow past what `f32` arithmetic on directions resolves, and the lobe is a
/// mirror for every practical purpose. `1e-3` keeps the peak near `3e5`, finite.
pub const MIN_ALPHA: f32 = 1e-3;

/// An isotropic GGX distribution of width `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    /// The distribution of a glTF perceptual roughness `r` (`alpha = r^2`, glTF 2.0
    /// Appendix B), never narrower than [`MIN_ALPHA`]; a non-finite `r` counts as smooth.
    #[inline]
    pub fn from_roughness(roughness: f32) -> Ggx {
        let r = if roughness.is_finite() {
            roughness.clamp(0.0, 1.0)
        } else {
            0.0
        };
        Ggx::from_alpha(r * r)
    }

    /// The distribution of width `alpha`, clamped to at least [`MIN_ALPHA`].
    #[inline]
    pub fn from_alpha(alpha: f32) -> Ggx {
        let alpha = if alpha.is_finite() {
            alpha.max(MIN_ALPHA)
        } else {
            MIN_ALPHA
        };
        Ggx { alpha }
    }

    /// `D(h)` for the local unit microfacet normal `h`; zero below the surface.
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        // 1 / (pi a^2 (cos^2 + sin^2 / a^2)^2), the form of eq. 33 that needs no tan and
        // keeps its precision at the peak (sin^2 from x and y, not 1 - cos^2).
        let a2 = self.alpha * self.alpha;
        let e = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
        1.0 / (PI * a2 * e * e)
    }

    /// Smith's `Lambda(w)` for the local unit direction `w` (either side of the surface);
    /// infinite at grazing.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        let sin2 = w.x * w.x + w.y * w.y;
        if cos2 == 0.0 {
            return f32::INFINITY;
        }
        let alpha2_tan2 = self.alpha * self.alpha * sin2 / cos2;
        // (sqrt(1 + x) - 1) / 2 = x / (2 (sqrt(1 + x) + 1)), exact near normal incidence.
        alpha2_tan2 / (2.0 * ((1.0 + alpha2_tan2).sqrt() + 1.0))
    }

    /// Smith's masking `G1(w)`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing `G2(wo, wi)`.
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density `D_w(h)` over solid angle of the normals visible from `w` (from its mirror
    /// image above the surface when `w` is below).
    #[inline]
    pub fn visible_normal_pdf(&self, w: Vec3, h: Vec3) -> f32 {
        let cos_w = w.z.abs();
        let w_dot_h = if w.z < 0.0 { -w.dot(h) } else { w.dot(h) };
        if cos_w == 0.0 || w_dot_h <= 0.0 {
            return 0.0;
        }
        self.g1(w) * w_dot_h * self.d(h) / cos_w
    }

    /// The reflection of the local `wo` (above the surface) off a visible normal drawn
    /// with `u`: `(wi, h)`, or `None` when the normal faces away (`wi` may be below the
    /// surface; the caller decides what that means).
    #[inline]
    pub fn sample_reflection(&self, wo: Vec3, u: Vec2) -> Option<(Vec3, Vec3)> {
        let h = self.sample_visible_normal(wo, u);
        let wo_dot_h = wo.dot(h);
        if wo_dot_h <= 0.0 {
            return None;
        }
        Some((2.0 * wo_dot_h * h - wo, h))
    }

    /// A microfacet normal drawn from `D_w` for the local unit `w` with the uniform `u`
    /// (Heitz 2018, section 3 and its listing).
    pub fn sample_visible_normal(&self, w: Vec3, u: Vec2) -> Vec3 {
        let w = if w.z < 0.0 { -w } else { w };
        // The view in the stretched configuration, where the distribution is alpha = 1.
        let wh = Vec3::new(self.alpha * w.x, self.alpha * w.y, w.z).normalize_or_zero();
        let wh = if wh == Vec3::ZERO { Vec3::Z } else { wh };
        // An orthonormal basis about the view (any basis at normal incidence).
        let len2 = wh.x * wh.x + wh.y * wh.y;
        let t1 = if len2 > 1e-12 {
            Vec3::new(-wh.y, wh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        // A uniform point on the unit disk (polar map), its far half squashed onto the
        // projected hemisphere's outline: the projected area seen from wh.
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        let s = 0.5 * (1.0 + wh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        // Lift onto the hemisphere and unstretch the normal.
        let lift = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        let nh = p1 * t1 + p2 * t2 + lift * wh;
        Vec3::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf_properties::{chi_square_directions, sphere_integral};

    fn direction(theta_degrees: f32, phi: f32) -> Vec3 {
        let t = theta_degrees.to_radians();
        Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
    }

    #[test]
    fn d_integrates_to_one_over_projected_area() {
        // 1D in theta (D is isotropic): 2 pi integral of D cos sin d theta, midpoint rule
        // fine enough to resolve the narrowest peak (width ~ alpha radians).
        let mut worst = 0.0f64;
        for alpha in [0.02f32, 0.05, 0.1, 0.3, 0.6, 1.0] {
            let ggx = Ggx::from_alpha(alpha);
            let steps = 200_000;
            let dt = std::f64::consts::FRAC_PI_2 / steps as f64;
            let mut sum = 0.0f64;
            for i in 0..steps {
                let t = (i as f64 + 0.5) * dt;
                let h = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
                sum += ggx.d(h) as f64 * t.cos() * t.sin();
            }
            let integral = sum * dt * 2.0 * std::f64::consts::PI;
            worst = worst.max((integral - 1.0).abs());
            assert!((integral - 1.0).abs() < 2e-3, "alpha {alpha}: {integral}");
        }
        println!("GGX projected-area normalisation: worst |integral - 1| = {worst:.2e}");
    }

    #[test]
    fn visible_normal_pdf_integrates_to_one() {
        let mut worst = 0.0f64;
        for alpha in [0.1f32, 0.3, 0.7, 1.0] {
            let ggx = Ggx::from_alpha(alpha);
            for (theta, phi) in [(0.0, 0.0), (30.0, 1.0), (60.0, 2.5), (85.0, 4.0)] {
                for w in [direction(theta, phi), -direction(theta, phi)] {
                    let integral = sphere_integral(|h| ggx.visible_normal_pdf(w, h) as f64);
                    worst = worst.max((integral - 1.0).abs());
                    assert!(
                        (integral - 1.0).abs() < 5e-3,
                        "alpha {alpha} w {w}: {integral}"
                    );
                }
            }
        }
        println!("GGX visible-normal pdf: worst |integral - 1| = {worst:.2e}");
    }

    #[test]
    fn sampled_visible_normals_follow_their_pdf() {
        let mut worst: f64 = 0.0;
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let ggx = Ggx::from_alpha(alpha);
            for (index, w) in [
                direction(0.0, 0.0),
                direction(50.0, 0.7),
                -direction(80.0, 2.0),
            ]
            .into_iter()
            .enumerate()
            {
                let report = chi_square_directions(
                    0x5eed + index as u64,
                    |_, u| Some(ggx.sample_visible_normal(w, u)),
                    |h| ggx.visible_normal_pdf(w, h),
                );
                worst = worst.max(report.normalised());
                assert!(report.passes(), "alpha {alpha} w {w}: {report:?}");
            }
        }
        println!("GGX visible-normal sampling: worst chi-square / threshold = {worst:.3}");
    }

    #[test]
    fn the_chi_square_comparison_rejects_a_slightly_wrong_width() {
        // The comparison has the power to see a 15 % error in alpha.
        let (sampled, claimed) = (Ggx::from_alpha(0.3), Ggx::from_alpha(0.345));
        let w = direction(40.0, 0.5);
        let report = chi_square_directions(
            99,
            |_, u| Some(sampled.sample_visible_normal(w, u)),
            |h| claimed.visible_normal_pdf(w, h),
        );
        println!("chi-square of a 15 % wrong alpha: {report:?}");
        assert!(!report.passes(), "{report:?}");
    }

    #[test]
    fn masking_is_one_at_normal_incidence_and_zero_at_grazing() {
        let ggx = Ggx::from_alpha(0.4);
        assert_eq!(ggx.g1(Vec3::Z), 1.0);
        assert_eq!(ggx.g1(Vec3::X), 0.0);
        let w = direction(70.0, 0.3);
        assert!(ggx.g2(w, w) < ggx.g1(w) && ggx.g1(w) < 1.0);
        // A smooth surface masks nothing away from grazing.
        assert!(Ggx::from_alpha(MIN_ALPHA).g1(w) > 0.9999);
    }

    #[test]
    fn the_smallest_width_stays_finite() {
        let ggx = Ggx::from_roughness(0.0);
        assert_eq!(ggx.alpha, MIN_ALPHA);
        assert!(ggx.d(Vec3::Z).is_finite() && ggx.d(Vec3::Z) > 1e5);
        let h = ggx.sample_visible_normal(direction(40.0, 0.2), Vec2::new(0.3, 0.8));
        assert!(h.is_finite() && h.z > 0.999);
        assert!(ggx.visible_normal_pdf(direction(40.0, 0.2), h).is_finite());
        assert_eq!(Ggx::from_roughness(f32::NAN).alpha, MIN_ALPHA);
    }
}
