//! The camera as the 4x4 matrices compositors read from an OpenEXR header: `worldToCamera`
//! and `worldToNDC`.
//!
//! Both use Imath's row-vector convention (`p' = p * M`, translation in the last row), the one
//! OpenEXR's standard attributes are defined in. Camera space has +X right, +Y up and the
//! camera looking down -Z. Normalized device coordinates follow OpenImageIO's definition:
//! (0, 0) is the image's top-left corner and (1, 1) its bottom-right, after dividing by the
//! homogeneous w. For perspective cameras (pinhole, and a thin lens through its centre) w is
//! the depth in front of the camera and NDC z is `1 / depth`; for an orthographic camera w is
//! 1 and NDC z is the depth.

use glam::{Mat4, Vec4};

use super::{Camera, CameraModel};

/// Rows of `m` in Imath's row-vector layout (the transpose of glam's column-vector matrix).
fn imath_rows(m: Mat4) -> [[f32; 4]; 4] {
    // glam stores columns; the columns of the column-vector matrix are the rows of the
    // row-vector one.
    m.to_cols_array_2d()
}

impl Camera {
    /// Column-vector world-to-camera transform (glam convention).
    fn world_to_camera_transform(&self) -> Mat4 {
        let back = -self.forward;
        Mat4::from_cols(
            Vec4::new(self.right.x, self.up.x, back.x, 0.0),
            Vec4::new(self.right.y, self.up.y, back.y, 0.0),
            Vec4::new(self.right.z, self.up.z, back.z, 0.0),
            Vec4::new(
                -self.right.dot(self.eye),
                -self.up.dot(self.eye),
                -back.dot(self.eye),
                1.0,
            ),
        )
    }

    /// Column-vector camera-to-NDC transform (glam convention).
    fn camera_to_ndc_transform(&self) -> Mat4 {
        let plane = self.w.length();
        let (half_width, half_height) = (self.u.length(), self.v.length());
        match self.model {
            CameraModel::Orthographic => {
                // ndc = (0.5 + 0.5 x / |U|, 0.5 - 0.5 y / |V|, -z), w = 1.
                Mat4::from_cols(
                    Vec4::new(0.5 / half_width, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, -0.5 / half_height, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, -1.0, 0.0),
                    Vec4::new(0.5, 0.5, 0.0, 1.0),
                )
            }
            CameraModel::Pinhole | CameraModel::ThinLens { .. } => {
                // With depth d = -z: ndc.x d = 0.5 x plane / |U| + 0.5 d,
                // ndc.y d = -0.5 y plane / |V| + 0.5 d, ndc.z d = 1, w = d.
                Mat4::from_cols(
                    Vec4::new(0.5 * plane / half_width, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, -0.5 * plane / half_height, 0.0, 0.0),
                    Vec4::new(-0.5, -0.5, 0.0, -1.0),
                    Vec4::new(0.0, 0.0, 1.0, 0.0),
                )
            }
        }
    }

    /// OpenEXR's `worldToCamera` attribute: row-vector rows (see the module doc).
    pub fn world_to_camera_matrix(&self) -> [[f32; 4]; 4] {
        imath_rows(self.world_to_camera_transform())
    }

    /// OpenEXR's `worldToNDC` attribute: row-vector rows (see the module doc).
    pub fn world_to_ndc_matrix(&self) -> [[f32; 4]; 4] {
        imath_rows(self.camera_to_ndc_transform() * self.world_to_camera_transform())
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};

    use crate::camera::Camera;
    use crate::scene::{CameraDesc, Projection};

    /// `p * M` with `M` given as Imath rows.
    fn times(p: Vec3, m: &[[f32; 4]; 4]) -> [f32; 4] {
        let v = [p.x, p.y, p.z, 1.0];
        let mut out = [0.0f32; 4];
        for (j, o) in out.iter_mut().enumerate() {
            *o = (0..4).map(|i| v[i] * m[i][j]).sum();
        }
        out
    }

    fn cameras() -> Vec<Camera> {
        let eye = Vec3::new(1.0, 2.0, 5.0);
        let target = Vec3::new(-0.5, 0.3, -1.0);
        [
            Projection::Pinhole { vfov_degrees: 40.0 },
            Projection::Orthographic { height: 3.0 },
            Projection::ThinLens {
                vfov_degrees: 30.0,
                aperture_radius: 0.1,
                focus_distance: 4.0,
            },
        ]
        .into_iter()
        .map(|projection| {
            Camera::new(
                &CameraDesc {
                    eye,
                    target,
                    up: Vec3::Y,
                    projection,
                },
                160,
                90,
            )
        })
        .collect()
    }

    #[test]
    fn points_on_a_pixel_ray_project_to_that_pixel() {
        for camera in cameras() {
            let ndc = camera.world_to_ndc_matrix();
            let (w, h) = camera.resolution();
            for (px, py) in [(0.5, 0.5), (80.0, 45.0), (159.5, 10.25), (3.0, 89.0)] {
                // The lens centre's ray (a thin lens's focus point lies on it).
                let (origin, dir) = camera.generate_ray(px, py, Vec2::splat(0.5));
                for distance in [0.5f32, 3.0, 40.0] {
                    let q = times(origin + dir * distance, &ndc);
                    let (x, y) = (q[0] / q[3] * w as f32, q[1] / q[3] * h as f32);
                    assert!(
                        (x - px).abs() < 2e-3 && (y - py).abs() < 2e-3,
                        "{:?}: pixel ({px}, {py}) projected to ({x}, {y})",
                        camera.model()
                    );
                }
            }
        }
    }

    #[test]
    fn world_to_camera_puts_the_eye_at_the_origin_looking_down_minus_z() {
        for camera in cameras() {
            let m = camera.world_to_camera_matrix();
            let eye = times(camera.eye(), &m);
            assert!(eye[..3].iter().all(|c| c.abs() < 1e-5), "{eye:?}");
            let ahead = times(camera.eye() + camera.forward() * 2.0, &m);
            assert!(
                (ahead[2] + 2.0).abs() < 1e-5 && ahead[0].abs() < 1e-5,
                "{ahead:?}"
            );
        }
    }
}
