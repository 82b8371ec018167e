//! Texture gradients: turning a world-space footprint at a hit into st-space derivatives.
//!
//! A footprint at a surface is a pair of world-space vectors dP/dx, dP/dy in the surface's
//! tangent plane. For ray cones they are the axes of the ellipse the cone's circle projects
//! to (seed 000, "Projecting a Ray Cone to a Surface"); for ray differentials they are the
//! differentials themselves. Either way, st derivatives follow from the surface's texture
//! parameterisation: barycentric offsets on triangles (seed 000, "Texture Derivatives on a
//! Triangle"; seed 002, box "Normal-Interpolated Triangles") or projection on dP/ds, dP/dt on
//! general surfaces such as spheres (seed 000, "Texture Derivatives on a General Surface").
//!
//! Every function here returns finite values: degenerate triangles, zero-area st mappings
//! and missing parameterisations give zero gradients (a point sample), never NaN.

use glam::{Vec2, Vec3};

use super::robust::{finite, unit_or, MIN_COSINE};
use crate::hit::{Patch, SurfaceHit};

/// Texture-space derivatives of one lookup, in normalised st units per pixel
/// (OpenImageIO's `dsdx, dtdx, dsdy, dtdy`). All zero means a point sample at mip level 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureGradients {
    /// ds per pixel along the footprint's first axis.
    pub dsdx: f32,
    /// dt per pixel along the footprint's first axis.
    pub dtdx: f32,
    /// ds per pixel along the footprint's second axis.
    pub dsdy: f32,
    /// dt per pixel along the footprint's second axis.
    pub dtdy: f32,
}

impl TextureGradients {
    /// Zero gradients: a point sample.
    pub const ZERO: TextureGradients = TextureGradients {
        dsdx: 0.0,
        dtdx: 0.0,
        dsdy: 0.0,
        dtdy: 0.0,
    };

    /// Gradients from the two st-space axes.
    #[inline]
    pub fn from_axes(ddx: Vec2, ddy: Vec2) -> TextureGradients {
        TextureGradients {
            dsdx: finite(ddx.x),
            dtdx: finite(ddx.y),
            dsdy: finite(ddy.x),
            dtdy: finite(ddy.y),
        }
    }

    /// The x axis (ds/dx, dt/dx).
    #[inline]
    pub fn ddx(&self) -> Vec2 {
        Vec2::new(self.dsdx, self.dtdx)
    }

    /// The y axis (ds/dy, dt/dy).
    #[inline]
    pub fn ddy(&self) -> Vec2 {
        Vec2::new(self.dsdy, self.dtdy)
    }

    /// Length of the longer axis (seed 002, eq. 26 before the log2).
    #[inline]
    pub fn max_axis_length(&self) -> f32 {
        self.ddx().length().max(self.ddy().length())
    }

    /// True when every component is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.dsdx.is_finite()
            && self.dtdx.is_finite()
            && self.dsdy.is_finite()
            && self.dtdy.is_finite()
    }
}

/// The elliptical footprint of a circular cone of width `width` arriving along unit `dir` at a
/// surface with unit normal `normal` (seed 000, "Projecting a Ray Cone to a Surface"):
///
/// dPdx = |w| normalize(D - (D.N)N) / max(|D.N|, 1/aniso),  dPdy = |w| normalize(D x N).
///
/// `max_aniso` is clamped to [1, 1e6]. A head-on hit (D parallel to N) has no preferred axis
/// and gets an arbitrary orthonormal pair of the tangent plane.
// Always inlined: lane loops (`integrator::lanes::footprints`) vectorise only what is
// inlined into them.
#[inline(always)]
pub fn project_cone_to_ellipse(
    width: f32,
    dir: Vec3,
    normal: Vec3,
    max_aniso: f32,
) -> (Vec3, Vec3) {
    let w = finite(width).abs();
    let aniso = if max_aniso.is_nan() {
        1.0
    } else {
        max_aniso.clamp(1.0, 1.0e6)
    };
    let cos = dir.dot(normal);
    let tangent = dir - cos * normal;
    let (major_dir, minor_dir) = if tangent.length_squared() > 1.0e-12 {
        let major = tangent.normalize();
        // normalize(D x N) = normalize(tangent x N): perpendicular to the major axis in-plane.
        (
            major,
            unit_or(major.cross(normal), normal.any_orthonormal_vector()),
        )
    } else {
        normal.any_orthonormal_pair()
    };
    let stretch = cos.abs().max(aniso.recip()).max(MIN_COSINE);
    (major_dir * (w / stretch), minor_dir * w)
}

