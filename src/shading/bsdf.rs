//! The BSDF interface every material lobe implements, for integrators that sample
//! directions (a path tracer) as well as those that follow delta lobes deterministically
//! (Whitted).
//!
//! Conventions (as in pbrt-v4, section 9.1): `wo` points from the surface towards where the
//! light goes (the viewer), `wi` towards where it comes from; both are unit vectors in world
//! space. [`Bsdf::eval`] is `f(wo, wi)` without the cosine; [`Bsdf::pdf`] the solid-angle
//! density with which [`Bsdf::sample`] picks `wi`. Delta lobes (a smooth mirror, a smooth
//! dielectric) scatter into single directions: `eval` and `pdf` are zero for them, and only
//! `sample` finds those directions, flagging the sample with [`LobeFlags::SPECULAR`]. Every sample carries its lobe's
//! [`LobeFlags`] and the relative index of refraction it crosses (pbrt-v4's `BSDFSample`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// Which kinds of lobe a BSDF has, or which one produced a sample: pbrt-v4's `BxDFFlags`
/// (section 9.1.2), the side (reflection, transmission) combined with the shape (diffuse,
/// glossy, specular). A specular (delta) lobe scatters into single directions and has no
/// density; diffuse and glossy lobes have one.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct LobeFlags(u8);

impl LobeFlags {
    pub const NONE: LobeFlags = LobeFlags(0);
    pub const REFLECTION: LobeFlags = LobeFlags(1);
    pub const TRANSMISSION: LobeFlags = LobeFlags(2);
    pub const DIFFUSE: LobeFlags = LobeFlags(4);
    pub const GLOSSY: LobeFlags = LobeFlags(8);
    pub const SPECULAR: LobeFlags = LobeFlags(16);
    pub const DIFFUSE_REFLECTION: LobeFlags = LobeFlags(4 | 1);
    pub const GLOSSY_REFLECTION: LobeFlags = LobeFlags(8 | 1);
    pub const GLOSSY_TRANSMISSION: LobeFlags = LobeFlags(8 | 2);
    pub const SPECULAR_REFLECTION: LobeFlags = LobeFlags(16 | 1);
    pub const SPECULAR_TRANSMISSION: LobeFlags = LobeFlags(16 | 2);

    /// Whether every flag of `other` is set in `self`.
    #[inline]
    pub const fn contains(self, other: LobeFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// Whether `self` and `other` share a flag.
    #[inline]
    pub const fn intersects(self, other: LobeFlags) -> bool {
        self.0 & other.0 != 0
    }

    #[inline]
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    #[inline]
    pub const fn is_reflective(self) -> bool {
        self.intersects(LobeFlags::REFLECTION)
    }

    #[inline]
    pub const fn is_transmissive(self) -> bool {
        self.intersects(LobeFlags::TRANSMISSION)
    }

    #[inline]
    pub const fn is_diffuse(self) -> bool {
        self.intersects(LobeFlags::DIFFUSE)
    }

    #[inline]
    pub const fn is_glossy(self) -> bool {
        self.intersects(LobeFlags::GLOSSY)
    }

    /// A delta lobe: its directions are found only by sampling.
    #[inline]
    pub const fn is_specular(self) -> bool {
        self.intersects(LobeFlags::SPECULAR)
    }

    /// A lobe with a density (diffuse or glossy), which light sampling can reach.
    #[inline]
    pub const fn has_density(self) -> bool {
        self.intersects(LobeFlags(LobeFlags::DIFFUSE.0 | LobeFlags::GLOSSY.0))
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = LobeFlags;
    #[inline]
    fn bitor(self, other: LobeFlags) -> LobeFlags {
        LobeFlags(self.0 | other.0)
    }
}

impl std::ops::BitOrAssign for LobeFlags {
    #[inline]
    fn bitor_assign(&mut self, other: LobeFlags) {
        self.0 |= other.0;
    }
}

impl std::fmt::Debug for LobeFlags {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names = [
            (LobeFlags::REFLECTION, "reflection"),
            (LobeFlags::TRANSMISSION, "transmission"),
            (LobeFlags::DIFFUSE, "diffuse"),
            (LobeFlags::GLOSSY, "glossy"),
            (LobeFlags::SPECULAR, "specular"),
        ];
        let set: Vec<&str> = names
            .iter()
            .filter(|(flag, _)| self.contains(*flag))
            .map(|(_, name)| *name)
            .collect();
        write!(f, "LobeFlags({})", set.join(" | "))
    }
}

/// A direction drawn from a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit direction the light comes from.
    pub wi: Vec3,
    /// What the sample multiplies the path throughput by: `f(wo, wi) |n . wi| / pdf` for a
    /// lobe with a density; for a delta lobe, the energy it carries divided by the
    /// probability of choosing it.
    pub weight: Vec3,
    /// Solid-angle density of `wi` for a lobe with a density; the discrete probability of
    /// the chosen lobe for a delta one.
    pub pdf: f32,
    /// The lobe that produced the sample: exactly one of reflection and transmission, and
    /// one of diffuse, glossy and specular.
    pub flags: LobeFlags,
    /// The relative index of refraction across the boundary the sample crosses: the index on
    /// `wo`'s side over the index on `wi`'s side (`n_incident / n_transmitted` for the ray
    /// arriving along `-wo`, as [`super::refract`] takes it), 1 for a reflection. pbrt-v4's
    /// `BSDFSample::eta` is the reciprocal.
    pub eta: f32,
}

