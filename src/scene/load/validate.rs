//! Checks a finished [`SceneDescription`] for values the renderer cannot use: non-finite
//! numbers anywhere, zero image size, non-positive sphere radius or index of refraction,
//! physically meaningless values (negative light intensities, negative colour components,
//! base colours and weights outside [0, 1]), out-of-range material/texture/vertex indices, degenerate cameras.
//! The loaders refuse these values first where they can say where they were written (TOML
//! line and column, MTL line, glTF material or light); this is the last line of defence.
//!
//! Every loader runs this last, so the renderer may assume a valid description.

use glam::{Vec2, Vec3};

use super::error::SceneError;
use crate::scene::{
    Environment, Light, Material, MaterialModel, Projection, SceneDescription, TextureBinding,
};

/// The first problem found, as a one-line error naming `scene.source`.
pub fn validate(scene: &SceneDescription) -> Result<(), SceneError> {
    check(scene).map_err(|message| SceneError::invalid(&scene.source, message))
}

fn finite3(v: Vec3, what: &str) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{what} is not finite ({v})"))
    }
}

fn finite(x: f32, what: &str) -> Result<(), String> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(format!("{what} is not finite ({x})"))
    }
}

/// Light colours, emission and the environment: any brightness, but never negative.
fn non_negative3(v: Vec3, what: &str) -> Result<(), String> {
    finite3(v, what)?;
    if v.min_element() >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what} {v} has a negative component"))
    }
}

/// Intensities: never negative.
fn non_negative(x: f32, what: &str) -> Result<(), String> {
    finite(x, what)?;
    if x >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what} {x} is negative"))
    }
}

