//! Curved surfaces: bicubic Bezier patches, the one form every curved surface of a scene
//! takes after loading.
//!
//! Seed 004 describes rectangular Bezier patches ("Rectangular Bezier Patches"), cubic
//! Hermite rectangles and Lagrange rectangles, and Bezier triangles. All of them are
//! polynomials of degree at most 3 in each parameter, so each is converted exactly (up to
//! the rounding of the conversion, done in f64) to a bicubic Bezier patch when it is
//! loaded ([`basis`]): the renderer, the intersector and the footprints see one kind of
//! surface.
//!
//! A patch is `P(u, v) = sum_ij B_i(u) B_j(v) P_ij` (seed 004's "Bezier Rectangle"
//! equation) with the cubic Bernstein polynomials `B_i`, for `(u, v)` in `[0, 1]^2`. Its
//! control points are stored row by row with `u` running fastest: `control[4 j + i]` is
//! `P_ij`, so the first four points are the edge `v = 0`.
//!
//! What this module must not do: know about Embree or rays in flight; the intersection
//! of a ray with a patch is [`intersect`], which is plain arithmetic on a [`BezierPatch`].

pub mod basis;
pub mod bpt;
pub mod height;
pub mod hull_tree;
pub mod intersect;
pub mod tessellate;

use glam::{DVec3, Vec2, Vec3};

/// A bicubic Bezier patch in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct BezierPatch {
    /// Control points `P_ij` at `control[4 j + i]` (`i` along u, `j` along v).
    pub control: [Vec3; 16],
    /// Texture coordinates (OpenImageIO convention) at the corners
    /// `(u, v) = (0, 0), (1, 0), (0, 1), (1, 1)`, interpolated bilinearly in (u, v);
    /// `None` uses `(s, t) = (u, v)`.
    pub corner_st: Option<[Vec2; 4]>,
    /// Index into `SceneDescription::materials`.
    pub material: usize,
}

/// Position and derivatives of a patch at one `(u, v)`, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchPoint {
    pub position: DVec3,
    pub dpdu: DVec3,
    pub dpdv: DVec3,
    pub d2pdu2: DVec3,
    pub d2pdudv: DVec3,
    pub d2pdv2: DVec3,
}

/// Cubic Bernstein polynomials at `t` and their first and second derivatives.
#[inline]
pub fn bernstein3(t: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
    let d = [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * t * s,
        6.0 * t * s - 3.0 * t * t,
        3.0 * t * t,
    ];
    let dd = [6.0 * s, 18.0 * t - 12.0, 6.0 - 18.0 * t, 6.0 * t];
    (b, d, dd)
}

/// The control points of `patch` in f64, in the patch's order.
#[inline]
pub fn control_f64(control: &[Vec3; 16]) -> [DVec3; 16] {
    control.map(|p| p.as_dvec3())
}

/// Position and first and second partial derivatives of the bicubic patch with f64
/// control points `c` at `(u, v)` (the tensor-product Bernstein sums and their derivatives).
pub fn evaluate(c: &[DVec3; 16], u: f64, v: f64) -> PatchPoint {
    let (bu, du, ddu) = bernstein3(u);
    let (bv, dv, ddv) = bernstein3(v);
    let mut point = PatchPoint {
        position: DVec3::ZERO,
        dpdu: DVec3::ZERO,
        dpdv: DVec3::ZERO,
        d2pdu2: DVec3::ZERO,
        d2pdudv: DVec3::ZERO,
        d2pdv2: DVec3::ZERO,
    };
    for j in 0..4 {
        for i in 0..4 {
            let p = c[4 * j + i];
            point.position += p * (bu[i] * bv[j]);
            point.dpdu += p * (du[i] * bv[j]);
            point.dpdv += p * (bu[i] * dv[j]);
            point.d2pdu2 += p * (ddu[i] * bv[j]);
            point.d2pdudv += p * (du[i] * dv[j]);
            point.d2pdv2 += p * (bu[i] * ddv[j]);
        }
    }
    point
}

impl BezierPatch {
    /// Position and derivatives at `(u, v)`.
    pub fn evaluate(&self, u: f64, v: f64) -> PatchPoint {
        evaluate(&control_f64(&self.control), u, v)
    }

