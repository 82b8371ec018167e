//! Placing one loaded part (an OBJ or glTF file) into a scene: an optional affine
//! placement and an optional material override, with every index re-based.

use glam::{Affine3A, DMat3, EulerRot, Mat3A, Quat, Vec3};

use crate::scene::{Light, SceneDescription, TextureBinding, TriangleMesh};

/// Translate / rotate (degrees about x, then y, then z) / scale, applied as `T * R * S`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placement {
    pub translate: Vec3,
    pub rotate_degrees: Vec3,
    pub scale: Vec3,
}

impl Default for Placement {
    fn default() -> Self {
        Placement {
            translate: Vec3::ZERO,
            rotate_degrees: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl Placement {
    /// The affine map `T * Rz * Ry * Rx * S` (x rotation applied first).
    pub(crate) fn matrix(&self) -> Affine3A {
        let r = self.rotate_degrees;
        let rotation = Quat::from_euler(
            EulerRot::ZYX,
            r.z.to_radians(),
            r.y.to_radians(),
            r.x.to_radians(),
        );
        Affine3A::from_scale_rotation_translation(self.scale, rotation, self.translate)
    }
}

/// Maps points, normals (by the inverse transpose) and directions through an affine map.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Transform {
    pub matrix: Affine3A,
    normal_matrix: Mat3A,
    /// The map reverses handedness (a negative determinant, e.g. a negative scale).
    mirrors: bool,
}

impl Transform {
    /// `None` when the map is singular (a zero scale, or axes so nearly dependent that the
    /// unit cube keeps under a millionth of the volume its edges' lengths span): it would
    /// flatten the geometry. The test is relative, in f64, so a uniform scale of 1e-7 or 1e13
    /// (whose determinant leaves f32's range) is as good as 1.
    pub(crate) fn new(matrix: Affine3A) -> Option<Self> {
        let linear = DMat3::from_cols(
            matrix.matrix3.x_axis.as_dvec3(),
            matrix.matrix3.y_axis.as_dvec3(),
            matrix.matrix3.z_axis.as_dvec3(),
        );
        let edges = linear.x_axis.length() * linear.y_axis.length() * linear.z_axis.length();
        let det = linear.determinant();
        if !(edges.is_finite() && edges > 0.0 && det.abs() > 1e-6 * edges) {
            return None;
        }
        // Normals are renormalised, so the inverse transpose may be scaled at will: scaled to
        // a largest entry of 1, it fits f32 whatever the map's scale.
        let inverse_transpose = linear.inverse().transpose();
        let largest = inverse_transpose
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        Some(Transform {
            matrix,
            normal_matrix: Mat3A::from((inverse_transpose / largest).as_mat3()),
            mirrors: det < 0.0,
        })
    }

    /// Moves `mesh` through the map: positions, normals, and, when the map mirrors, the
    /// winding of every triangle. A mirror turns a counter-clockwise triangle clockwise; put
    /// back, its front (one-sided emission, the geometric normal) faces where the shading
    /// normals, mapped by the inverse transpose, point: the mirrored side, as glTF 2.0 asks
    /// ("the determinant of the node's global transform defines the winding order") and as
    /// pbrt-v4 and Blender keep it.
    pub(crate) fn mesh(&self, mesh: &mut TriangleMesh) {
        for p in &mut mesh.positions {
            *p = self.point(*p);
        }
        for n in &mut mesh.normals {
            *n = self.normal(*n);
        }
        if self.mirrors {
            for triangle in &mut mesh.triangles {
                triangle.swap(1, 2);
            }
        }
    }

    #[inline]
    pub(crate) fn point(&self, p: Vec3) -> Vec3 {
        self.matrix.transform_point3(p)
    }

    /// A shading normal, renormalised (zero stays zero).
    #[inline]
    pub(crate) fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_matrix * n).normalize_or_zero()
    }

    /// A unit direction (light directions).
    #[inline]
    pub(crate) fn direction(&self, d: Vec3) -> Vec3 {
        self.matrix.transform_vector3(d).normalize_or_zero()
    }