fn check(scene: &SceneDescription) -> Result<(), String> {
    let s = &scene.settings;
    if s.width == 0 || s.height == 0 {
        return Err(format!("image size {}x{} has zero area", s.width, s.height));
    }
    finite(s.min_throughput, "render.min_throughput")?;
    finite(s.exposure, "render.exposure")?;
    if let Some(camera) = &scene.camera {
        finite3(camera.eye, "camera eye")?;
        finite3(camera.target, "camera target")?;
        finite3(camera.up, "camera up")?;
        let forward = camera.target - camera.eye;
        if forward.length_squared() == 0.0 {
            return Err("camera eye and target coincide".into());
        }
        if forward.cross(camera.up).length_squared()
            <= 1e-12 * forward.length_squared() * camera.up.length_squared()
        {
            return Err("camera up is zero or parallel to the viewing direction".into());
        }
        // The camera computes in f32 down to 1e-7 degrees and up to 179 (`camera::Camera`).
        let fov_ok = |f: f32| f.is_finite() && (1e-7..=179.0).contains(&f);
        match camera.projection {
            Projection::Pinhole { vfov_degrees } if !fov_ok(vfov_degrees) => {
                return Err(format!(
                    "camera fov {vfov_degrees} must lie in [1e-7, 179] degrees"
                ));
            }
            Projection::ThinLens {
                vfov_degrees,
                aperture_radius,
                focus_distance,
            } => {
                if !fov_ok(vfov_degrees) {
                    return Err(format!(
                        "camera fov {vfov_degrees} must lie in [1e-7, 179] degrees"
                    ));
                }
                if !(aperture_radius.is_finite() && aperture_radius >= 0.0) {
                    return Err(format!(
                        "camera aperture_radius {aperture_radius} must be finite and >= 0"
                    ));
                }
                if !(focus_distance.is_finite() && focus_distance > 0.0) {
                    return Err(format!(
                        "camera focus_distance {focus_distance} must be finite and > 0"
                    ));
                }
            }
            Projection::Orthographic { height } if !(height.is_finite() && height > 0.0) => {
                return Err(format!(
                    "orthographic camera height {height} must be finite and > 0"
                ));
            }
            _ => {}
        }
    }
    for (i, light) in scene.lights.iter().enumerate() {
        let what = format!("light {i}");
        match *light {
            Light::Point {
                position,
                color,
                intensity,
            } => {
                finite3(position, &what)?;
                non_negative3(color, &format!("{what} color"))?;
                non_negative(intensity, &format!("{what} intensity"))?;
            }
            Light::Directional {
                direction,
                color,
                intensity,
            } => {
                finite3(direction, &what)?;
                non_negative3(color, &format!("{what} color"))?;
                non_negative(intensity, &format!("{what} intensity"))?;
                if direction.length_squared() == 0.0 {
                    return Err(format!("{what}: direction is zero"));
                }
            }
            Light::Spot {
                position,
                direction,
                color,
                intensity,
                inner_angle,
                outer_angle,
            } => {
                finite3(position, &what)?;
                finite3(direction, &what)?;
                non_negative3(color, &format!("{what} color"))?;
                non_negative(intensity, &format!("{what} intensity"))?;
                if direction.length_squared() == 0.0 {
                    return Err(format!("{what}: direction is zero"));
                }
                if !(inner_angle.is_finite()
                    && outer_angle.is_finite()
                    && 0.0 <= inner_angle
                    && inner_angle <= outer_angle)
                {
                    return Err(format!(
                        "{what}: spot angles must satisfy 0 <= inner <= outer"
                    ));
                }
            }
        }
    }
    match scene.environment {
        Environment::Color(c) => non_negative3(c, "environment color")?,
        Environment::LatLong { texture, intensity } => {
            non_negative(intensity, "environment intensity")?;
            if texture >= scene.textures.len() {
                return Err(format!("environment texture index {texture} out of range"));
            }
        }
    }
    for material in &scene.materials {
        check_material(material, scene.textures.len())?;
    }
    for mesh in &scene.meshes {
        let what = format!("mesh '{}'", mesh.name);
        if mesh.material >= scene.materials.len() {
            return Err(format!(
                "{what}: material index {} out of range",
                mesh.material
            ));
        }
        if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!(
                "{what}: vertex {i} position is not finite ({})",
                mesh.positions[i]
            ));
        }
        if !mesh.normals.is_empty() {
            if mesh.normals.len() != mesh.positions.len() {
                return Err(format!(
                    "{what}: {} normals for {} vertices",
                    mesh.normals.len(),
                    mesh.positions.len()
                ));
            }
            if let Some(i) = mesh
                .normals
                .iter()
                .position(|n| !n.is_finite() || n.length_squared() == 0.0)
            {
                return Err(format!(
                    "{what}: vertex {i} normal is zero or not finite ({})",
                    mesh.normals[i]
                ));
            }
        }
        if !mesh.st.is_empty() {
            if mesh.st.len() != mesh.positions.len() {
                return Err(format!(
                    "{what}: {} texture coordinates for {} vertices",
                    mesh.st.len(),
                    mesh.positions.len()
                ));
            }
            if let Some(i) = mesh.st.iter().position(|st: &Vec2| !st.is_finite()) {
                return Err(format!(
                    "{what}: vertex {i} texture coordinate is not finite"
                ));
            }
        }
        let n = mesh.positions.len();
        if let Some(t) = mesh
            .triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n))
        {
            return Err(format!("{what}: triangle {t:?} indexes past {n} vertices"));
        }
    }
    for (i, sphere) in scene.spheres.iter().enumerate() {
        finite3(sphere.center, &format!("sphere {i} center"))?;
        if !(sphere.radius.is_finite() && sphere.radius > 0.0) {
            return Err(format!(
                "sphere {i}: radius {} must be positive",
                sphere.radius
            ));
        }
        if sphere.material >= scene.materials.len() {
            return Err(format!(
                "sphere {i}: material index {} out of range",
                sphere.material
            ));
        }
    }
    for (i, patch) in scene.patches.iter().enumerate() {
        if let Some(problem) = patch.problem() {
            return Err(format!("patch {i}: {problem}"));
        }
        if patch.material >= scene.materials.len() {
            return Err(format!(
                "patch {i}: material index {} out of range",
                patch.material
            ));
        }
        if let Some(st) = patch.corner_st {
            if st.iter().any(|c| !c.is_finite()) {
                return Err(format!(
                    "patch {i}: corner texture coordinates are not finite"
                ));
            }
        }
    }
    Ok(())
}