    /// Axis-aligned bounds of the control points, which contain the patch (a Bezier patch
    /// lies in the convex hull of its control points).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let lo = self.control.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
        let hi = self
            .control
            .iter()
            .fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
        (lo, hi)
    }

    /// Texture coordinates at `(u, v)` and their derivatives with respect to u and v.
    pub fn st(&self, u: f32, v: f32) -> (Vec2, Vec2, Vec2) {
        match self.corner_st {
            None => (Vec2::new(u, v), Vec2::X, Vec2::Y),
            Some([a, b, c, d]) => {
                let st = a * ((1.0 - u) * (1.0 - v))
                    + b * (u * (1.0 - v))
                    + c * ((1.0 - u) * v)
                    + d * (u * v);
                let dst_du = (b - a) * (1.0 - v) + (d - c) * v;
                let dst_dv = (c - a) * (1.0 - u) + (d - b) * u;
                (st, dst_du, dst_dv)
            }
        }
    }

    /// Why the patch cannot be rendered, if it cannot: a non-finite control point, or a
    /// fully degenerate patch (no point of it spans any area: all control points on one
    /// point or one line). Collapsed edges, as at the teapot's lid and bottom, are fine.
    pub fn problem(&self) -> Option<String> {
        if let Some(i) = self.control.iter().position(|p| !p.is_finite()) {
            return Some(format!(
                "control point {i} is not finite ({})",
                self.control[i]
            ));
        }
        let (lo, hi) = self.bounds();
        let extent = f64::from((hi - lo).max_element());
        if extent == 0.0 {
            return Some("fully degenerate: every control point is the same point".into());
        }
        // Sample the normal's length on a grid; a patch whose every sample spans no area
        // (relative to its size) is a point or a curve, not a surface.
        let c = control_f64(&self.control);
        let spans_area = (0..=6).any(|a| {
            (0..=6).any(|b| {
                let p = evaluate(&c, f64::from(a) / 6.0, f64::from(b) / 6.0);
                p.dpdu.cross(p.dpdv).length() > 1e-9 * extent * extent
            })
        });
        (!spans_area).then(|| "fully degenerate: the patch spans no area".to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy() -> BezierPatch {
        let mut control = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                let h = ((i * 7 + j * 3) % 5) as f32 * 0.3 - 0.6;
                control[4 * j + i] = Vec3::new(i as f32, h, j as f32);
            }
        }
        BezierPatch {
            control,
            corner_st: None,
            material: 0,
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let patch = wavy();
        let h = 1e-5;
        for &(u, v) in &[(0.3, 0.6), (0.0, 0.0), (0.9, 0.1), (0.5, 1.0)] {
            let p = patch.evaluate(u, v);
            let pu = |u: f64| patch.evaluate(u, v);
            let pv = |v: f64| patch.evaluate(u, v);
            let fd_u = (pu(u + h).position - pu(u - h).position) / (2.0 * h);
            let fd_v = (pv(v + h).position - pv(v - h).position) / (2.0 * h);
            let fd_uu = (pu(u + h).dpdu - pu(u - h).dpdu) / (2.0 * h);
            let fd_uv = (pv(v + h).dpdu - pv(v - h).dpdu) / (2.0 * h);
            let fd_vv = (pv(v + h).dpdv - pv(v - h).dpdv) / (2.0 * h);
            for (exact, fd) in [
                (p.dpdu, fd_u),
                (p.dpdv, fd_v),
                (p.d2pdu2, fd_uu),
                (p.d2pdudv, fd_uv),
                (p.d2pdv2, fd_vv),
            ] {
                assert!(
                    (exact - fd).length() < 1e-6,
                    "{exact} vs {fd} at ({u}, {v})"
                );
            }
        }
    }

    #[test]
    fn corners_are_the_corner_control_points() {
        let patch = wavy();
        for (u, v, index) in [(0.0, 0.0, 0), (1.0, 0.0, 3), (0.0, 1.0, 12), (1.0, 1.0, 15)] {
            let p = patch.evaluate(u, v).position;
            assert!((p - patch.control[index].as_dvec3()).length() < 1e-12);
        }
    }

    #[test]
    fn degenerate_patches_are_named() {
        let mut patch = wavy();
        assert_eq!(patch.problem(), None);
        patch.control = [Vec3::ONE; 16];
        assert!(patch.problem().unwrap().contains("same point"));
        patch.control = std::array::from_fn(|k| Vec3::new(k as f32, 2.0 * k as f32, 0.0));
        assert!(patch.problem().unwrap().contains("no area"));
        patch.control[5].y = f32::NAN;
        assert!(patch.problem().unwrap().contains("control point 5"));
    }
}
