//! Cameras: turn a pixel position (and a lens sample) into a ray, and give that ray the
//! footprint it starts with.
//!
//! Three projections (`crate::scene::Projection`): pinhole, thin lens and orthographic.
//! Each is described by seed 000's camera frame: `W` from the eye to the centre of the view
//! rectangle, `U` and `V` half its width and height. The pinhole's and the orthographic
//! camera's rectangle lies at the target's distance, the thin lens's on its focal plane.
//! Pixel coordinates run x right, y down, with pixel centres at +0.5.
//!
//! Initial footprints: seed 000's cone initialisation per projection (and the second cone
//! of the two-cone envelope), seed 002's eq. 8 for ray differentials (for a thin lens,
//! differentiated with respect to the pixel at a fixed lens sample; for an orthographic
//! camera, the origin moves and the direction does not).

mod lens;
mod matrices;

use glam::{Vec2, Vec3};

use crate::footprint::robust::unit_or;
use crate::footprint::{
    ConeEnvelope, DistanceFootprint, Footprint, LodStrategy, RayCone, RayDifferential,
};
use crate::scene::{CameraDesc, Projection};

pub use lens::concentric_disk;

/// The projection a [`Camera`] uses, with its validated parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraModel {
    /// All rays from the eye point.
    Pinhole,
    /// A thin lens of `lens_radius` focused on the view rectangle.
    ThinLens {
        /// Radius of the lens disk in world units (positive).
        lens_radius: f32,
    },
    /// Parallel rays from the view rectangle.
    Orthographic,
}

/// A camera ready to generate rays for an image of `width` x `height` pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    model: CameraModel,
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// Eye to the centre of the view rectangle.
    w: Vec3,
    /// Half the view rectangle's width (to the right) and height (upwards).
    u: Vec3,
    v: Vec3,
    /// |U| and |V|, which every camera ray's footprint needs (computed once).
    half_width: f32,
    half_height: f32,
    width: u32,
    height: u32,
}

