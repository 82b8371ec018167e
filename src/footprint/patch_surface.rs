//! Footprints on curved patches, from the patch's exact derivatives instead of vertex-normal
//! estimates.
//!
//! At a patch point the first fundamental form is `I = [E F; F G]` with `E = P_u.P_u`,
//! `F = P_u.P_v`, `G = P_v.P_v`, and the second `II = [L M; M N]` with `L = P_uu.n`,
//! `M = P_uv.n`, `N = P_vv.n` for the unit normal `n = P_u x P_v / |P_u x P_v|`.
//!
//! - A surface displacement `dP` is `P_u du + P_v dv` with `I [du dv]^T = [dP.P_u dP.P_v]^T`
//!   (its tangential part; seed 000, "Texture Derivatives on a General Surface", maps
//!   footprint axes to texture space through dP/du, dP/dv like this).
//! - The normal's derivatives are the Weingarten equations, `[n_u n_v] = -[P_u P_v] I^-1 II`
//!   (the shape operator of seed 002, section 3.2, eqs. 21-22, which reduce to `dN = dP / r`
//!   on a sphere with outward normals).
//! - The principal curvatures are the eigenvalues of `I^-1 II`; the scalar curvature a ray
//!   cone uses follows triangles' rule (seed 000, "Computing Curvature"): the one of smaller
//!   magnitude when both bend the same way, 0 on a saddle, signed positive where the surface
//!   bulges towards its normal.

use glam::{Vec2, Vec3};

pub use crate::hit::CurvedFrame;

impl CurvedFrame {
    /// `(E, F, G)` and `1 / (EG - F^2)`, or `None` where the tangents are degenerate.
    fn first_form(&self) -> Option<(f32, f32, f32, f32)> {
        let (e, f, g) = (
            self.dpdu.dot(self.dpdu),
            self.dpdu.dot(self.dpdv),
            self.dpdv.dot(self.dpdv),
        );
        let det = e * g - f * f;
        let inv = det.recip();
        (det > 1e-30 * (e * g).max(f32::MIN_POSITIVE) && inv.is_finite()).then_some((e, f, g, inv))
    }

    /// Unit normal `P_u x P_v / |P_u x P_v|` (zero where degenerate).
    pub fn normal(&self) -> Vec3 {
        self.dpdu.cross(self.dpdv).normalize_or_zero()
    }

    /// `(du, dv)` of the tangential part of the displacement `dp`.
    pub fn parameter_offset(&self, dp: Vec3) -> Option<Vec2> {
        let (e, f, g, inv) = self.first_form()?;
        let (a, b) = (dp.dot(self.dpdu), dp.dot(self.dpdv));
        let offset = Vec2::new((g * a - f * b) * inv, (e * b - f * a) * inv);
        offset.is_finite().then_some(offset)
    }

    /// `(L, M, N)` for the unit normal `P_u x P_v / |P_u x P_v|`.
    fn second_form(&self) -> (f32, f32, f32) {
        let n = self.normal();
        (self.d2pdu2.dot(n), self.d2pdudv.dot(n), self.d2pdv2.dot(n))
    }

    /// `(n_u, n_v)`: derivatives of the unit normal `P_u x P_v / |P_u x P_v|` (Weingarten).
    pub fn normal_derivatives(&self) -> Option<(Vec3, Vec3)> {
        let (e, f, g, inv) = self.first_form()?;
        let (l, m, n) = self.second_form();
        let nu = (self.dpdu * (f * m - g * l) + self.dpdv * (f * l - e * m)) * inv;
        let nv = (self.dpdu * (f * n - g * m) + self.dpdv * (f * m - e * n)) * inv;
        (nu.is_finite() && nv.is_finite()).then_some((nu, nv))
    }

    /// dN for the surface displacement `dp`, N the unit normal `P_u x P_v / |P_u x P_v|`.
    pub fn normal_derivative(&self, dp: Vec3) -> Vec3 {
        match (self.parameter_offset(dp), self.normal_derivatives()) {
            (Some(d), Some((nu, nv))) => nu * d.x + nv * d.y,
            _ => Vec3::ZERO,
        }
    }

    /// Principal curvatures `(k1, k2)`, positive where the surface bulges towards its normal
    /// `P_u x P_v` (1/r on a sphere whose normals point out).
    pub fn principal_curvatures(&self) -> Option<(f32, f32)> {
        let (e, f, g, inv) = self.first_form()?;
        let (l, m, n) = self.second_form();
        // Eigenvalues of I^-1 II: H +- sqrt(H^2 - K); their negatives bulge towards n.
        let gauss = (l * n - m * m) * inv;
        let mean = (e * n - 2.0 * f * m + g * l) * inv * 0.5;
        let root = (mean * mean - gauss).max(0.0).sqrt();
        let (k1, k2) = (-(mean + root), -(mean - root));
        (k1.is_finite() && k2.is_finite()).then_some((k1, k2))
    }