    /// Applies the map to a light in place.
    pub(crate) fn light(&self, light: &mut Light) {
        match light {
            Light::Point { position, .. } => *position = self.point(*position),
            Light::Directional { direction, .. } => *direction = self.direction(*direction),
            Light::Spot {
                position,
                direction,
                ..
            } => {
                *position = self.point(*position);
                *direction = self.direction(*direction);
            }
        }
    }
}

/// Appends `part` to `scene`: geometry through `transform`, materials and textures re-based,
/// or every mesh bound to `material_override` (then the part's own materials are dropped).
/// The part's camera is taken (transformed) only when `scene` has none.
pub(crate) fn append(
    scene: &mut SceneDescription,
    part: SceneDescription,
    transform: Option<&Transform>,
    material_override: Option<usize>,
) {
    let texture_base = scene.textures.len();
    let material_base = scene.materials.len();
    if material_override.is_none() {
        scene.textures.extend(part.textures);
        let rebase = |b: &mut Option<TextureBinding>| {
            if let Some(binding) = b {
                binding.texture += texture_base;
            }
        };
        for mut material in part.materials {
            material.texture_slots_mut().into_iter().for_each(rebase);
            scene.materials.push(material);
        }
    }
    for mut mesh in part.meshes {
        mesh.material = material_override.unwrap_or(mesh.material + material_base);
        if let Some(t) = transform {
            t.mesh(&mut mesh);
        }
        scene.meshes.push(mesh);
    }
    for mut light in part.lights {
        if let Some(t) = transform {
            t.light(&mut light);
        }
        scene.lights.push(light);
    }
    if scene.camera.is_none() {
        if let Some(mut camera) = part.camera {
            if let Some(t) = transform {
                camera.eye = t.point(camera.eye);
                camera.target = t.point(camera.target);
                camera.up = t.direction(camera.up);
            }
            scene.camera = Some(camera);
        }
    }
    // Fog from a glTF's extras is in the file's world space: kept as it is when the part is
    // the scene itself or placed with the identity; a moved part's fog is left out (a
    // rotated box is no longer a box) and a note says so.
    if !part.fog.is_empty() {
        if transform.is_none_or(|t| t.matrix == Affine3A::IDENTITY) {
            scene.fog.extend(part.fog);
        } else {
            scene.notes.push(format!(
                "{} fog volume(s) of '{}' left out: placed parts carry no fog",
                part.fog.len(),
                part.source
            ));
        }
    }
    scene.notes.extend(part.notes);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, TriangleMesh};

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn placement_scales_then_rotates_then_translates() {
        let placement = Placement {
            translate: Vec3::new(10.0, 0.0, 0.0),
            rotate_degrees: Vec3::new(0.0, 90.0, 0.0),
            scale: Vec3::splat(2.0),
        };
        let t = Transform::new(placement.matrix()).unwrap();
        // (1,0,0) -> scale (2,0,0) -> rotate 90 deg about y -> (0,0,-2) -> translate.
        assert!(close(t.point(Vec3::X), Vec3::new(10.0, 0.0, -2.0)));
    }

    #[test]
    fn rotations_apply_x_first() {
        let placement = Placement {
            rotate_degrees: Vec3::new(90.0, 90.0, 0.0),
            ..Placement::default()
        };
        let t = Transform::new(placement.matrix()).unwrap();
        // y -> (x rot 90) z -> (y rot 90) x
        assert!(close(t.point(Vec3::Y), Vec3::X));
    }

    #[test]
    fn normals_use_the_inverse_transpose() {
        let placement = Placement {
            scale: Vec3::new(4.0, 1.0, 1.0),
            ..Placement::default()
        };
        let t = Transform::new(placement.matrix()).unwrap();
        // The plane x + y = 0 with normal (1,1,0)/sqrt2 becomes x/4 + y = 0: normal ~ (1/4, 1, 0).
        let n = t.normal(Vec3::new(1.0, 1.0, 0.0).normalize());
        assert!(close(n, Vec3::new(0.25, 1.0, 0.0).normalize()), "{n}");
    }

    #[test]
    fn singular_placements_are_rejected() {
        let placement = Placement {
            scale: Vec3::new(1.0, 0.0, 1.0),
            ..Placement::default()
        };
        assert!(Transform::new(placement.matrix()).is_none());
        // Two axes a ten-millionth of a radian apart flatten the geometry too.
        let sheared = Affine3A::from_cols(
            Vec3::X.into(),
            Vec3::new(1.0, 1e-7, 0.0).into(),
            Vec3::Z.into(),
            Vec3::ZERO.into(),
        );
        assert!(Transform::new(sheared).is_none());
    }

    /// Uniform scales far from 1 are proper maps: placed and with their normals. A scale of
    /// 1e-7 (determinant 1e-21) and one of 1e13 (determinant beyond f32) were refused as
    /// "scale must not be zero".
    #[test]
    fn tiny_and_huge_scales_are_not_singular() {
        for scale in [1e-7f32, 1e-12, 1e13, 1e18] {
            let placement = Placement {
                scale: Vec3::new(scale, 2.0 * scale, scale),
                rotate_degrees: Vec3::new(0.0, 30.0, 0.0),
                ..Placement::default()
            };
            let t = Transform::new(placement.matrix())
                .unwrap_or_else(|| panic!("scale {scale} refused"));
            assert!(((t.point(Vec3::Y).y / scale) - 2.0).abs() < 1e-5);
            // The plane x + y = 0 becomes x / s + y / (2 s) = 0 before the rotation.
            let n = t.normal(Vec3::new(1.0, 1.0, 0.0).normalize());
            let rotate = Quat::from_rotation_y(30f32.to_radians());
            let expected = rotate * Vec3::new(1.0, 0.5, 0.0).normalize();
            assert!(close(n, expected), "scale {scale}: {n} against {expected}");
        }
    }

    /// A mirroring placement keeps a triangle's front on the side its mapped normal points
    /// to: the winding is reversed. It was kept, so a mirrored lamp emitted away from where
    /// its normals pointed.
    #[test]
    fn a_mirroring_placement_reverses_the_winding() {
        let quad = || TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        };
        let front = |m: &TriangleMesh| {
            let [a, b, c] = m.triangles[0].map(|i| m.positions[i as usize]);
            (b - a).cross(c - a).normalize()
        };
        for (scale, mirrored) in [
            (Vec3::new(-1.0, 1.0, 1.0), true),
            (Vec3::new(1.0, 1.0, -2.0), true),
            (Vec3::new(-1.0, -1.0, 1.0), false),
            (Vec3::splat(3.0), false),
        ] {
            let t = Transform::new(
                Placement {
                    scale,
                    ..Placement::default()
                }
                .matrix(),
            )
            .unwrap();
            assert_eq!(t.mirrors, mirrored, "{scale}");
            let mut mesh = quad();
            t.mesh(&mut mesh);
            assert!(
                close(front(&mesh), mesh.normals[0]),
                "scale {scale}: front {} against normal {}",
                front(&mesh),
                mesh.normals[0]
            );
        }
    }

    #[test]
    fn append_rebases_materials_and_textures() {
        let mut scene = SceneDescription {
            materials: vec![Material::default()],
            ..Default::default()
        };
        let part = SceneDescription {
            materials: vec![Material::default(), Material::default()],
            meshes: vec![TriangleMesh {
                material: 1,
                ..Default::default()
            }],
            ..Default::default()
        };
        append(&mut scene, part.clone(), None, None);
        assert_eq!(scene.materials.len(), 3);
        assert_eq!(scene.meshes[0].material, 2);
        append(&mut scene, part, None, Some(0));
        assert_eq!(scene.materials.len(), 3);
        assert_eq!(scene.meshes[1].material, 0);
    }
}
