//! `[[fog]]` volumes, from TOML tables and from glTF's root `extras.fog` array (the same
//! keys in JSON), checked and turned into [`FogVolume`]s (documented in
//! `docs/scene-format.md`).
//!
//! Both formats deserialise into one [`RawFog`]; [`fog_volume`] validates it, so a bad
//! parameter reads the same in either format: negative or missing `sigma`, a zero plane
//! normal, a box whose `min` exceeds its `max`, keys that do not belong to the density kind.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use serde::Deserialize;

use super::files::Files;
use super::merge::{Placement, Transform};
use super::toml_format::{v3, Num, Scale, V3};
use super::SceneError;
use crate::medium::{
    ClosedMesh, ConstantDensity, Density, ExponentialDensity, FogBounds, FogBox, FogVolume,
    LinearDensity,
};

/// The colour fog blends towards when a volume gives none (a light grey).
pub const DEFAULT_FOG_COLOR: Vec3 = Vec3::splat(0.8);

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawDensityKind {
    Constant,
    Linear,
    Exponential,
}

/// `bounds`: a box (`min`, `max`) or a closed mesh (`mesh`, placed by `translate`,
/// `rotate`, `scale` as a `[[mesh]]` is).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBounds {
    min: Option<V3>,
    max: Option<V3>,
    mesh: Option<String>,
    translate: Option<V3>,
    rotate: Option<V3>,
    scale: Option<Scale>,
}

/// One fog volume as written in the file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFog {
    density: RawDensityKind,
    sigma: Num,
    color: Option<V3>,
    plane: Option<[Num; 4]>,
    height: Option<Num>,
    falloff: Option<Num>,
    bounds: Option<RawBounds>,
    albedo: Option<V3>,
    absorption: Option<V3>,
    g: Option<Num>,
}

/// Checks `raw` and builds the volume, reading a bounding mesh through `files`; the error
/// is the message without the file.
pub(super) fn fog_volume(raw: &RawFog, files: &Files) -> Result<FogVolume, String> {
    let sigma = raw.sigma.0;
    if sigma < 0.0 {
        return Err(format!("fog sigma = {sigma} must be >= 0"));
    }
    let sigma = f64::from(sigma);
    let kind = match raw.density {
        RawDensityKind::Constant => "constant",
        RawDensityKind::Linear => "linear",
        RawDensityKind::Exponential => "exponential",
    };
    let only_for = |present: bool, key: &str, wanted: RawDensityKind| -> Result<(), String> {
        if present && std::mem::discriminant(&raw.density) != std::mem::discriminant(&wanted) {
            Err(format!("fog {key} does not apply to {kind} fog"))
        } else {
            Ok(())
        }
    };
    only_for(raw.plane.is_some(), "plane", RawDensityKind::Linear)?;
    only_for(raw.height.is_some(), "height", RawDensityKind::Exponential)?;
    only_for(
        raw.falloff.is_some(),
        "falloff",
        RawDensityKind::Exponential,
    )?;
    let density = match raw.density {
        RawDensityKind::Constant => Density::Constant(ConstantDensity { sigma }),
        RawDensityKind::Linear => {
            let plane = raw
                .plane
                .ok_or("linear fog needs plane = [A, B, C, D]")?
                .map(|n| f64::from(n.0));
            Density::Linear(LinearDensity::from_plane(sigma, plane).ok_or_else(|| {
                format!(
                    "fog plane = [{}, {}, {}, {}] has a zero normal (A, B, C)",
                    plane[0], plane[1], plane[2], plane[3]
                )
            })?)
        }
        RawDensityKind::Exponential => Density::Exponential(ExponentialDensity {
            sigma,
            height: f64::from(raw.height.map_or(0.0, |h| h.0)),
            falloff: f64::from(raw.falloff.ok_or("exponential fog needs falloff")?.0),
        }),
    };
    let bounds = match &raw.bounds {
        None => None,
        Some(b) => Some(fog_bounds(b, files)?),
    };
    let color = raw.color.map_or(DEFAULT_FOG_COLOR, v3);
    if color.min_element() < 0.0 {
        return Err(format!(
            "fog color = [{}, {}, {}]: components must be >= 0",
            color.x, color.y, color.z
        ));
    }
    let unit = |c: Vec3, key: &str| -> Result<Vec3, String> {
        if c.min_element() < 0.0 || c.max_element() > 1.0 {
            Err(format!(
                "fog {key} = [{}, {}, {}]: components must lie in [0, 1]",
                c.x, c.y, c.z
            ))
        } else {
            Ok(c)
        }
    };
    let albedo = match (raw.albedo, raw.absorption) {
        (Some(_), Some(_)) => {
            return Err(
                "fog albedo and absorption are two ways of saying the same thing: give one".into(),
            )
        }
        (Some(a), None) => unit(v3(a), "albedo")?,
        (None, Some(a)) => Vec3::ONE - unit(v3(a), "absorption")?,
        (None, None) => Vec3::ONE,
    };
    let g = raw.g.map_or(0.0, |g| g.0);
    if !(g > -1.0 && g < 1.0) {
        return Err(format!("fog g = {g} must lie in (-1, 1)"));
    }
    Ok(FogVolume {
        density,
        bounds,
        color,
        albedo,
        g,
    })
}