impl Camera {
    /// A camera for `desc` rendering `width` x `height` pixels. Degenerate descriptions are
    /// repaired rather than rejected (the scene loader validates and reports them): eye ==
    /// target looks down -Z, an up vector parallel to the view picks another, field of view
    /// is clamped to [1e-7, 179] degrees (45 if not finite; the lower bound keeps the view's
    /// half-height, `tan(fov / 2)` times the target's distance, a normal f32 at any distance
    /// a scene can have, and frames a 0.0175-unit patch from 1e6 units away, which the old
    /// bound of 1e-3 degrees widened to 17 units), a non-positive focus distance
    /// uses the target's distance, a non-positive orthographic height becomes 1, and a zero
    /// image size counts as 1.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let width = width.max(1);
        let height = height.max(1);
        let aspect = width as f32 / height as f32;
        let eye = if desc.eye.is_finite() {
            desc.eye
        } else {
            Vec3::ZERO
        };
        let to_target = desc.target - eye;
        let target_distance = {
            let d = to_target.length();
            if d.is_finite() && d > 1.0e-12 {
                d
            } else {
                1.0
            }
        };
        let forward = unit_or(to_target, Vec3::NEG_Z);
        let right = unit_or(forward.cross(desc.up), forward.any_orthonormal_vector());
        let up = right.cross(forward);
        let tan_half = |vfov: f32| {
            let deg = if vfov.is_finite() {
                vfov.clamp(1.0e-7, 179.0)
            } else {
                45.0
            };
            (deg.to_radians() * 0.5).tan()
        };
        let (model, plane_distance, half_height) = match desc.projection {
            Projection::Pinhole { vfov_degrees } => (
                CameraModel::Pinhole,
                target_distance,
                tan_half(vfov_degrees) * target_distance,
            ),
            Projection::ThinLens {
                vfov_degrees,
                aperture_radius,
                focus_distance,
            } => {
                let focus = if focus_distance.is_finite() && focus_distance > 0.0 {
                    focus_distance
                } else {
                    target_distance
                };
                let radius = if aperture_radius.is_finite() {
                    aperture_radius.abs()
                } else {
                    0.0
                };
                let model = if radius > 0.0 {
                    CameraModel::ThinLens {
                        lens_radius: radius,
                    }
                } else {
                    CameraModel::Pinhole
                };
                (model, focus, tan_half(vfov_degrees) * focus)
            }
            Projection::Orthographic { height } => {
                let h = if height.is_finite() && height > 0.0 {
                    height
                } else {
                    1.0
                };
                (CameraModel::Orthographic, target_distance, 0.5 * h)
            }
        };
        let u = right * (half_height * aspect);
        let v = up * half_height;
        Camera {
            model,
            eye,
            forward,
            right,
            up,
            w: forward * plane_distance,
            u,
            v,
            half_width: u.length(),
            half_height: v.length(),
            width,
            height,
        }
    }

    /// The projection in use (a thin lens of zero radius is a pinhole).
    #[inline]
    pub fn model(&self) -> CameraModel {
        self.model
    }

    /// Unit viewing direction.
    #[inline]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The eye point (centre of the lens).
    #[inline]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// Image size in pixels.
    #[inline]
    pub fn resolution(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Width of one pixel on the view rectangle: 2 min(|U| / w_img, |V| / h_img).
    #[inline]
    pub fn pixel_size(&self) -> f32 {
        2.0 * (self.half_width / self.width as f32).min(self.half_height / self.height as f32)
    }

    /// The point on the view rectangle under pixel coordinates (px, py), relative to the eye.
    #[inline]
    fn rectangle_point(&self, px: f32, py: f32) -> Vec3 {
        let x = 2.0 * px / self.width as f32 - 1.0;
        let y = 1.0 - 2.0 * py / self.height as f32;
        self.w + self.u * x + self.v * y
    }

    /// How the view-rectangle point moves per pixel in x and in y.
    #[inline]
    fn rectangle_per_pixel(&self) -> (Vec3, Vec3) {
        (
            self.u * (2.0 / self.width as f32),
            self.v * (-2.0 / self.height as f32),
        )
    }

    /// Pixel coordinates px in [0,width), py in [0,height) (y down, pixel centre at +0.5),
    /// lens sample in [0,1)^2 (ignored unless thin lens). Returns the ray origin and unit
    /// direction. Non-finite pixel coordinates are treated as the image centre.
    #[inline]
    pub fn generate_ray(&self, px: f32, py: f32, lens: Vec2) -> (Vec3, Vec3) {
        let (px, py) = self.sanitize_pixel(px, py);
        let on_rectangle = self.rectangle_point(px, py);
        match self.model {
            CameraModel::Pinhole => (self.eye, unit_or(on_rectangle, self.forward)),
            CameraModel::ThinLens { lens_radius } => {
                let disk = concentric_disk(lens) * lens_radius;
                let origin = self.eye + self.right * disk.x + self.up * disk.y;
                let focus = self.eye + on_rectangle;
                (origin, unit_or(focus - origin, self.forward))
            }
            CameraModel::Orthographic => (self.eye + (on_rectangle - self.w), self.forward),
        }
    }

    /// Unit directions of pinhole rays through the pixel positions (`px[i]`, `py[i]`), lane
    /// by lane the bits [`Camera::generate_ray`] gives (the same operations in the same
    /// order), computed as structure-of-arrays so that the divisions and square roots of a
    /// packet's lanes run as vector instructions. Every ray starts at [`Camera::eye`].
    /// Returns `None` unless the camera is a pinhole. Always inlined, so that a
    /// `simd::dispatch` kernel compiles it for its level.
    #[inline(always)]
    pub fn pinhole_directions<const N: usize>(
        &self,
        px: &[f32; N],
        py: &[f32; N],
    ) -> Option<[[f32; N]; 3]> {
        if self.model != CameraModel::Pinhole {
            return None;
        }
        let mut out = [[0.0f32; N]; 3];
        for lane in 0..N {
            let direction = self.pinhole_direction(px[lane], py[lane]);
            out[0][lane] = direction.x;
            out[1][lane] = direction.y;
            out[2][lane] = direction.z;
        }
        Some(out)
    }

    /// The unit direction of the pinhole ray through pixel position (px, py), as
    /// [`Camera::generate_ray`] makes it.
    #[inline]
    fn pinhole_direction(&self, px: f32, py: f32) -> Vec3 {
        let (px, py) = self.sanitize_pixel(px, py);
        unit_or(self.rectangle_point(px, py), self.forward)
    }

    #[inline]
    fn sanitize_pixel(&self, px: f32, py: f32) -> (f32, f32) {
        let fix = |p: f32, size: u32| if p.is_finite() { p } else { 0.5 * size as f32 };
        (fix(px, self.width), fix(py, self.height))
    }

    /// The footprint the ray (`origin`, unit `dir`) through pixel (px, py) starts with when
    /// it is its pixel's only sample: [`Camera::sample_footprint`] with one sample.
    pub fn initial_footprint(
        &self,
        strategy: LodStrategy,
        px: f32,
        py: f32,
        origin: Vec3,
        dir: Vec3,
    ) -> Footprint {
        self.sample_footprint(strategy, px, py, origin, dir, 1)
    }

    /// The footprint the ray (`origin`, unit `dir`) through pixel (px, py) starts with, as
    /// one of `samples_per_pixel` samples of its pixel.
    ///
    /// - `Distance`: zero width spreading at the pinhole angle (perspective cameras) or one
    ///   pixel wide without spread (orthographic).
    /// - `Cone1`: seed 000's cone for the projection (thin lens: the lens cone).
    /// - `Cone`: seed 000's two-cone envelope: pinhole + thin lens of one-pixel width
    ///   focused on the view rectangle; thin lens + pinhole; orthographic + thin lens of
    ///   one-pixel width. The extra cone is ignored on the first hit of pinhole and
    ///   orthographic cameras.
    /// - `Differential`: seed 002, eq. 8 (pinhole), the same at a fixed lens point for a
    ///   thin lens (`origin` is that point), moving origins for orthographic.
    ///
    /// Every extent that one pixel sets (the pinhole spread, the orthographic and pixel-lens
    /// widths, the differentials' per-pixel steps) is scaled by
    /// [`sample_footprint_scale`]: N samples share the pixel, so each filters about 1/N of
    /// its area. The lens aperture's cone is not a pixel extent and keeps its size.
    pub fn sample_footprint(
        &self,
        strategy: LodStrategy,
        px: f32,
        py: f32,
        origin: Vec3,
        dir: Vec3,
        samples_per_pixel: u32,
    ) -> Footprint {
        let dw = self.axis_cosine(dir);
        self.sample_footprint_at(strategy, px, py, origin, dw, samples_per_pixel)
    }

    /// |D.W| for the ray direction `dir` (made unit, or the camera's forward axis if it
    /// cannot be): what the cones of [`Camera::sample_footprint`] need of the direction.
    #[inline(always)]
    pub fn axis_cosine(&self, dir: Vec3) -> f32 {
        unit_or(dir, self.forward).dot(self.w).abs()
    }

    /// [`Camera::sample_footprint`] with the direction given as its [`Camera::axis_cosine`],
    /// which the camera block computes for 16 rays at once.
    #[inline]
    pub fn sample_footprint_at(
        &self,
        strategy: LodStrategy,
        px: f32,
        py: f32,
        origin: Vec3,
        dw: f32,
        samples_per_pixel: u32,
    ) -> Footprint {
        let scale = sample_footprint_scale(samples_per_pixel);
        let ww = self.w.length_squared();
        let (hu, hv) = (self.half_width, self.half_height);
        let pinhole = || {
            let cone = RayCone::pinhole_at_axis_cosine(dw, ww, hu, hv, self.width, self.height);
            RayCone::new(cone.width, cone.angle * scale)
        };
        let ortho = || {
            let cone = RayCone::orthographic(hu, hv, self.width, self.height);
            RayCone::new(cone.width * scale, cone.angle)
        };
        let pixel_lens = || RayCone::thin_lens_at_axis_cosine(self.pixel_size() * scale, dw, ww);
        match strategy {
            LodStrategy::Mip0 => Footprint::Mip0,
            LodStrategy::Distance => Footprint::Distance(match self.model {
                CameraModel::Orthographic => DistanceFootprint::new(ortho().width, 0.0),
                _ => DistanceFootprint::new(0.0, pinhole().angle),
            }),
            LodStrategy::Cone1 => Footprint::Cone1(match self.model {
                CameraModel::Pinhole => pinhole(),
                CameraModel::ThinLens { lens_radius } => {
                    RayCone::thin_lens_at_axis_cosine(2.0 * lens_radius, dw, ww)
                }
                CameraModel::Orthographic => ortho(),
            }),
            LodStrategy::Cone => Footprint::Cone(match self.model {
                CameraModel::Pinhole => ConeEnvelope::new(pinhole(), pixel_lens(), true),
                CameraModel::ThinLens { lens_radius } => ConeEnvelope::new(
                    RayCone::thin_lens_at_axis_cosine(2.0 * lens_radius, dw, ww),
                    pinhole(),
                    false,
                ),
                CameraModel::Orthographic => ConeEnvelope::new(ortho(), pixel_lens(), true),
            }),
            LodStrategy::Differential => {
                let (px, py) = self.sanitize_pixel(px, py);
                let (dx, dy) = self.rectangle_per_pixel();
                let (dx, dy) = (dx * scale, dy * scale);
                Footprint::Differential(match self.model {
                    CameraModel::Pinhole => {
                        RayDifferential::from_point(self.rectangle_point(px, py), dx, dy)
                    }
                    CameraModel::ThinLens { .. } => {
                        let lens_point = if origin.is_finite() { origin } else { self.eye };
                        let focus = self.eye + self.rectangle_point(px, py);
                        RayDifferential::from_point(focus - lens_point, dx, dy)
                    }
                    CameraModel::Orthographic => RayDifferential::parallel(dx, dy),
                })
            }
        }
    }
}

