//! A single ray cone: width and spread angle of the region a ray samples (seed 000).
//!
//! Under the small-angle approximation a cone is two numbers, its width `w` at the ray's
//! current position and its spread angle `alpha` (positive diverging, negative converging).
//! This file holds the cone's own algebra: initialisation per camera model, propagation,
//! reflection and refraction. Projecting a cone onto a surface lives in
//! `gradients.rs`; the two-cone envelope in `cone_envelope.rs`.

use glam::Vec3;

use super::robust::finite;

/// A ray cone: `width` at the current position along the ray and spread `angle` in radians.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCone {
    /// Width at the current position (w); non-negative after any propagation.
    pub width: f32,
    /// Spread angle in radians (alpha): positive diverging, negative converging.
    pub angle: f32,
}

impl RayCone {
    /// A cone of `width` and spread `angle`, with non-finite values made finite.
    #[inline]
    pub fn new(width: f32, angle: f32) -> RayCone {
        RayCone {
            width: finite(width),
            angle: finite(angle),
        }
    }

    /// Pinhole camera (seed 000): zero width at the eye, one pixel wide on the view
    /// rectangle. `w_axis` runs from the eye to the rectangle's centre, `half_width` and
    /// `half_height` are |U| and |V|, `dir` is the unit ray direction:
    /// alpha = 2 min(|U| D.W / (w_img W.W), |V| D.W / (h_img W.W)).
    #[inline]
    pub fn pinhole(
        dir: Vec3,
        w_axis: Vec3,
        half_width: f32,
        half_height: f32,
        image_width: u32,
        image_height: u32,
    ) -> RayCone {
        let dw = dir.dot(w_axis).abs();
        Self::pinhole_at_axis_cosine(
            dw,
            w_axis.length_squared(),
            half_width,
            half_height,
            image_width,
            image_height,
        )
    }

    /// [`RayCone::pinhole`] from `dw` = |D.W| and `ww` = W.W, for callers that compute
    /// |D.W| for many rays at once.
    #[inline]
    pub fn pinhole_at_axis_cosine(
        dw: f32,
        ww: f32,
        half_width: f32,
        half_height: f32,
        image_width: u32,
        image_height: u32,
    ) -> RayCone {
        let per_pixel =
            (half_width / image_width.max(1) as f32).min(half_height / image_height.max(1) as f32);
        RayCone::new(0.0, 2.0 * per_pixel * dw / ww)
    }

    /// Thin-lens camera (seed 000): starts as wide as the lens and converges to zero on the
    /// focal plane at the end of `w_axis`: alpha = -w_lens D.W / W.W, w = w_lens.
    #[inline]
    pub fn thin_lens(lens_width: f32, dir: Vec3, w_axis: Vec3) -> RayCone {
        let dw = dir.dot(w_axis).abs();
        Self::thin_lens_at_axis_cosine(lens_width, dw, w_axis.length_squared())
    }

    /// [`RayCone::thin_lens`] from `dw` = |D.W| and `ww` = W.W.
    #[inline]
    pub fn thin_lens_at_axis_cosine(lens_width: f32, dw: f32, ww: f32) -> RayCone {
        RayCone::new(lens_width, -lens_width * dw / ww)
    }

    /// Orthographic camera (seed 000): no spread, one pixel wide:
    /// alpha = 0, w = 2 min(|U| / w_img, |V| / h_img).
    #[inline]
    pub fn orthographic(
        half_width: f32,
        half_height: f32,
        image_width: u32,
        image_height: u32,
    ) -> RayCone {
        let per_pixel =
            (half_width / image_width.max(1) as f32).min(half_height / image_height.max(1) as f32);
        RayCone::new(2.0 * per_pixel, 0.0)
    }