/// A box or a closed mesh from `bounds`.
fn fog_bounds(raw: &RawBounds, files: &Files) -> Result<FogBounds, String> {
    let placed = raw.translate.is_some() || raw.rotate.is_some() || raw.scale.is_some();
    match (raw.min, raw.max, &raw.mesh) {
        (Some(min), Some(max), None) if !placed => {
            let (min, max) = (v3(min), v3(max));
            if min.cmpgt(max).any() {
                return Err(format!(
                    "fog bounds min = [{}, {}, {}] exceeds max = [{}, {}, {}]",
                    min.x, min.y, min.z, max.x, max.y, max.z
                ));
            }
            Ok(FogBounds::Box(FogBox {
                min: min.as_dvec3(),
                max: max.as_dvec3(),
            }))
        }
        (None, None, Some(file)) => {
            let placement = Placement {
                translate: raw.translate.map_or(Vec3::ZERO, v3),
                rotate_degrees: raw.rotate.map_or(Vec3::ZERO, v3),
                scale: raw.scale.as_ref().map_or(Vec3::ONE, |s| s.0),
            };
            let transform = Transform::new(placement.matrix())
                .ok_or("fog bounds mesh scale must not be zero")?;
            let path = files.resolve(file);
            let part = super::load_bounds_mesh(files, &path).map_err(|e| match e {
                SceneError::Unreadable { reason, .. } => {
                    format!("cannot read fog bounds mesh '{}': {reason}", path.display())
                }
                SceneError::UnknownFormat { extension, .. } => format!(
                    "fog bounds mesh '{}' has unknown format '{extension}' (known: obj, gltf, glb)",
                    path.display()
                ),
                other => format!("fog bounds mesh: {other}"),
            })?;
            let triangles: Vec<[DVec3; 3]> = part
                .meshes
                .iter()
                .flat_map(|mesh| {
                    mesh.triangles
                        .iter()
                        .map(|t| t.map(|i| transform.point(mesh.positions[i as usize]).as_dvec3()))
                })
                .collect();
            let mesh = ClosedMesh::new(&triangles)
                .map_err(|e| format!("fog bounds mesh '{}' {e}", path.display()))?;
            Ok(FogBounds::Mesh(Arc::new(mesh)))
        }
        _ => Err(
            "fog bounds must be a box { min = [x, y, z], max = [x, y, z] } or a closed mesh \
             { mesh = \"file\" } (optionally placed by translate, rotate, scale)"
                .into(),
        ),
    }
}

/// The fog volumes in a glTF file's root `extras` (`{"fog": [{...}, ...]}`); other extras
/// are left alone.
pub(super) fn gltf_fog(
    extras: Option<&serde_json::value::RawValue>,
    files: &Files,
) -> Result<Vec<FogVolume>, String> {
    let Some(extras) = extras else {
        return Ok(Vec::new());
    };
    let value: serde_json::Value =
        serde_json::from_str(extras.get()).map_err(|e| format!("extras: {e}"))?;
    let Some(fog) = value.get("fog") else {
        return Ok(Vec::new());
    };
    let raw: Vec<RawFog> =
        serde_json::from_value(fog.clone()).map_err(|e| format!("extras.fog: {e}"))?;
    raw.iter()
        .enumerate()
        .map(|(i, r)| fog_volume(r, files).map_err(|e| format!("extras.fog[{i}]: {e}")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::value::RawValue;

    fn extras(json: &str) -> Result<Vec<FogVolume>, String> {
        let raw = RawValue::from_string(json.to_owned()).unwrap();
        gltf_fog(Some(&raw), &Files::disk(std::path::Path::new(".")))
    }

    #[test]
    fn gltf_extras_carry_the_toml_keys() {
        let fog = extras(
            r#"{"author": "someone", "fog": [
                {"density": "exponential", "sigma": 0.1, "height": 2, "falloff": 0.5,
                 "color": [0.5, 0.6, 0.7], "bounds": {"min": [-1, 0, -1], "max": [1, 3, 1]}},
                {"density": "constant", "sigma": 0.02, "g": -0.3}
            ]}"#,
        )
        .unwrap();
        assert_eq!(fog.len(), 2);
        assert_eq!(
            fog[0].density,
            Density::Exponential(ExponentialDensity {
                // Scene numbers are f32, as everywhere in the scene description.
                sigma: f64::from(0.1f32),
                height: 2.0,
                falloff: 0.5
            })
        );
        assert_eq!(fog[0].color, Vec3::new(0.5, 0.6, 0.7));
        assert_eq!(fog[1].g, -0.3);
        assert_eq!(fog[1].color, DEFAULT_FOG_COLOR);
        // Extras without fog are someone else's business.
        assert_eq!(extras(r#"{"author": "someone"}"#).unwrap(), Vec::new());
        assert_eq!(
            gltf_fog(None, &Files::disk(std::path::Path::new("."))).unwrap(),
            Vec::new()
        );
    }

    #[test]
    fn bad_gltf_fog_names_the_entry() {
        let e = extras(r#"{"fog": [{"density": "constant", "sigma": 1}, {"density": "linear", "sigma": 1, "plane": [0, 0, 0, 1]}]}"#)
            .unwrap_err();
        assert!(
            e.starts_with("extras.fog[1]: ") && e.contains("zero normal"),
            "{e}"
        );
        let e = extras(r#"{"fog": [{"density": "constant", "sigma": -1}]}"#).unwrap_err();
        assert!(e.contains("sigma = -1 must be >= 0"), "{e}");
        let e = extras(r#"{"fog": {"density": "constant"}}"#).unwrap_err();
        assert!(e.starts_with("extras.fog: "), "{e}");
    }
}
