//! The footprint ellipse and the mip-level choice shared by the mip-mapped filters
//! (reference note, steps 1, 2, 4 and 5).
//!
//! The st Jacobian's singular values give the ellipse's major and minor lengths
//! (full widths, in normalised st units). The level is chosen from the minor length;
//! anisotropy is then covered by probes along the major axis (`aniso`) or by an
//! elliptical kernel (`ewa`). Arithmetic is f32 except where OpenImageIO widens to f64,
//! so probe counts agree with it on rounding boundaries.

use super::mip_pyramid::MipPyramid;
use super::TextureQuery;

/// Derivatives shorter than this count as degenerate (OIIO's epsilon).
const EPS: f32 = 1.0e-8;
/// Largest derivative magnitude used; keeps squares and sums finite in f32.
const MAX_DERIV: f32 = 1.0e18;
/// Hard ceiling on the anisotropy limit, bounding the work per lookup.
pub(crate) const MAX_ANISO_CEILING: f32 = 1024.0;

/// Derivatives after degeneracy handling: (dsdx, dtdx, dsdy, dtdy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Derivs {
    pub dsdx: f32,
    pub dtdx: f32,
    pub dsdy: f32,
    pub dtdy: f32,
}

#[inline(always)]
fn sane(d: f32) -> f32 {
    if d.is_nan() {
        0.0
    } else {
        d.clamp(-MAX_DERIV, MAX_DERIV)
    }
}

/// Step 1: replaces vanishing derivative vectors by tiny ones (zero derivatives
/// become a point sample at level 0); a lone tiny vector becomes perpendicular to
/// the other.
#[inline]
pub(crate) fn adjust_derivatives(q: &TextureQuery) -> Derivs {
    let (mut dsdx, mut dtdx) = (sane(q.dsdx), sane(q.dtdx));
    let (mut dsdy, mut dtdy) = (sane(q.dsdy), sane(q.dtdy));
    let eps2 = EPS * EPS;
    let dxlen2 = dsdx * dsdx + dtdx * dtdx;
    let dylen2 = dsdy * dsdy + dtdy * dtdy;
    if dxlen2 < eps2 {
        if dylen2 < eps2 {
            dsdx = EPS;
            dtdx = 0.0;
            dsdy = 0.0;
            dtdy = EPS;
        } else {
            let scale = EPS / dylen2.sqrt();
            dsdx = dtdy * scale;
            dtdx = -dsdy * scale;
        }
    } else if dylen2 < eps2 {
        let scale = EPS / dxlen2.sqrt();
        dsdy = -dtdx * scale;
        dtdy = dsdx * scale;
    }
    Derivs {
        dsdx,
        dtdx,
        dsdy,
        dtdy,
    }
}

/// Major and minor lengths (full widths) and the major axis direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Axes {
    pub major: f32,
    pub minor: f32,
    /// (b, a - c) of the ellipse's implicit form, in f32: the doubled angle's
    /// sine and cosine up to a common factor. The angle itself costs an `atan2`
    /// and is only needed when more than one probe is taken, so [`Axes::theta`]
    /// computes it on demand.
    pub doubled_angle: (f32, f32),
}

impl Axes {
    /// Angle of the major axis from the s axis, in radians (OIIO's theta).
    #[inline]
    pub fn theta(&self) -> f32 {
        let (y, x) = self.doubled_angle;
        y.atan2(x) * 0.5 + std::f32::consts::FRAC_PI_2
    }

    /// (sin, cos) of [`Axes::theta`] without trigonometric calls: theta = phi + pi/2
    /// with phi half the doubled angle, from the half-angle formulas in f64. Each of
    /// sin(phi), cos(phi) comes from whichever formula is well conditioned (the
    /// larger by a root, the other as sin(2 phi) / (2 * larger)), so the result
    /// agrees with `theta().sin_cos()` to about 1e-7.
    #[inline]
    // `!(r > 0.0)` also catches a NaN length, which `r <= 0.0` would not.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn direction(&self) -> (f32, f32) {
        let (y, x) = (self.doubled_angle.0 as f64, self.doubled_angle.1 as f64);
        let r = (x * x + y * y).sqrt();
        if !(r > 0.0) || !r.is_finite() {
            // Circle (any direction serves) or unusable input: phi = 0.
            return (1.0, 0.0);
        }
        let (cos2, sin2) = (x / r, y / r);
        // phi = atan2(y, x) / 2 lies in [-pi/2, pi/2], so cos(phi) >= 0.
        let (sin_phi, cos_phi) = if cos2 >= 0.0 {
            let c = ((1.0 + cos2) * 0.5).sqrt();
            (sin2 / (2.0 * c), c)
        } else {
            let s = ((1.0 - cos2) * 0.5).sqrt().copysign(y);
            (s, sin2 / (2.0 * s))
        };
        (cos_phi as f32, -sin_phi as f32)
    }
}

