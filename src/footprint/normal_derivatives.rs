//! Derivatives of the shading normal along a surface displacement, which reflection and
//! refraction of ray differentials need (seed 002, section 3.2 and the box on
//! normal-interpolated triangles).
//!
//! Planar triangles have a constant normal (zero derivative). Normal-interpolated triangles
//! differentiate the unnormalised interpolated normal through the barycentric derivatives of
//! the displacement, then the normalisation. Spheres use N = (P - O) / r, so dN = dP / r
//! (seed 002, eqs. 21-22).

use glam::Vec3;

use super::gradients::barycentric_offsets;
use crate::hit::{Patch, SurfaceHit};

/// dN for the displacement `dp` on the surface of `hit`, where N is `hit.shading_normal`
/// (same orientation). Degenerate geometry (zero-area triangle, zero interpolated normal,
/// zero radius) gives zero.
#[inline]
pub fn shading_normal_derivative(hit: &SurfaceHit, dp: Vec3) -> Vec3 {
    let dn = match &hit.patch {
        Patch::Triangle { p, n: Some(n), .. } => interpolated_normal_derivative(p, n, hit, dp),
        Patch::Triangle { n: None, .. } => Vec3::ZERO,
        Patch::Sphere { radius, .. } => {
            let inv_r = radius.abs().recip();
            // The shading normal of a sphere is the outward normal N = (P - O) / r.
            let outward = if hit.shading_normal.dot(hit.geometric_normal) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            dp * (inv_r * outward)
        }
        Patch::Curved { frame, .. } => {
            // The Weingarten derivative is that of P_u x P_v normalised; match the shading
            // normal's side.
            let dn = frame.normal_derivative(dp);
            if frame.normal().dot(hit.shading_normal) >= 0.0 {
                dn
            } else {
                -dn
            }
        }
    };
    if dn.is_finite() {
        dn
    } else {
        Vec3::ZERO
    }
}

/// Seed 002 box: dn = sum (L_i . dP) N_i, dN = ((n.n) dn - (n.dn) n) / (n.n)^(3/2), with the
/// sign matching the hit's (possibly flipped) shading normal.
#[inline]
fn interpolated_normal_derivative(
    p: &[Vec3; 3],
    n: &[Vec3; 3],
    hit: &SurfaceHit,
    dp: Vec3,
) -> Vec3 {
    let Some(db) = barycentric_offsets(p, dp) else {
        return Vec3::ZERO;
    };
    let (u, v) = (hit.barycentric.x, hit.barycentric.y);
    let interpolated = n[0] * (1.0 - u - v) + n[1] * u + n[2] * v;
    let nn = interpolated.length_squared();
    if !(nn.is_finite() && nn > 1.0e-30) {
        return Vec3::ZERO;
    }
    let dn = (n[1] - n[0]) * db.x + (n[2] - n[0]) * db.y;
    let d_unit = (dn * nn - interpolated * interpolated.dot(dn)) / (nn * nn.sqrt());
    if interpolated.dot(hit.shading_normal) < 0.0 {
        -d_unit
    } else {
        d_unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn triangle_hit(p: [Vec3; 3], n: [Vec3; 3], uv: Vec2) -> SurfaceHit {
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let interpolated = n[0] * (1.0 - uv.x - uv.y) + n[1] * uv.x + n[2] * uv.y;
        let mut ns = interpolated.normalize();
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        SurfaceHit {
            t: 1.0,
            position: p[0] * (1.0 - uv.x - uv.y) + p[1] * uv.x + p[2] * uv.y,
            geometric_normal: ng,
            shading_normal: ns,
            barycentric: uv,
            st: Vec2::ZERO,
            dpds: Vec3::ZERO,
            dpdt: Vec3::ZERO,
            material: 0,
            patch: Patch::Triangle {
                p,
                n: Some(n),
                st: None,
            },
        }
    }

    #[test]
    fn interpolated_normal_derivative_matches_finite_differences() {
        let p = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let n = [
            Vec3::new(-0.3, -0.2, 1.0),
            Vec3::new(0.4, 0.0, 2.0),
            Vec3::new(0.0, 0.5, 1.0),
        ];
        let uv = Vec2::new(0.3, 0.25);
        let hit = triangle_hit(p, n, uv);
        let dp = Vec3::new(0.01, -0.004, 0.0);
        let analytic = shading_normal_derivative(&hit, dp);
        let h = 0.01;
        let shifted = |s: f32| {
            let q = uv + Vec2::new(dp.x, dp.y) * s;
            (n[0] * (1.0 - q.x - q.y) + n[1] * q.x + n[2] * q.y).normalize()
        };
        let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
        assert!(
            (analytic - fd).length() < 1e-3 * fd.length().max(1e-3),
            "{analytic:?} {fd:?}"
        );
    }

    #[test]
    fn flat_and_degenerate_triangles_have_constant_normals() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let hit = triangle_hit(p, [Vec3::Z; 3], Vec2::new(0.2, 0.2));
        assert_eq!(shading_normal_derivative(&hit, Vec3::X), Vec3::ZERO);
        let mut degenerate = hit;
        degenerate.patch = Patch::Triangle {
            p: [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            n: Some([Vec3::Z, Vec3::X, Vec3::Y]),
            st: None,
        };
        assert_eq!(shading_normal_derivative(&degenerate, Vec3::X), Vec3::ZERO);
        let mut zero = hit;
        zero.patch = Patch::Triangle {
            p,
            n: Some([Vec3::ZERO; 3]),
            st: None,
        };
        assert_eq!(shading_normal_derivative(&zero, Vec3::X), Vec3::ZERO);
    }
}