fn check_material(m: &Material, texture_count: usize) -> Result<(), String> {
    let what = format!("material '{}'", m.name);
    non_negative3(m.base_color, &format!("{what} base_color"))?;
    // A reflectance above 1 gives back more light than arrives (every loader refuses it
    // where it was written; this catches a description built otherwise).
    if m.base_color.max_element() > 1.0 {
        return Err(format!(
            "{what}: base_color {} has a component above 1",
            m.base_color
        ));
    }
    non_negative3(m.attenuation_color, &format!("{what} attenuation_color"))?;
    non_negative3(m.emission, &format!("{what} emission"))?;
    let classic = m.model.classic().copied().unwrap_or_default();
    for (name, value) in [
        ("specular", classic.specular),
        ("shininess", classic.shininess),
        ("mirror", m.mirror),
        ("transmission", m.transmission),
        ("ior", m.ior),
        ("alpha", m.alpha),
    ] {
        finite(value, &format!("{what} {name}"))?;
    }
    for (name, value) in [
        ("specular", classic.specular),
        ("mirror", m.mirror),
        ("transmission", m.transmission),
        ("alpha", m.alpha),
    ] {
        if !(0.0..=1.0).contains(&value) {
            return Err(format!("{what}: {name} {value} must lie in [0, 1]"));
        }
    }
    finite(m.normal_scale, &format!("{what} normal_scale"))?;
    if classic.shininess < 0.0 {
        return Err(format!(
            "{what}: shininess {} must be >= 0",
            classic.shininess
        ));
    }
    if m.ior <= 0.0 {
        return Err(format!("{what}: ior {} must be > 0", m.ior));
    }
    if m.attenuation_distance.is_nan() || m.attenuation_distance <= 0.0 {
        return Err(format!(
            "{what}: attenuation_distance {} must be > 0",
            m.attenuation_distance
        ));
    }
    if let Some(cutoff) = m.alpha_cutoff {
        finite(cutoff, &format!("{what} alpha_cutoff"))?;
    }
    let none = None;
    let model_maps = match &m.model {
        MaterialModel::MetallicRoughness(model) => [
            &model.metallic_roughness_texture,
            &model.roughness_texture,
            &model.metallic_texture,
        ],
        MaterialModel::Classic(_) => [&none; 3],
    };
    for (slot, binding) in [
        ("base_color_texture", &m.base_color_texture),
        ("alpha_texture", &m.alpha_texture),
        ("metallic_roughness_texture", model_maps[0]),
        ("roughness_texture", model_maps[1]),
        ("metallic_texture", model_maps[2]),
        ("emission_texture", &m.emission_texture),
        ("normal_texture", &m.normal_texture),
    ] {
        if let Some(TextureBinding { texture, transform }) = binding {
            if *texture >= texture_count {
                return Err(format!("{what}: {slot} index {texture} out of range"));
            }
            if !transform.is_finite() {
                return Err(format!("{what}: {slot} transform is not finite"));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Sphere, TriangleMesh};

    fn base() -> SceneDescription {
        SceneDescription {
            source: "t.toml".into(),
            materials: vec![Material::default()],
            spheres: vec![Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                material: 0,
            }],
            ..Default::default()
        }
    }

    #[test]
    fn a_plain_scene_passes() {
        assert!(validate(&base()).is_ok());
    }

    #[test]
    fn bad_values_fail_with_the_file_named() {
        let mut s = base();
        s.spheres[0].radius = -1.0;
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .starts_with("t.toml: sphere 0: radius -1"));
        let mut s = base();
        s.settings.height = 0;
        assert!(validate(&s).unwrap_err().to_string().contains("zero area"));
        let mut s = base();
        s.materials[0].transmission = 1.5;
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .contains("transmission 1.5"));
        let mut s = base();
        s.materials[0].base_color = Vec3::new(2.0, 0.0, 0.0);
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .contains("base_color [2, 0, 0] has a component above 1"));
        let mut s = base();
        s.materials[0].ior = 0.0;
        assert!(validate(&s).unwrap_err().to_string().contains("ior"));
        let mut s = base();
        s.materials[0].emission = Vec3::new(1.0, -0.5, 1.0);
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .contains("emission [1, -0.5, 1] has a negative component"));
        let mut s = base();
        s.lights.push(Light::Point {
            position: Vec3::Y,
            color: Vec3::ONE,
            intensity: -3.0,
        });
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .contains("light 0 intensity -3 is negative"));
        let mut s = base();
        s.meshes.push(TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        });
        assert!(validate(&s).unwrap_err().to_string().contains("not finite"));
        let mut s = base();
        s.meshes.push(TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 3]],
            ..Default::default()
        });
        assert!(validate(&s)
            .unwrap_err()
            .to_string()
            .contains("indexes past"));
    }
}