impl Camera {
    /// The footprint a camera ray through the point `p` (on a surface of unit normal `n`)
    /// would have there: dP/dx and dP/dy on the tangent plane, for lookups at hits whose
    /// own differentials were lost to a non-specular bounce. pbrt-v4 approximates its
    /// non-specular bounces the same way (`Approximate_dp_dxy`): a ray from the eye towards
    /// `p` and its neighbours one pixel over, turned by the per-pixel direction step at the
    /// image centre (or moved by the per-pixel step, orthographic), are intersected with
    /// the tangent plane; the steps are scaled by [`sample_footprint_scale`].
    pub fn approximate_dp_dxy(&self, p: Vec3, n: Vec3, samples_per_pixel: u32) -> (Vec3, Vec3) {
        let scale = sample_footprint_scale(samples_per_pixel);
        let (dx, dy) = self.rectangle_per_pixel();
        let n = unit_or(n, self.forward);
        let on_plane = |origin: Vec3, dir: Vec3| -> Vec3 {
            let denominator = n.dot(dir);
            let denominator = if denominator.abs() < 1e-6 {
                1e-6f32.copysign(denominator)
            } else {
                denominator
            };
            let t = n.dot(p - origin) / denominator;
            crate::footprint::robust::finite3(origin + dir * t - p)
        };
        match self.model {
            CameraModel::Orthographic => {
                let origin = p - self.forward * self.forward.dot(p - self.eye);
                (
                    on_plane(origin + dx * scale, self.forward),
                    on_plane(origin + dy * scale, self.forward),
                )
            }
            _ => {
                let dir = unit_or(p - self.eye, self.forward);
                let w = self.w.length().max(f32::MIN_POSITIVE);
                // The direction step per pixel at the image centre, |dx| / |W|.
                let (ddx, ddy) = (dx * (scale / w), dy * (scale / w));
                (on_plane(self.eye, dir + ddx), on_plane(self.eye, dir + ddy))
            }
        }
    }
}