impl BsdfSample {
    /// A reflected sample (`eta` 1).
    #[inline]
    pub fn reflected(wi: Vec3, weight: Vec3, pdf: f32, flags: LobeFlags) -> BsdfSample {
        BsdfSample {
            wi,
            weight,
            pdf,
            flags,
            eta: 1.0,
        }
    }

    /// A delta lobe's sample: no density (light sampling cannot find its direction).
    #[inline]
    pub fn is_specular(&self) -> bool {
        self.flags.is_specular()
    }

    #[inline]
    pub fn is_transmission(&self) -> bool {
        self.flags.is_transmissive()
    }
}

/// A material's scattering at one shading point.
pub trait Bsdf {
    /// `f(wo, wi)`, without the cosine; zero for delta lobes.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3;
    /// Draws `wi` for `wo` from the uniform numbers `u_lobe` (which lobe) and `u` (where in
    /// it); `None` when nothing scatters (e.g. `wo` below an opaque surface).
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample>;
    /// Solid-angle density of [`Bsdf::sample`] choosing `wi`; zero for delta lobes.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;
    /// The lobes the BSDF has here: a delta lobe's directions only `sample` finds.
    fn flags(&self) -> LobeFlags;
}

/// Two unit vectors completing the unit `n` to an orthonormal basis, without a division by
/// a small number (Duff et al. 2017, "Building an Orthonormal Basis, Revisited", listing 3).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A cosine-distributed direction about the unit `n` (density `(n . w) / pi`), by
/// Malley's method: a uniform point on the unit disk (concentric mapping, Shirley and Chiu
/// 1997) lifted onto the hemisphere (pbrt-v4, section A.5.3).
#[inline]
pub fn sample_cosine_hemisphere(n: Vec3, u: Vec2) -> Vec3 {
    let (r, theta) = concentric_polar(u);
    lift_to_hemisphere(n, disk_point(r, theta.cos(), theta.sin()))
}

/// The unit disk's point `d` lifted onto the hemisphere about the unit `n`: the second half
/// of [`sample_cosine_hemisphere`], for lanes that take the first half's sines and cosines
/// in a loop of their own.
#[inline(always)]
pub fn lift_to_hemisphere(n: Vec3, d: Vec2) -> Vec3 {
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    let (t, b) = orthonormal_basis(n);
    (t * d.x + b * d.y + n * z).normalize()
}