/// Step 2: singular values of the st Jacobian. Squares and their sums are f32,
/// then widened to f64 for the root, as OIIO does.
#[inline]
pub(crate) fn ellipse_axes(d: &Derivs) -> Axes {
    let a = (d.dtdx * d.dtdx + d.dtdy * d.dtdy) as f64;
    let b = -2.0 * (d.dsdx * d.dtdx + d.dsdy * d.dtdy) as f64;
    let c = (d.dsdx * d.dsdx + d.dsdy * d.dsdy) as f64;
    // sqrt of the sum of squares rather than hypot(): no overflow is possible here
    // (|a|, |b|, |c| < 1e37) and it avoids a slow libm call.
    let root = ((a - c) * (a - c) + b * b).sqrt();
    let minor2 = ((a + c - root) * 0.5) as f32;
    let major2 = ((a + c + root) * 0.5) as f32;
    Axes {
        major: major2.max(0.0).sqrt().min(1000.0),
        minor: minor2.max(0.0).sqrt().min(1000.0),
        doubled_angle: (b as f32, (a - c) as f32),
    }
}

/// The usable anisotropy limit: at least 1, at most [`MAX_ANISO_CEILING`].
#[inline(always)]
pub(crate) fn aniso_limit(max_aniso: f32) -> f32 {
    if max_aniso.is_nan() {
        1.0
    } else {
        max_aniso.clamp(1.0, MAX_ANISO_CEILING)
    }
}

/// Step 4: aspect ratio clamped to the limit; the conservative rule moves the major
/// axis halfway towards minor * limit and widens the minor axis to match.
#[inline]
pub(crate) fn clamp_anisotropy(axes: &mut Axes, limit: f32) -> f32 {
    let aspect = if axes.minor > 0.0 {
        (axes.major / axes.minor).clamp(1.0, 1.0e6)
    } else {
        1.0e6
    };
    if aspect > limit {
        axes.major = (axes.major + axes.minor * limit) * 0.5;
        axes.minor = axes.major / limit;
        return limit;
    }
    aspect
}

/// Up to two mip levels and their blend weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LevelChoice {
    pub levels: [usize; 2],
    pub weights: [f32; 2],
}

impl LevelChoice {
    fn single(level: usize) -> Self {
        LevelChoice {
            levels: [level, level],
            weights: [1.0, 0.0],
        }
    }

    /// The blended level as a real number (for the `lod` AOV).
    pub fn fractional(&self) -> f32 {
        self.levels[0] as f32 + self.weights[1] * (self.levels[1] as f32 - self.levels[0] as f32)
    }
}

/// Step 5: the first level whose min(width, height) makes the filter width at most
/// one texel, blended with the level above linearly in filter width. Returns `None`
/// for magnification (level 0 alone, the caller may then shrink the aspect).
#[inline]
pub(crate) fn choose_levels(pyramid: &MipPyramid, filter_width: f32) -> Option<LevelChoice> {
    for (m, level) in pyramid.levels.iter().enumerate() {
        let width_texels = filter_width * level.min_side();
        if width_texels <= 1.0 {
            if m == 0 {
                return None;
            }
            let blend = (2.0 * width_texels - 1.0).clamp(0.0, 1.0);
            return Some(LevelChoice {
                levels: [m - 1, m],
                weights: [1.0 - blend, blend],
            });
        }
    }
    Some(LevelChoice::single(pyramid.levels.len() - 1))
}

/// The whole footprint of the anisotropic filters: axes, aspect and levels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Footprint {
    pub axes: Axes,
    pub aspect: f32,
    pub levels: LevelChoice,
    /// The footprint is finer than level 0 (level 0 alone is used).
    pub magnified: bool,
}

/// Steps 1-5 for the anisotropic filters.
#[inline]
pub(crate) fn footprint(pyramid: &MipPyramid, q: &TextureQuery, max_aniso: f32) -> Footprint {
    let limit = aniso_limit(max_aniso);
    let d = adjust_derivatives(q);
    let mut axes = ellipse_axes(&d);
    let mut aspect = clamp_anisotropy(&mut axes, limit);
    let mut magnified = false;
    let levels = match choose_levels(pyramid, axes.minor) {
        Some(choice) => choice,
        None => {
            magnified = true;
            // Magnification: a degenerate minor axis would ask for pointlessly many
            // probes, so base the aspect on the major axis in level-0 texels.
            let l0 = &pyramid.levels[0];
            let r = l0.width.max(l0.height) as f32;
            if axes.minor * r < 0.5 {
                aspect = (axes.major * r * 2.0).clamp(1.0, limit);
            }
            LevelChoice::single(0)
        }
    };
    Footprint {
        axes,
        aspect,
        levels,
        magnified,
    }
}

#[cfg(test)]
mod tests {
    use super::super::mip_pyramid::MipLevel;
    use super::*;