    /// The cone moved `distance` along its ray (seed 000: w' = w + alpha d). A cone whose
    /// width and angle are both negative has passed its apex and is really diverging, so
    /// both signs are flipped: the width stays non-negative.
    #[inline]
    pub fn propagate(self, distance: f32) -> RayCone {
        let d = if distance.is_nan() {
            0.0
        } else {
            distance.max(0.0)
        };
        let w = finite(self.width + self.angle * d);
        if w < 0.0 && self.angle < 0.0 {
            RayCone::new(-w, -self.angle)
        } else {
            RayCone::new(w, self.angle)
        }
    }

    /// The cone after a mirror reflection off a surface of curvature `k` (signed for the
    /// side the ray arrives from): alpha' = alpha + 2 k |w| (seed 000).
    #[inline]
    pub fn reflect(self, curvature: f32) -> RayCone {
        RayCone::new(
            self.width,
            self.angle + 2.0 * finite(curvature) * self.width.abs(),
        )
    }

    /// The cone after refraction with `eta` = n_incident / n_transmitted through a surface
    /// of curvature `k`: alpha' = eta (alpha + k |w|) - k |w| (seed 000, with n_o / n_i = eta).
    #[inline]
    pub fn refract(self, curvature: f32, eta: f32) -> RayCone {
        let eta = if eta.is_finite() && eta > 0.0 {
            eta
        } else {
            1.0
        };
        let kw = finite(curvature) * self.width.abs();
        // eta (alpha + k|w|) - k|w|, arranged to be exact for eta = 1.
        RayCone::new(self.width, eta * self.angle + (eta - 1.0) * kw)
    }

    /// Width as a non-negative length.
    #[inline]
    pub fn abs_width(&self) -> f32 {
        self.width.abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinhole_cone_is_one_pixel_wide_on_the_view_rectangle() {
        let w_axis = Vec3::new(0.0, 0.0, -2.0);
        let (u, v) = (1.5f32, 1.0f32);
        let (iw, ih) = (300, 200);
        let pixel = 2.0 * u / iw as f32;
        for dir in [Vec3::NEG_Z, Vec3::new(0.5, 0.3, -2.0).normalize()] {
            let cone = RayCone::pinhole(dir, w_axis, u, v, iw, ih);
            // Distance along the ray to the view rectangle's plane.
            let d = 2.0 / -dir.z;
            let at_plane = cone.propagate(d);
            assert!((at_plane.width - pixel).abs() < 1e-6 * pixel.max(1.0));
        }
    }

    #[test]
    fn thin_lens_cone_converges_on_the_focal_plane_and_flips() {
        let w_axis = Vec3::new(0.0, 0.0, -5.0);
        let dir = Vec3::new(0.2, 0.0, -1.0).normalize();
        let cone = RayCone::thin_lens(0.1, dir, w_axis);
        let focal = 5.0 / -dir.z;
        assert!(cone.propagate(focal).width.abs() < 1e-6);
        let beyond = cone.propagate(2.0 * focal);
        assert!((beyond.width - 0.1).abs() < 1e-5 && beyond.angle > 0.0);
    }

    #[test]
    fn orthographic_cone_keeps_its_width() {
        let cone = RayCone::orthographic(2.0, 1.0, 400, 200);
        assert_eq!(cone.width, 0.01);
        assert_eq!(cone.propagate(100.0).width, 0.01);
    }

    #[test]
    fn reflection_and_refraction_follow_seed_000() {
        let cone = RayCone::new(0.2, 0.01);
        assert!((cone.reflect(0.5).angle - (0.01 + 2.0 * 0.5 * 0.2)).abs() < 1e-7);
        assert!((cone.reflect(-0.5).angle - (0.01 - 0.2)).abs() < 1e-7);
        let r = cone.refract(0.5, 1.0 / 1.5);
        assert!((r.angle - ((0.01 + 0.1) / 1.5 - 0.1)).abs() < 1e-7);
        assert_eq!(cone.refract(0.5, 1.0).angle, cone.angle);
        assert_eq!(cone.refract(0.5, f32::NAN).angle, cone.angle);
    }
}