    /// The curvature a ray cone sees (see the module doc), for the normal `P_u x P_v`.
    pub fn cone_curvature(&self) -> f32 {
        match self.principal_curvatures() {
            Some((k1, k2)) if k1 * k2 >= 0.0 => {
                if k1.abs() < k2.abs() {
                    k1
                } else {
                    k2
                }
            }
            _ => 0.0,
        }
    }
}

/// Texture-space offset of the surface displacement `d`: `dst/du du + dst/dv dv`.
pub fn curved_st_offset(frame: &CurvedFrame, dstdu: Vec2, dstdv: Vec2, d: Vec3) -> Vec2 {
    match frame.parameter_offset(d) {
        Some(o) => dstdu * o.x + dstdv * o.y,
        None => Vec2::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sphere of radius r around the origin, parameterised by longitude u and
    /// colatitude v, at (u, v): its frame has the outward normal `P_v x P_u`, so the
    /// frame is taken with u and v swapped to make `P_u x P_v` point out.
    fn sphere_frame(r: f32, lon: f32, colat: f32) -> CurvedFrame {
        let (st, ct) = colat.sin_cos();
        let (sp, cp) = lon.sin_cos();
        // a = colatitude, b = longitude: P_a x P_b points outward.
        let pa = Vec3::new(ct * cp, ct * sp, -st) * r;
        let pb = Vec3::new(-st * sp, st * cp, 0.0) * r;
        let paa = Vec3::new(-st * cp, -st * sp, -ct) * r;
        let pab = Vec3::new(-ct * sp, ct * cp, 0.0) * r;
        let pbb = Vec3::new(-st * cp, -st * sp, 0.0) * r;
        CurvedFrame {
            dpdu: pa,
            dpdv: pb,
            d2pdu2: paa,
            d2pdudv: pab,
            d2pdv2: pbb,
        }
    }

    #[test]
    fn a_sphere_has_curvature_one_over_r_and_dn_equals_dp_over_r() {
        let frame = sphere_frame(2.0, 0.7, 1.1);
        let outward = Vec3::new(
            1.1f32.sin() * 0.7f32.cos(),
            1.1f32.sin() * 0.7f32.sin(),
            1.1f32.cos(),
        );
        assert!((frame.normal() - outward).length() < 1e-5);
        let (k1, k2) = frame.principal_curvatures().unwrap();
        assert!(
            (k1 - 0.5).abs() < 1e-5 && (k2 - 0.5).abs() < 1e-5,
            "{k1} {k2}"
        );
        assert!((frame.cone_curvature() - 0.5).abs() < 1e-5);
        let dp = frame.dpdu * 0.01 + frame.dpdv * -0.02;
        let dn = frame.normal_derivative(dp);
        assert!((dn - dp / 2.0).length() < 1e-6, "{dn} vs {}", dp / 2.0);
    }

    #[test]
    fn a_saddle_has_mixed_curvatures_and_cone_curvature_zero() {
        // z = (x^2 - y^2) / 2 at the origin, normal +z: principal curvatures -1 and 1.
        let frame = CurvedFrame {
            dpdu: Vec3::X,
            dpdv: Vec3::Y,
            d2pdu2: Vec3::Z,
            d2pdudv: Vec3::ZERO,
            d2pdv2: -Vec3::Z,
        };
        let (k1, k2) = frame.principal_curvatures().unwrap();
        assert!((k1.min(k2) + 1.0).abs() < 1e-6 && (k1.max(k2) - 1.0).abs() < 1e-6);
        assert_eq!(frame.cone_curvature(), 0.0);
    }

    #[test]
    fn st_offsets_follow_the_parameterisation() {
        let frame = CurvedFrame {
            dpdu: Vec3::new(2.0, 0.0, 0.0),
            dpdv: Vec3::new(1.0, 1.0, 0.0),
            d2pdu2: Vec3::ZERO,
            d2pdudv: Vec3::ZERO,
            d2pdv2: Vec3::ZERO,
        };
        let d = frame.dpdu * 0.25 + frame.dpdv * 0.5 + Vec3::Z * 3.0;
        let st = curved_st_offset(&frame, Vec2::new(1.0, 0.0), Vec2::new(0.0, 2.0), d);
        assert!((st - Vec2::new(0.25, 1.0)).length() < 1e-6, "{st}");
    }
}