    fn pyramid(w: u32, h: u32) -> MipPyramid {
        MipPyramid::build(
            MipLevel::new(w, h, vec![[0.0; 4]; (w * h) as usize]).unwrap(),
            "t",
        )
        .unwrap()
    }

    #[test]
    fn axes_are_singular_values() {
        let q = TextureQuery {
            dsdx: 0.3,
            dtdx: 0.0,
            dsdy: 0.0,
            dtdy: 0.1,
            ..Default::default()
        };
        let a = ellipse_axes(&adjust_derivatives(&q));
        assert!((a.major - 0.3).abs() < 1e-6 && (a.minor - 0.1).abs() < 1e-6);
        // Major along s: theta = 0 (mod pi).
        assert!(a.theta().sin().abs() < 1e-6);
        // A rotated Jacobian keeps its singular values.
        let (c, s) = (0.6f32, 0.8f32);
        let q = TextureQuery {
            dsdx: 0.3 * c,
            dtdx: 0.3 * s,
            dsdy: -0.1 * s,
            dtdy: 0.1 * c,
            ..Default::default()
        };
        let a = ellipse_axes(&adjust_derivatives(&q));
        assert!((a.major - 0.3).abs() < 1e-6 && (a.minor - 0.1).abs() < 1e-6);
        assert!((a.theta().cos().abs() - c).abs() < 1e-5);
    }

    #[test]
    fn direction_matches_the_angle_through_trigonometry() {
        let mut worst = 0.0f32;
        for k in -400..=400 {
            let a = k as f32 * (std::f32::consts::PI / 400.0);
            for len in [1e-12f32, 1e-3, 1.0, 3e6] {
                let axes = Axes {
                    major: 1.0,
                    minor: 0.5,
                    doubled_angle: (len * a.sin(), len * a.cos()),
                };
                let (sin, cos) = axes.direction();
                let (sin_ref, cos_ref) = axes.theta().sin_cos();
                worst = worst.max((sin - sin_ref).abs()).max((cos - cos_ref).abs());
                assert!((sin * sin + cos * cos - 1.0).abs() < 1e-6);
            }
        }
        // Exactly opposite doubled angles (+0 and -0 sine) keep atan2's sign convention.
        for y in [0.0f32, -0.0] {
            let axes = Axes {
                major: 1.0,
                minor: 0.5,
                doubled_angle: (y, -2.0),
            };
            let (sin, cos) = axes.direction();
            let (sin_ref, cos_ref) = axes.theta().sin_cos();
            worst = worst.max((sin - sin_ref).abs()).max((cos - cos_ref).abs());
        }
        assert!(worst < 5e-7, "{worst}");
    }

    #[test]
    fn zero_derivatives_become_a_point_at_level_zero() {
        let p = pyramid(64, 64);
        let f = footprint(&p, &TextureQuery::default(), 16.0);
        assert_eq!(f.levels, LevelChoice::single(0));
        assert_eq!(f.aspect, 1.0);
    }

    #[test]
    fn level_blend_is_linear_in_filter_width() {
        let p = pyramid(256, 64);
        // 1.5 texels at level 0 (min side 64): weights 0.5 / 0.5 of levels 0 and 1.
        let c = choose_levels(&p, 1.5 / 64.0).unwrap();
        assert_eq!(c.levels, [0, 1]);
        assert!((c.weights[1] - 0.5).abs() < 1e-6);
        assert!((c.fractional() - 0.5).abs() < 1e-6);
        // Wider than the whole texture: the coarsest level.
        let c = choose_levels(&p, 10.0).unwrap();
        assert_eq!(c.levels, [8, 8]);
    }

    #[test]
    fn anisotropy_limit_is_conservative() {
        let mut axes = Axes {
            major: 1.0,
            minor: 0.01,
            doubled_angle: (0.0, 1.0),
        };
        let aspect = clamp_anisotropy(&mut axes, 16.0);
        assert_eq!(aspect, 16.0);
        assert!((axes.major - 0.58).abs() < 1e-6);
        assert!((axes.minor - 0.58 / 16.0).abs() < 1e-6);
    }

    #[test]
    fn extreme_derivatives_stay_finite() {
        let p = pyramid(32, 8);
        for q in [
            TextureQuery {
                dsdx: 3e30,
                dtdx: -2e30,
                dsdy: 1e-30,
                dtdy: 7.0,
                ..Default::default()
            },
            TextureQuery {
                dsdx: 1.0,
                dtdx: 1e-6,
                dsdy: 1.0,
                dtdy: 1e-6,
                ..Default::default()
            },
        ] {
            let f = footprint(&p, &q, 16.0);
            assert!(f.axes.major.is_finite() && f.axes.minor.is_finite());
            assert!(f.aspect >= 1.0 && f.aspect <= 16.0);
        }
    }
}