/// How much narrower than a whole pixel's a camera ray's footprint is when
/// `samples_per_pixel` rays share the pixel: 1/sqrt(N), the side of the pixel's share of
/// area, but at least 1/8 so that large counts still filter. pbrt-v4 (Pharr, Jakob &
/// Humphreys, "Physically Based Rendering", 4th ed.) scales its camera rays' differentials by
/// the same max(1/8, 1/sqrt(N)) before tracing them (`RayDifferential::ScaleDifferentials`).
#[inline]
pub fn sample_footprint_scale(samples_per_pixel: u32) -> f32 {
    (1.0 / (samples_per_pixel.max(1) as f32).sqrt()).max(0.125)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::{unit_f32, xorshift32};

    fn desc(projection: Projection) -> CameraDesc {
        CameraDesc {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            projection,
        }
    }

    #[test]
    fn pinhole_directions_are_generate_ray_bit_for_bit() {
        // Lanes inside, on and outside the image, and non-finite positions (the image
        // centre), for wide and narrow fields of view and image shapes.
        let specials = [
            0.0,
            0.5,
            -3.25,
            1.0e7,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut state = 12345u32;
        let mut next = move || unit_f32(xorshift32(&mut state));
        for (vfov, width, height) in [(40.0, 1280, 720), (170.0, 7, 3), (0.01, 64, 64)] {
            let cam = Camera::new(
                &desc(Projection::Pinhole { vfov_degrees: vfov }),
                width,
                height,
            );
            for round in 0..50 {
                let px: [f32; 16] = std::array::from_fn(|lane| match (round, lane) {
                    (0, l) if l < specials.len() => specials[l],
                    _ => next() * (width as f32 + 2.0) - 1.0,
                });
                let py: [f32; 16] = std::array::from_fn(|lane| match (round, lane) {
                    (1, l) if l < specials.len() => specials[l],
                    _ => next() * (height as f32 + 2.0) - 1.0,
                });
                let d = cam.pinhole_directions(&px, &py).expect("a pinhole");
                for lane in 0..16 {
                    let (origin, direction) = cam.generate_ray(px[lane], py[lane], Vec2::ZERO);
                    assert_eq!(origin, cam.eye());
                    let packed = [d[0][lane], d[1][lane], d[2][lane]];
                    assert_eq!(
                        packed.map(f32::to_bits),
                        direction.to_array().map(f32::to_bits)
                    );
                }
            }
        }
        let lens = Projection::ThinLens {
            vfov_degrees: 40.0,
            aperture_radius: 0.1,
            focus_distance: 5.0,
        };
        for projection in [lens, Projection::Orthographic { height: 2.0 }] {
            let cam = Camera::new(&desc(projection), 64, 64);
            assert!(cam.pinhole_directions(&[0.5; 16], &[0.5; 16]).is_none());
        }
    }

    #[test]
    fn approximate_differentials_are_the_pixel_footprint_at_the_point() {
        // 90 degree vertical field of view over 100 rows: a pixel spans 2 tan(45)/100 =
        // 0.02 per unit of distance. At 3 units straight ahead, facing the camera: 0.06 in x
        // and y (one sample per pixel), and a quarter of that with 16 samples.
        let cam = Camera::new(&desc(Projection::Pinhole { vfov_degrees: 90.0 }), 200, 100);
        let p = Vec3::new(0.0, 1.0, 2.0);
        let (dx, dy) = cam.approximate_dp_dxy(p, Vec3::Z, 1);
        assert!((dx - Vec3::new(0.06, 0.0, 0.0)).length() < 1e-4, "{dx}");
        assert!((dy - Vec3::new(0.0, -0.06, 0.0)).length() < 1e-4, "{dy}");
        let (dx16, _) = cam.approximate_dp_dxy(p, Vec3::Z, 16);
        assert!((dx16.length() - 0.015).abs() < 1e-4, "{dx16}");
        // A surface tilted 60 degrees away stretches the x step by 1 / cos(60) = 2.
        let tilted = Vec3::new(3f32.sqrt() / 2.0, 0.0, 0.5);
        let (dx, _) = cam.approximate_dp_dxy(p, tilted, 1);
        // (Finite steps, as pbrt-v4 takes them: 0.124 instead of the first-order 0.12.)
        assert!((dx.length() - 0.12).abs() < 6e-3, "{dx}");
        assert!(dx.dot(tilted).abs() < 1e-4, "off the tangent plane: {dx}");
        // Orthographic: the pixel step itself, projected.
        let ortho = Camera::new(&desc(Projection::Orthographic { height: 2.0 }), 200, 100);
        let (dx, dy) = ortho.approximate_dp_dxy(p, Vec3::Z, 1);
        assert!((dx.length() - 0.02).abs() < 1e-5 && (dy.length() - 0.02).abs() < 1e-5);
    }

    #[test]
    fn pinhole_rays_cover_the_field_of_view() {
        let cam = Camera::new(&desc(Projection::Pinhole { vfov_degrees: 90.0 }), 200, 100);
        let (o, d) = cam.generate_ray(100.0, 50.0, Vec2::splat(0.5));
        assert_eq!(o, Vec3::new(0.0, 1.0, 5.0));
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        // Top edge of the image: 45 degrees up.
        let (_, top) = cam.generate_ray(100.0, 0.0, Vec2::ZERO);
        assert!((top.y - top.z.abs()).abs() < 1e-5 && top.y > 0.0);
        // Right edge: aspect 2, so tan = 2.
        let (_, right) = cam.generate_ray(200.0, 50.0, Vec2::ZERO);
        assert!((right.x / -right.z - 2.0).abs() < 1e-5);
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focal_plane() {
        let projection = Projection::ThinLens {
            vfov_degrees: 40.0,
            aperture_radius: 0.2,
            focus_distance: 3.0,
        };
        let cam = Camera::new(&desc(projection), 64, 64);
        let mut points = Vec::new();
        for lens in [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.9, 0.5),
            Vec2::new(0.4, 0.8),
        ] {
            let (o, d) = cam.generate_ray(20.5, 40.5, lens);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let t = (o.z - 2.0) / -d.z;
            points.push(o + d * t);
        }
        assert!((points[0] - points[1]).length() < 1e-4 && (points[0] - points[2]).length() < 1e-4);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_one_pixel_apart() {
        let cam = Camera::new(&desc(Projection::Orthographic { height: 4.0 }), 80, 40);
        let (o0, d0) = cam.generate_ray(10.5, 10.5, Vec2::ZERO);
        let (o1, d1) = cam.generate_ray(11.5, 10.5, Vec2::ZERO);
        assert_eq!(d0, d1);
        assert!(((o1 - o0).length() - cam.pixel_size()).abs() < 1e-6);
        assert!((cam.pixel_size() - 0.1).abs() < 1e-6);
    }

    #[test]
    fn degenerate_descriptions_give_finite_rays() {
        let bad = CameraDesc {
            eye: Vec3::ONE,
            target: Vec3::ONE,
            up: Vec3::ZERO,
            projection: Projection::ThinLens {
                vfov_degrees: f32::NAN,
                aperture_radius: -0.1,
                focus_distance: 0.0,
            },
        };
        let cam = Camera::new(&bad, 0, 0);
        let (o, d) = cam.generate_ray(f32::NAN, 0.3, Vec2::splat(0.7));
        assert!(o.is_finite() && d.is_finite());
        assert!((d.length() - 1.0).abs() < 1e-5);
        for strategy in LodStrategy::ALL {
            let f = cam.initial_footprint(strategy, 0.5, 0.5, o, d);
            assert!(f.width().is_finite());
        }
    }

    #[test]
    fn footprints_shrink_with_the_sample_count() {
        // The footprint's size 7 units along the ray (`width + spread * t`) at N samples per
        // pixel, relative to N = 1: 1/sqrt(N), never below 1/8; N = 1 is the single-sample
        // footprint exactly.
        let size = |f: Footprint| {
            let (width, spread) = f.cone_at_origin();
            width + spread * 7.0
        };
        let perspective = Projection::Pinhole { vfov_degrees: 40.0 };
        let orthographic = Projection::Orthographic { height: 4.0 };
        let thin_lens = Projection::ThinLens {
            vfov_degrees: 40.0,
            aperture_radius: 0.2,
            focus_distance: 5.0,
        };
        let cases = [
            (perspective.clone(), LodStrategy::Distance),
            (perspective.clone(), LodStrategy::Cone1),
            (perspective.clone(), LodStrategy::Cone),
            (perspective.clone(), LodStrategy::Differential),
            (orthographic.clone(), LodStrategy::Distance),
            (orthographic.clone(), LodStrategy::Cone1),
            (orthographic.clone(), LodStrategy::Cone),
            (orthographic.clone(), LodStrategy::Differential),
            (thin_lens.clone(), LodStrategy::Distance),
            (thin_lens.clone(), LodStrategy::Differential),
        ];
        for (projection, strategy) in cases {
            let cam = Camera::new(&desc(projection.clone()), 160, 90);
            let (o, d) = cam.generate_ray(37.25, 61.5, Vec2::new(0.3, 0.8));
            let one = cam.sample_footprint(strategy, 37.25, 61.5, o, d, 1);
            assert_eq!(one, cam.initial_footprint(strategy, 37.25, 61.5, o, d));
            let whole = size(one);
            assert!(whole > 0.0, "{projection:?} {strategy:?}");
            for (spp, ratio) in [(4, 0.5), (16, 0.25), (64, 0.125), (1024, 0.125)] {
                let part = size(cam.sample_footprint(strategy, 37.25, 61.5, o, d, spp));
                assert!(
                    (part / whole - ratio).abs() < 1e-4,
                    "{projection:?} {strategy:?} at {spp} spp: {part} / {whole}"
                );
            }
        }
        // The lens aperture's cone is not a pixel's: a thin lens's Cone1 keeps its size.
        let cam = Camera::new(&desc(thin_lens), 160, 90);
        let (o, d) = cam.generate_ray(37.25, 61.5, Vec2::new(0.3, 0.8));
        assert_eq!(
            cam.sample_footprint(LodStrategy::Cone1, 37.25, 61.5, o, d, 16),
            cam.initial_footprint(LodStrategy::Cone1, 37.25, 61.5, o, d)
        );
        assert_eq!(sample_footprint_scale(0), 1.0);
        assert_eq!(sample_footprint_scale(1), 1.0);
        assert_eq!(sample_footprint_scale(16), 0.25);
    }
}