/// A unit vector uniform on the sphere (density `1 / 4 pi`): `z` uniform in `[-1, 1]`,
/// azimuth uniform (pbrt-v4, section A.5.2).
#[inline]
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Shirley and Chiu's concentric map from the unit square to the unit disk, which keeps
/// strata compact, as the polar coordinates `(r, theta)` of the disk's point ((0, 0) for
/// its centre); [`disk_point`] makes the point.
#[inline(always)]
pub fn concentric_polar(u: Vec2) -> (f32, f32) {
    let o = 2.0 * u - Vec2::ONE;
    if o == Vec2::ZERO {
        return (0.0, 0.0);
    }
    if o.x.abs() > o.y.abs() {
        (o.x, PI / 4.0 * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - PI / 4.0 * (o.x / o.y))
    }
}

/// The disk's point at radius `r` and the angle whose cosine and sine are given.
#[inline(always)]
pub fn disk_point(r: f32, cos_theta: f32, sin_theta: f32) -> Vec2 {
    r * Vec2::new(cos_theta, sin_theta)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::test_rng::{unit_f32_of_u64, xorshift64_star};

    /// A small deterministic generator of uniform numbers in [0, 1) (xorshift64*).
    pub(crate) struct Uniforms(pub u64);

    impl Uniforms {
        pub(crate) fn next(&mut self) -> f32 {
            unit_f32_of_u64(xorshift64_star(&mut self.0))
        }
        pub(crate) fn vec2(&mut self) -> Vec2 {
            Vec2::new(self.next(), self.next())
        }
    }

    #[test]
    fn lobe_flags_combine_sides_and_shapes() {
        let glass = LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION;
        assert!(glass.is_specular() && glass.is_reflective() && glass.is_transmissive());
        assert!(!glass.has_density() && !glass.is_diffuse() && !glass.is_glossy());
        assert!(glass.contains(LobeFlags::SPECULAR_TRANSMISSION));
        assert!(!glass.contains(LobeFlags::GLOSSY_TRANSMISSION));
        let plastic = LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION;
        assert!(plastic.has_density() && !plastic.is_specular() && !plastic.is_transmissive());
        assert!(LobeFlags::NONE.is_empty() && !LobeFlags::NONE.has_density());
        let mut both = plastic;
        both |= glass;
        assert!(both.contains(plastic) && both.contains(glass) && both.has_density());
        assert_eq!(
            format!("{:?}", LobeFlags::GLOSSY_TRANSMISSION),
            "LobeFlags(transmission | glossy)"
        );
        let sample = BsdfSample::reflected(Vec3::Z, Vec3::ONE, 1.0, LobeFlags::DIFFUSE_REFLECTION);
        assert_eq!(sample.eta, 1.0);
        assert!(!sample.is_specular() && !sample.is_transmission());
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        let mut u = Uniforms(7);
        for _ in 0..1000 {
            let n = Vec3::new(u.next() - 0.5, u.next() - 0.5, u.next() - 0.5).normalize();
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
        }
        let (t, b) = orthonormal_basis(-Vec3::Z);
        assert!(t.is_finite() && b.is_finite());
    }

    #[test]
    fn cosine_samples_have_the_cosine_moments() {
        // E[cos] = 2/3 and E[cos^2] = 1/2 under the density cos / pi.
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let mut u = Uniforms(11);
        let count = 200_000;
        let (mut m1, mut m2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let w = sample_cosine_hemisphere(n, u.vec2());
            let c = w.dot(n) as f64;
            assert!(c >= -1e-6 && (w.length() - 1.0).abs() < 1e-5);
            m1 += c;
            m2 += c * c;
        }
        let (m1, m2) = (m1 / count as f64, m2 / count as f64);
        assert!((m1 - 2.0 / 3.0).abs() < 3e-3, "E[cos] = {m1}");
        assert!((m2 - 0.5).abs() < 3e-3, "E[cos^2] = {m2}");
    }
}