/// Barycentric offsets (du, dv) of a world-space displacement `d` on the plane of triangle `p`
/// (Embree's convention `P = (1-u-v) p0 + u p1 + v p2`); components of `d` off the plane are
/// dropped. `None` for a degenerate (zero-area, collinear, non-finite) triangle.
///
/// These are the L_beta . dP and L_gamma . dP of seed 002's box on normal-interpolated
/// triangles, with L_alpha . dP = -(du + dv) since the weights of an in-plane direction sum
/// to zero.
#[inline]
pub fn barycentric_offsets(p: &[Vec3; 3], d: Vec3) -> Option<Vec2> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let n = e1.cross(e2);
    let nn = n.length_squared();
    let scale = e1.length_squared() * e2.length_squared();
    if !(nn.is_finite() && scale.is_finite()) || nn <= 1.0e-12 * scale || nn < 1.0e-36 {
        return None;
    }
    let inv = nn.recip();
    let du = d.cross(e2).dot(n) * inv;
    let dv = e1.cross(d).dot(n) * inv;
    (du.is_finite() && dv.is_finite()).then_some(Vec2::new(du, dv))
}

/// st change along `d` on a triangle with texture coordinates `st` (seed 000: ddx =
/// (a_x - 1) T_a + b_x T_b + c_x T_c; seed 002 box: dT/dx = sum (L_i . dP/dx) T_i).
#[inline]
pub fn triangle_st_offset(p: &[Vec3; 3], st: &[Vec2; 3], d: Vec3) -> Vec2 {
    match barycentric_offsets(p, d) {
        Some(b) => (st[1] - st[0]) * b.x + (st[2] - st[0]) * b.y,
        None => Vec2::ZERO,
    }
}

/// st change along `d` on a general surface with orthogonal texture derivatives dP/ds, dP/dt
/// (seed 000: ddx = (dPdx.dPds / dPds.dPds, dPdx.dPdt / dPdt.dPdt)). A vanishing derivative
/// (such as dP/ds at a sphere's pole) contributes nothing.
#[inline]
pub fn general_st_offset(dpds: Vec3, dpdt: Vec3, d: Vec3) -> Vec2 {
    let project = |axis: Vec3| {
        let len2 = axis.length_squared();
        if len2.is_finite() && len2 > 1.0e-30 {
            d.dot(axis) / len2
        } else {
            0.0
        }
    };
    Vec2::new(project(dpds), project(dpdt))
}

/// Texture gradients at `hit` for the world-space footprint axes `dpdx`, `dpdy`: barycentric
/// on triangles with st, dP/ds-dP/dt projection on other surfaces (spheres), zero where the
/// surface has no texture parameterisation.
#[inline]
pub fn surface_gradients(hit: &SurfaceHit, dpdx: Vec3, dpdy: Vec3) -> TextureGradients {
    let (ddx, ddy) = match &hit.patch {
        Patch::Triangle {
            p, st: Some(st), ..
        } => {
            if barycentric_offsets(p, dpdx).is_some() {
                (
                    triangle_st_offset(p, st, dpdx),
                    triangle_st_offset(p, st, dpdy),
                )
            } else {
                // Degenerate triangle: use the hit's own dP/ds, dP/dt if it has any.
                (
                    general_st_offset(hit.dpds, hit.dpdt, dpdx),
                    general_st_offset(hit.dpds, hit.dpdt, dpdy),
                )
            }
        }
        Patch::Triangle { st: None, .. } => return TextureGradients::ZERO,
        Patch::Curved {
            frame,
            dstdu,
            dstdv,
            ..
        } => (
            super::patch_surface::curved_st_offset(frame, *dstdu, *dstdv, dpdx),
            super::patch_surface::curved_st_offset(frame, *dstdu, *dstdv, dpdy),
        ),
        Patch::Sphere { center, radius } => {
            let (dpds, dpdt) = if hit.dpds != Vec3::ZERO || hit.dpdt != Vec3::ZERO {
                (hit.dpds, hit.dpdt)
            } else {
                let n = unit_or(hit.position - *center, Vec3::Y);
                let (_, dpds, dpdt) = super::environment::lat_long_frame(n, *radius);
                (dpds, dpdt)
            };
            (
                general_st_offset(dpds, dpdt, dpdx),
                general_st_offset(dpds, dpdt, dpdy),
            )
        }
    };
    TextureGradients::from_axes(ddx, ddy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_on_projection_is_isotropic() {
        let (x, y) = project_cone_to_ellipse(0.5, Vec3::NEG_Z, Vec3::Z, 16.0);
        assert!((x.length() - 0.5).abs() < 1e-6 && (y.length() - 0.5).abs() < 1e-6);
        assert!(x.dot(y).abs() < 1e-6);
        assert!(x.z.abs() < 1e-6 && y.z.abs() < 1e-6);
    }

    #[test]
    fn tilted_projection_stretches_by_inverse_cosine_up_to_the_clamp() {
        let n = Vec3::Y;
        for &deg in &[0.0f32, 30.0, 60.0, 80.0, 85.0, 89.0, 89.99] {
            let a = deg.to_radians();
            let dir = Vec3::new(a.sin(), -a.cos(), 0.0);
            let (x, y) = project_cone_to_ellipse(1.0, dir, n, 16.0);
            let expected = 1.0 / a.cos().max(1.0 / 16.0);
            assert!(
                (x.length() - expected).abs() < 1e-3 * expected,
                "{deg}: {}",
                x.length()
            );
            assert!((y.length() - 1.0).abs() < 1e-6);
            assert!(x.dot(n).abs() < 1e-5 && y.dot(n).abs() < 1e-5);
        }
    }

    #[test]
    fn barycentric_offsets_recover_edges_and_reject_degenerate_triangles() {
        let p = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
        ];
        let b = barycentric_offsets(&p, Vec3::new(1.0, 1.5, 7.0)).unwrap();
        assert!((b - Vec2::new(0.5, 0.5)).length() < 1e-6);
        let collinear = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert!(barycentric_offsets(&collinear, Vec3::Y).is_none());
        let point = [Vec3::ONE; 3];
        assert!(barycentric_offsets(&point, Vec3::Y).is_none());
    }

    #[test]
    fn triangle_offsets_follow_the_st_mapping() {
        let p = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let st = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 4.0)];
        let d = triangle_st_offset(&p, &st, Vec3::new(0.2, 0.1, 0.0));
        assert!((d - Vec2::new(0.1, 0.2)).length() < 1e-6);
        let flat = [Vec2::splat(0.3); 3];
        assert_eq!(triangle_st_offset(&p, &flat, Vec3::X), Vec2::ZERO);
    }

    #[test]
    fn general_offsets_divide_by_squared_lengths() {
        let d = general_st_offset(Vec3::X * 2.0, Vec3::Y * 0.5, Vec3::new(1.0, 1.0, 0.0));
        assert!((d - Vec2::new(0.5, 2.0)).length() < 1e-6);
        assert_eq!(
            general_st_offset(Vec3::ZERO, Vec3::ZERO, Vec3::X),
            Vec2::ZERO
        );
    }
}
