//! The TOML scene format (documented key by key in `docs/scene-format.md`).
//!
//! Parsing happens in two steps: serde reads the text into `Raw*` structs that mirror the
//! file (unknown keys, wrong types, `nan`/`inf` and negative sizes are rejected there, with
//! line and column), then [`build`] resolves names (materials, textures), loads referenced
//! mesh files and produces a [`SceneDescription`]. Values that reference something keep
//! their [`Spanned`] position so resolution errors point at the right place too.

use glam::{Affine2, Vec3};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::HashMap;
use std::fmt;
use toml::Spanned;

use super::error::{line_column, SceneError};
use super::files::{leave_out_textures, note_not_loaded, Files};
use super::merge::{append, Placement, Transform};
use crate::scene::{
    CameraDesc, ClassicModel, ColorSpace, Environment, FresnelMode, Light, Material, MaterialModel,
    MetallicRoughnessModel, Projection, RenderSettings, SceneDescription, Sphere, TextureBinding,
    TextureDesc, TextureSource, ToneMap, WrapMode,
};

/// A finite number: TOML's `nan` and `inf` literals (and overflow past f32) are rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Num(pub(super) f32);

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        let f = v as f32;
        if !v.is_finite() {
            return Err(de::Error::custom(format!(
                "number {v} is not finite (nan and inf are not allowed)"
            )));
        }
        if !f.is_finite() {
            return Err(de::Error::custom(format!(
                "number {v:e} is too large for f32"
            )));
        }
        Ok(Num(f))
    }
}

pub(super) type V3 = [Num; 3];

pub(super) fn v3(v: V3) -> Vec3 {
    Vec3::new(v[0].0, v[1].0, v[2].0)
}

/// `scale = 2` or `scale = [1, 2, 1]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scale(pub(super) Vec3);

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct ScaleVisitor;
        impl<'de> Visitor<'de> for ScaleVisitor {
            type Value = Scale;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of 3 numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
                let f = v as f32;
                if f.is_finite() {
                    Ok(Scale(Vec3::splat(f)))
                } else {
                    Err(E::custom(format!("scale {v} is not finite")))
                }
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
                let mut out = [0.0f32; 3];
                for (i, slot) in out.iter_mut().enumerate() {
                    let Num(v) = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                    *slot = v;
                }
                if seq.next_element::<Num>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Scale(Vec3::from(out)))
            }
        }
        d.deserialize_any(ScaleVisitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    render: Option<RawRender>,
    camera: Option<Spanned<RawCamera>>,
    #[serde(default)]
    light: Vec<Spanned<RawLight>>,
    environment: Option<Spanned<RawEnvironment>>,
    #[serde(default)]
    texture: Vec<RawTexture>,
    #[serde(default)]
    material: Vec<RawMaterial>,
    #[serde(default)]
    sphere: Vec<RawSphere>,
    #[serde(default)]
    mesh: Vec<RawMesh>,
    #[serde(default)]
    patch: Vec<super::patches::RawPatch>,
    #[serde(default)]
    bezier_triangle: Vec<super::patches::RawBezierTriangle>,
    #[serde(default)]
    patch_file: Vec<super::patches::RawPatchFile>,
    #[serde(default)]
    fog: Vec<Spanned<super::fog::RawFog>>,
    #[serde(default)]
    height_patch: Vec<super::patches::RawHeightPatch>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRender {
    width: Option<Spanned<u32>>,
    height: Option<Spanned<u32>>,
    spp: Option<Spanned<u32>>,
    max_depth: Option<u32>,
    min_throughput: Option<Spanned<Num>>,
    tonemap: Option<RawToneMap>,
    exposure: Option<Num>,
    fresnel: Option<RawFresnel>,
    seed: Option<u32>,
    integrator: Option<Spanned<String>>,
    gi: Option<bool>,
    diffuse_bounces: Option<u32>,
    vct_resolution: Option<Spanned<u32>>,
    vct_bounces: Option<Spanned<u32>>,
    fog_model: Option<RawFogModel>,
    fog_march_steps: Option<Spanned<u32>>,
    clamp: Option<Spanned<f64>>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum RawFogModel {
    Exact,
    LinearBlend,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum RawToneMap {
    Clamp,
    Reinhard,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum RawFresnel {
    Exact,
    Schlick,
}

#[derive(Deserialize, Clone, Copy, Default, PartialEq)]
#[serde(rename_all = "snake_case")]
enum CameraType {
    #[default]
    Pinhole,
    ThinLens,
    Orthographic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    #[serde(rename = "type", default)]
    kind: CameraType,
    eye: V3,
    target: V3,
    up: Option<V3>,
    fov: Option<Num>,
    aperture_radius: Option<Num>,
    focus_distance: Option<Num>,
    height: Option<Num>,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "snake_case")]
enum LightType {
    Point,
    Directional,
    Spot,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<V3>,
    direction: Option<V3>,
    color: Option<Spanned<V3>>,
    intensity: Option<Spanned<Num>>,
    inner_angle: Option<Num>,
    outer_angle: Option<Num>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnvironment {
    color: Option<Spanned<V3>>,
    texture: Option<Spanned<String>>,
    intensity: Option<Spanned<Num>>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum RawColorSpace {
    Srgb,
    Linear,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum RawWrap {
    Periodic,
    Clamp,
    Black,
    Mirror,
}

impl RawWrap {
    fn mode(self) -> WrapMode {
        match self {
            RawWrap::Periodic => WrapMode::Periodic,
            RawWrap::Clamp => WrapMode::Clamp,
            RawWrap::Black => WrapMode::Black,
            RawWrap::Mirror => WrapMode::Mirror,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTexture {
    name: Spanned<String>,
    file: Spanned<String>,
    color_space: Option<RawColorSpace>,
    wrap: Option<RawWrap>,
    wrap_s: Option<RawWrap>,
    wrap_t: Option<RawWrap>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: Spanned<String>,
    base_color: Option<Spanned<V3>>,
    base_color_texture: Option<Spanned<String>>,
    texture_scale: Option<[Num; 2]>,
    texture_offset: Option<[Num; 2]>,
    texture_rotation: Option<Num>,
    specular: Option<Spanned<Num>>,
    shininess: Option<Spanned<Num>>,
    mirror: Option<Spanned<Num>>,
    transmission: Option<Spanned<Num>>,
    ior: Option<Spanned<Num>>,
    attenuation_color: Option<Spanned<V3>>,
    attenuation_distance: Option<Spanned<Num>>,
    emission: Option<Spanned<V3>>,
    alpha: Option<Spanned<Num>>,
    alpha_texture: Option<Spanned<String>>,
    alpha_cutoff: Option<Spanned<Num>>,
    // Plain f64 (not Num), so a nan is reported with the material's name.
    roughness: Option<Spanned<f64>>,
    metallic: Option<Spanned<f64>>,
    metallic_roughness_texture: Option<Spanned<String>>,
    emission_texture: Option<Spanned<String>>,
    two_sided: Option<bool>,
    normal_texture: Option<Spanned<String>>,
    normal_scale: Option<Spanned<Num>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSphere {
    center: V3,
    radius: Spanned<Num>,
    material: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Spanned<String>,
    material: Option<Spanned<String>>,
    translate: Option<V3>,
    rotate: Option<V3>,
    scale: Option<Spanned<Scale>>,
}

/// Errors located in the TOML text.
pub(super) struct Located<'a> {
    text: &'a str,
    label: &'a str,
}

impl Located<'_> {
    pub(super) fn at<T>(&self, spanned: &Spanned<T>, message: impl fmt::Display) -> SceneError {
        SceneError::at_offset(self.label, self.text, spanned.span().start, message)
    }

    /// `file:line:column` of a value, for notes.
    fn place<T>(&self, spanned: &Spanned<T>) -> String {
        let (line, column) = line_column(self.text, spanned.span().start);
        format!("{}:{line}:{column}", self.label)
    }
}

/// Parses a TOML scene and loads what it references (relative to `files`); the result has
/// no defaults added and is not yet validated.
pub(crate) fn parse(
    text: &str,
    files: &Files,
    label: &str,
) -> Result<SceneDescription, SceneError> {
    let raw: RawScene = toml::from_str(text).map_err(|e| match e.span() {
        Some(span) => SceneError::at_offset(label, text, span.start, e.message()),
        None => SceneError::invalid(label, e.message()),
    })?;
    build(raw, files, &Located { text, label })
}

/// Sets `slot` from an optional weight that must lie in [0, 1].
fn unit_weight(
    loc: &Located,
    slot: &mut f32,
    value: &Option<Spanned<Num>>,
    key: &str,
) -> Result<(), SceneError> {
    if let Some(v) = value {
        let x = v.get_ref().0;
        if !(0.0..=1.0).contains(&x) {
            return Err(loc.at(v, format!("{key} = {x} must lie in [0, 1]")));
        }
        *slot = x;
    }
    Ok(())
}

/// What a colour's components may be.
#[derive(Clone, Copy)]
enum ColorRange {
    /// Reflectances and transmittances: a surface or medium cannot give back more light than
    /// it receives, nor less than none.
    Unit,
    /// Radiances and light colours: any brightness, but never negative.
    NonNegative,
}

/// A colour checked against `range`, the error pointing at the value.
fn color(
    loc: &Located,
    value: &Spanned<V3>,
    key: &str,
    range: ColorRange,
) -> Result<Vec3, SceneError> {
    let c = v3(*value.get_ref());
    if let Some(tiny) = c.to_array().into_iter().find(|v| v.is_subnormal()) {
        return Err(loc.at(value, below_normal(key, tiny)));
    }
    match range {
        ColorRange::Unit if c.min_element() < 0.0 || c.max_element() > 1.0 => Err(loc.at(
            value,
            format!(
                "{key} = [{}, {}, {}]: components must lie in [0, 1]",
                c.x, c.y, c.z
            ),
        )),
        ColorRange::NonNegative if c.min_element() < 0.0 => Err(loc.at(
            value,
            format!(
                "{key} = [{}, {}, {}]: components must be >= 0",
                c.x, c.y, c.z
            ),
        )),
        _ => Ok(c),
    }
}

/// The message for a non-zero value below the smallest normal f32: rendering threads flush
/// such values to zero (as Embree asks), so it would render as 0 without a word.
fn below_normal(key: &str, value: f32) -> String {
    format!(
        "{key}: {value:e} is below the smallest normal float ({:e}), which renders as 0",
        f32::MIN_POSITIVE
    )
}

/// A number that must be >= 0 (an intensity), the error pointing at the value.
fn non_negative(loc: &Located, value: &Spanned<Num>, key: &str) -> Result<f32, SceneError> {
    let x = value.get_ref().0;
    if x.is_subnormal() {
        Err(loc.at(value, below_normal(key, x)))
    } else if x >= 0.0 {
        Ok(x)
    } else {
        Err(loc.at(value, format!("{key} = {x} must be >= 0")))
    }
}

fn unknown_name(
    loc: &Located,
    name: &Spanned<String>,
    kind: &str,
    known: &HashMap<String, usize>,
) -> SceneError {
    let mut names: Vec<&str> = known.keys().map(String::as_str).collect();
    names.sort_unstable();
    let list = if names.is_empty() {
        "none defined".to_owned()
    } else {
        names.join(", ")
    };
    loc.at(
        name,
        format!("unknown {kind} '{}' (known: {list})", name.get_ref()),
    )
}

/// What `[[texture]]` tables declared, beside the textures added to the scene.
struct DeclaredTextures {
    /// Index in `scene.textures` by name.
    names: HashMap<String, usize>,
    /// Whether each texture's t wrap was written (`wrap_t` or `wrap`) rather than defaulted.
    wrap_t_written: Vec<bool>,
    /// Textures whose file cannot be read: kept until the scene is built, so references to
    /// them are checked as any other, then left out (`files::leave_out_textures`).
    missing: Vec<usize>,
}

/// Adds the `[[texture]]` tables to `scene.textures` (a file that cannot be read gets a note).
fn declare_textures(
    tables: &[RawTexture],
    files: &Files,
    loc: &Located,
    scene: &mut SceneDescription,
) -> Result<DeclaredTextures, SceneError> {
    let mut declared = DeclaredTextures {
        names: HashMap::new(),
        wrap_t_written: Vec::new(),
        missing: Vec::new(),
    };
    for t in tables {
        let name = t.name.get_ref().clone();
        if declared.names.contains_key(&name) {
            return Err(loc.at(&t.name, format!("texture '{name}' is defined twice")));
        }
        let path = files.resolve(t.file.get_ref());
        let source = files.texture_source(&path).unwrap_or_else(|e| {
            let what = format!("texture '{name}' file '{}'", t.file.get_ref());
            let place = loc.place(&t.file);
            let consequence = "rendered without it";
            note_not_loaded(&mut scene.notes, &place, &what, &e, consequence);
            declared.missing.push(scene.textures.len());
            TextureSource::File(path.clone())
        });
        let wrap = t.wrap.map_or(WrapMode::Periodic, RawWrap::mode);
        scene.textures.push(TextureDesc {
            name: name.clone(),
            source,
            color_space: t.color_space.map(|space| match space {
                RawColorSpace::Linear => ColorSpace::Linear,
                RawColorSpace::Srgb => ColorSpace::Srgb,
            }),
            wrap_s: t.wrap_s.map_or(wrap, RawWrap::mode),
            wrap_t: t.wrap_t.map_or(wrap, RawWrap::mode),
        });
        declared
            .wrap_t_written
            .push(t.wrap_t.is_some() || t.wrap.is_some());
        declared.names.insert(name, scene.textures.len() - 1);
    }
    Ok(declared)
}

fn build(raw: RawScene, files: &Files, loc: &Located) -> Result<SceneDescription, SceneError> {
    let mut scene = SceneDescription {
        source: loc.label.to_owned(),
        ..Default::default()
    };
    if let Some(render) = &raw.render {
        scene.settings = settings(render, loc)?;
    }

    let DeclaredTextures {
        names: texture_names,
        wrap_t_written,
        missing: missing_textures,
    } = declare_textures(&raw.texture, files, loc, &mut scene)?;
    let texture = |name: &Spanned<String>| {
        texture_names
            .get(name.get_ref())
            .copied()
            .ok_or_else(|| unknown_name(loc, name, "texture", &texture_names))
    };

    // Materials, by name.
    let mut material_names: HashMap<String, usize> = HashMap::new();
    for m in &raw.material {
        let name = m.name.get_ref().clone();
        if material_names.contains_key(&name) {
            return Err(loc.at(&m.name, format!("material '{name}' is defined twice")));
        }
        let mut material = Material {
            name: name.clone(),
            ..Material::default()
        };
        if let Some(c) = &m.base_color {
            material.base_color = color(loc, c, "base_color", ColorRange::Unit)?;
        }
        let transform = texture_transform(m);
        if let Some(t) = &m.base_color_texture {
            material.base_color_texture = Some(TextureBinding {
                texture: texture(t)?,
                transform,
            });
        }
        let mut classic = ClassicModel::default();
        unit_weight(loc, &mut classic.specular, &m.specular, "specular")?;
        unit_weight(loc, &mut material.mirror, &m.mirror, "mirror")?;
        unit_weight(
            loc,
            &mut material.transmission,
            &m.transmission,
            "transmission",
        )?;
        unit_weight(loc, &mut material.alpha, &m.alpha, "alpha")?;
        // The metallic-roughness model (glTF 2.0 Appendix B): roughness selects it.
        let (mut roughness, mut metallic) = (None, None);
        if let Some(r) = &m.roughness {
            let x = *r.get_ref();
            if !(0.0..=1.0).contains(&x) {
                return Err(loc.at(
                    r,
                    format!("material '{name}': roughness = {x} must lie in [0, 1]"),
                ));
            }
            roughness = Some(x as f32);
        }
        if let Some(v) = &m.metallic {
            let x = *v.get_ref();
            if !(0.0..=1.0).contains(&x) {
                return Err(loc.at(
                    v,
                    format!("material '{name}': metallic = {x} must lie in [0, 1]"),
                ));
            }
            metallic = Some(x as f32);
        }
        if let Some(s) = &m.shininess {
            if s.get_ref().0 < 0.0 {
                return Err(loc.at(s, "shininess must be >= 0"));
            }
            classic.shininess = s.get_ref().0;
        }
        // `metallic` or a metallic-roughness texture without `roughness` selects the model
        // with glTF's default roughness factor, 1, as MTL's `Pm` and `map_Pm` do; the classic
        // model's `specular` and `shininess` then have no lobe to shape.
        material.model = if roughness.is_some()
            || metallic.is_some()
            || m.metallic_roughness_texture.is_some()
        {
            MaterialModel::MetallicRoughness(MetallicRoughnessModel::new(
                roughness.unwrap_or(1.0),
                metallic.unwrap_or(0.0),
            ))
        } else {
            MaterialModel::Classic(classic)
        };
        if let Some(ior) = &m.ior {
            if ior.get_ref().0 <= 0.0 {
                return Err(loc.at(ior, format!("ior = {} must be > 0", ior.get_ref().0)));
            }
            material.ior = ior.get_ref().0;
        }
        if let Some(c) = &m.attenuation_color {
            material.attenuation_color = color(loc, c, "attenuation_color", ColorRange::Unit)?;
        }
        if let Some(d) = &m.attenuation_distance {
            if d.get_ref().0 <= 0.0 {
                return Err(loc.at(d, "attenuation_distance must be > 0"));
            }
            material.attenuation_distance = d.get_ref().0;
        }
        if let Some(two_sided) = m.two_sided {
            material.two_sided = two_sided;
        }
        if let Some(e) = &m.emission {
            material.emission = color(loc, e, "emission", ColorRange::NonNegative)?;
        }
        if let Some(t) = &m.alpha_texture {
            let index = texture(t)?;
            if scene.textures[index].color_space != Some(ColorSpace::Linear) {
                return Err(loc.at(
                    t,
                    format!(
                        "alpha texture '{}' must be declared with color_space = \"linear\"",
                        t.get_ref()
                    ),
                ));
            }
            material.alpha_texture = Some(TextureBinding {
                texture: index,
                transform,
            });
        }
        if m.alpha_cutoff.is_some() || material.alpha_texture.is_some() {
            let mut cutoff = 0.5;
            unit_weight(loc, &mut cutoff, &m.alpha_cutoff, "alpha_cutoff")?;
            material.alpha_cutoff = Some(cutoff);
        }
        textured_inputs(loc, &scene.textures, &texture, m, transform, &mut material)?;
        scene.materials.push(material);
        material_names.insert(name, scene.materials.len() - 1);
    }
    let mut default_material = None;
    let mut material = |scene: &mut SceneDescription, name: &Option<Spanned<String>>| match name {
        Some(name) => material_names
            .get(name.get_ref())
            .copied()
            .ok_or_else(|| unknown_name(loc, name, "material", &material_names)),
        None => Ok(*default_material.get_or_insert_with(|| {
            scene.materials.push(Material {
                name: "default".into(),
                ..Material::default()
            });
            scene.materials.len() - 1
        })),
    };

    for s in &raw.sphere {
        let radius = s.radius.get_ref().0;
        if radius <= 0.0 {
            return Err(loc.at(
                &s.radius,
                format!("sphere radius {radius} must be positive"),
            ));
        }
        let index = material(&mut scene, &s.material)?;
        scene.spheres.push(Sphere {
            center: v3(s.center),
            radius,
            material: index,
        });
    }

    super::patches::build_patches(
        &mut scene,
        &raw.patch,
        &raw.bezier_triangle,
        &raw.patch_file,
        files,
        loc,
        &mut material,
    )?;
    super::patches::build_height_patches(&mut scene, &raw.height_patch, loc, &mut material)?;

    for m in &raw.mesh {
        let placement = Placement {
            translate: m.translate.map_or(Vec3::ZERO, v3),
            rotate_degrees: m.rotate.map_or(Vec3::ZERO, v3),
            scale: m.scale.as_ref().map_or(Vec3::ONE, |s| s.get_ref().0),
        };
        let transform = Transform::new(placement.matrix()).ok_or_else(|| match &m.scale {
            Some(s) => loc.at(s, "mesh scale must not be zero"),
            None => loc.at(&m.file, "mesh transform is singular"),
        })?;
        let material_override = match &m.material {
            Some(_) => Some(material(&mut scene, &m.material)?),
            None => None,
        };
        let path = files.resolve(m.file.get_ref());
        let part = super::load_part(files, &path).map_err(|e| match e {
            SceneError::Unreadable { reason, .. } => loc.at(
                &m.file,
                format!("cannot read mesh file '{}': {reason}", path.display()),
            ),
            SceneError::UnknownFormat { extension, .. } => loc.at(
                &m.file,
                format!(
                    "mesh file '{}' has unknown format '{extension}' (known: obj, gltf, glb)",
                    path.display()
                ),
            ),
            other => other,
        })?;
        append(&mut scene, part, Some(&transform), material_override);
    }

    if let Some(env) = &raw.environment {
        scene.environment = environment(env, &texture_names, loc)?;
        let map_missing = matches!(scene.environment,
            Environment::LatLong { texture, .. } if missing_textures.contains(&texture));
        if !map_missing {
            clamp_lat_long_poles(&mut scene, &wrap_t_written);
        }
    }
    if let Some(camera) = &raw.camera {
        scene.camera = Some(camera_desc(camera, loc)?);
    }
    for light in &raw.light {
        scene.lights.push(light_desc(light, loc)?);
    }
    for fog in &raw.fog {
        let volume = super::fog::fog_volume(fog.get_ref(), files).map_err(|e| loc.at(fog, e))?;
        scene.fog.push(volume);
    }
    leave_out_textures(&mut scene, &missing_textures);
    Ok(scene)
}

/// The keys of a material's textured inputs (metallic-roughness, emission, normal map), all
/// with the material's texture transform. Data textures (metallic-roughness, normal) must be
/// declared linear; the metallic-roughness texture belongs to the metallic-roughness model
/// (which it selects, with roughness 1 when the material does not set `roughness`).
fn textured_inputs(
    loc: &Located,
    textures: &[TextureDesc],
    texture: &dyn Fn(&Spanned<String>) -> Result<usize, SceneError>,
    m: &RawMaterial,
    transform: Affine2,
    material: &mut Material,
) -> Result<(), SceneError> {
    let linear = |t: &Spanned<String>, key: &str| {
        let index = texture(t)?;
        if textures[index].color_space != Some(ColorSpace::Linear) {
            return Err(loc.at(
                t,
                format!(
                    "{key} '{}' must be declared with color_space = \"linear\"",
                    t.get_ref()
                ),
            ));
        }
        Ok(TextureBinding {
            texture: index,
            transform,
        })
    };
    if let (Some(t), MaterialModel::MetallicRoughness(model)) =
        (&m.metallic_roughness_texture, &mut material.model)
    {
        model.metallic_roughness_texture = Some(linear(t, "metallic_roughness_texture")?);
    }
    if let Some(t) = &m.emission_texture {
        material.emission_texture = Some(TextureBinding {
            texture: texture(t)?,
            transform,
        });
    }
    if let Some(t) = &m.normal_texture {
        material.normal_texture = Some(linear(t, "normal_texture")?);
    }
    if let Some(scale) = &m.normal_scale {
        material.normal_scale = scale.get_ref().0;
    }
    Ok(())
}

/// `texture_scale`, `texture_offset`, `texture_rotation` as `T * R * S` applied to st:
/// glTF's `KHR_texture_transform` exactly, with the rotation in degrees instead of radians
/// (same sign: `texture_rotation = 90` is glTF's `rotation = pi/2`, taking (1, 0) to (0, -1)).
fn texture_transform(m: &RawMaterial) -> Affine2 {
    let scale = m.texture_scale.map_or([1.0, 1.0], |s| [s[0].0, s[1].0]);
    let offset = m.texture_offset.map_or([0.0, 0.0], |o| [o[0].0, o[1].0]);
    let rotation = m.texture_rotation.map_or(0.0, |r| r.0.to_radians());
    super::gltf::texture_transform(offset, rotation, scale)
}

fn settings(r: &RawRender, loc: &Located) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    if let Some(v) = &r.spp {
        if *v.get_ref() == 0 {
            return Err(loc.at(v, "render.spp must be at least 1"));
        }
        s.spp = Some(*v.get_ref());
    }
    for (slot, value, key) in [
        (&mut s.width, &r.width, "width"),
        (&mut s.height, &r.height, "height"),
    ] {
        if let Some(v) = value {
            if *v.get_ref() == 0 {
                return Err(loc.at(v, format!("render.{key} must be at least 1")));
            }
            *slot = *v.get_ref();
        }
    }
    if let Some(d) = r.max_depth {
        s.max_depth = d;
    }
    if let Some(t) = &r.min_throughput {
        if t.get_ref().0 < 0.0 {
            return Err(loc.at(t, "render.min_throughput must be >= 0"));
        }
        s.min_throughput = t.get_ref().0;
    }
    if let Some(t) = r.tonemap {
        s.tonemap = match t {
            RawToneMap::Clamp => ToneMap::Clamp,
            RawToneMap::Reinhard => ToneMap::Reinhard,
        };
    }
    if let Some(e) = r.exposure {
        s.exposure = e.0;
    }
    if let Some(f) = r.fresnel {
        s.fresnel = match f {
            RawFresnel::Exact => FresnelMode::Exact,
            RawFresnel::Schlick => FresnelMode::Schlick,
        };
    }
    if let Some(seed) = r.seed {
        s.seed = seed;
    }
    if let Some(name) = &r.integrator {
        s.integrator = name.get_ref().parse().map_err(
            |e: crate::integrator::selection::UnknownIntegrator| {
                loc.at(name, format!("render.integrator: {e}"))
            },
        )?;
    }
    if let Some(gi) = r.gi {
        s.gi = gi;
    }
    if let Some(bounces) = r.diffuse_bounces {
        s.diffuse_bounces = Some(bounces);
    }
    if let Some(n) = &r.vct_resolution {
        if !(2..=crate::vct::build::MAX_RESOLUTION).contains(n.get_ref()) {
            let max = crate::vct::build::MAX_RESOLUTION;
            return Err(loc.at(
                n,
                format!("render.vct_resolution must be between 2 and {max}"),
            ));
        }
        s.vct_resolution = Some(*n.get_ref());
    }
    if let Some(n) = &r.vct_bounces {
        if !(1..=8).contains(n.get_ref()) {
            return Err(loc.at(n, "render.vct_bounces must be between 1 and 8"));
        }
        s.vct_bounces = *n.get_ref();
    }
    if let Some(model) = r.fog_model {
        s.fog_model = match model {
            RawFogModel::Exact => crate::medium::FogModel::Exact,
            RawFogModel::LinearBlend => crate::medium::FogModel::LinearBlend,
        };
    }
    if let Some(steps) = &r.fog_march_steps {
        s.fog_integration = crate::medium::FogIntegration::march(*steps.get_ref())
            .ok_or_else(|| loc.at(steps, "render.fog_march_steps must be at least 1"))?;
    }
    if let Some(clamp) = &r.clamp {
        let value = crate::render::context::parse_sample_clamp(*clamp.get_ref())
            .map_err(|problem| loc.at(clamp, format!("render.clamp {problem}")))?;
        s.sample_clamp = Some(value);
    }
    Ok(s)
}

fn camera_desc(c: &Spanned<RawCamera>, loc: &Located) -> Result<CameraDesc, SceneError> {
    let raw = c.get_ref();
    let eye = v3(raw.eye);
    let target = v3(raw.target);
    let up = raw.up.map_or(Vec3::Y, v3);
    let fov = raw.fov.map_or(45.0, |f| f.0);
    let distance = (target - eye).length();
    if distance == 0.0 {
        return Err(loc.at(c, "camera eye and target coincide"));
    }
    if !(1e-7..=179.0).contains(&fov) {
        return Err(loc.at(
            c,
            format!("camera fov = {fov} must lie in [1e-7, 179] degrees"),
        ));
    }
    let projection = match raw.kind {
        CameraType::Pinhole => Projection::Pinhole { vfov_degrees: fov },
        CameraType::ThinLens => {
            let aperture_radius = raw
                .aperture_radius
                .ok_or_else(|| loc.at(c, "a thin_lens camera needs aperture_radius"))?
                .0;
            let focus_distance = raw.focus_distance.map_or(distance, |f| f.0);
            if aperture_radius < 0.0 || focus_distance <= 0.0 {
                return Err(loc.at(
                    c,
                    "camera aperture_radius must be >= 0 and focus_distance > 0",
                ));
            }
            Projection::ThinLens {
                vfov_degrees: fov,
                aperture_radius,
                focus_distance,
            }
        }
        CameraType::Orthographic => {
            let height = raw
                .height
                .map_or(2.0 * distance * (0.5 * fov.to_radians()).tan(), |h| h.0);
            if height <= 0.0 {
                return Err(loc.at(c, "orthographic camera height must be > 0"));
            }
            Projection::Orthographic { height }
        }
    };
    Ok(CameraDesc {
        eye,
        target,
        up,
        projection,
    })
}

fn light_desc(l: &Spanned<RawLight>, loc: &Located) -> Result<Light, SceneError> {
    let raw = l.get_ref();
    let color = match &raw.color {
        Some(c) => color(loc, c, "color", ColorRange::NonNegative)?,
        None => Vec3::ONE,
    };
    let intensity = match &raw.intensity {
        Some(i) => non_negative(loc, i, "intensity")?,
        None => 1.0,
    };
    let name = match raw.kind {
        LightType::Point => "point",
        LightType::Directional => "directional",
        LightType::Spot => "spot",
    };
    let position = || {
        raw.position
            .map(v3)
            .ok_or_else(|| loc.at(l, format!("a {name} light needs a position")))
    };
    let direction = || {
        let d = raw
            .direction
            .map(v3)
            .ok_or_else(|| loc.at(l, format!("a {name} light needs a direction")))?;
        if d.length_squared() == 0.0 {
            return Err(loc.at(l, "light direction must not be zero"));
        }
        Ok(d.normalize())
    };
    Ok(match raw.kind {
        LightType::Point => Light::Point {
            position: position()?,
            color,
            intensity,
        },
        LightType::Directional => Light::Directional {
            direction: direction()?,
            color,
            intensity,
        },
        LightType::Spot => {
            let inner = raw.inner_angle.map_or(30.0, |a| a.0);
            let outer = raw.outer_angle.map_or(45.0, |a| a.0);
            if !(0.0 <= inner && inner <= outer && outer <= 180.0) {
                return Err(loc.at(
                    l,
                    "spot angles must satisfy 0 <= inner_angle <= outer_angle <= 180",
                ));
            }
            Light::Spot {
                position: position()?,
                direction: direction()?,
                color,
                intensity,
                inner_angle: inner.to_radians(),
                outer_angle: outer.to_radians(),
            }
        }
    })
}

/// A lat-long map's t runs from one pole (t = 0) to the other (t = 1): wrapping it
/// periodically would blend the two poles' texels into each other, so an environment texture
/// whose `wrap_t` was not written is clamped in t (s stays as written, periodic by default,
/// which is right for the azimuth). A texture that materials also use keeps its own wrap
/// for them; the environment then gets its own entry.
fn clamp_lat_long_poles(scene: &mut SceneDescription, wrap_t_written: &[bool]) {
    let Environment::LatLong { texture, .. } = &mut scene.environment else {
        return;
    };
    if wrap_t_written.get(*texture).copied().unwrap_or(true) {
        return;
    }
    let used_by_materials = scene.materials.iter().any(|m| {
        m.texture_bindings()
            .any(|binding| binding.texture == *texture)
    });
    if used_by_materials {
        let mut own = scene.textures[*texture].clone();
        own.wrap_t = WrapMode::Clamp;
        scene.textures.push(own);
        *texture = scene.textures.len() - 1;
    } else {
        scene.textures[*texture].wrap_t = WrapMode::Clamp;
    }
}

fn environment(
    e: &Spanned<RawEnvironment>,
    textures: &HashMap<String, usize>,
    loc: &Located,
) -> Result<Environment, SceneError> {
    let raw = e.get_ref();
    // `intensity` scales the colour or the texture (radiance = colour or texel x intensity).
    let intensity = match &raw.intensity {
        Some(i) => non_negative(loc, i, "intensity")?,
        None => 1.0,
    };
    match (&raw.color, &raw.texture) {
        (Some(_), Some(_)) => Err(loc.at(e, "environment takes either color or texture, not both")),
        (Some(c), None) => {
            let radiance = color(loc, c, "color", ColorRange::NonNegative)? * intensity;
            if !radiance.is_finite() {
                return Err(loc.at(e, "color x intensity overflows to infinity"));
            }
            Ok(Environment::Color(radiance))
        }
        (None, Some(name)) => {
            let texture = textures
                .get(name.get_ref())
                .copied()
                .ok_or_else(|| unknown_name(loc, name, "texture", textures))?;
            Ok(Environment::LatLong { texture, intensity })
        }
        (None, None) => match &raw.intensity {
            Some(i) => Err(loc.at(
                i,
                "intensity scales the environment's color or texture, and neither is given",
            )),
            None => Ok(Environment::Color(Vec3::ZERO)),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;
    use std::path::Path;

    fn parse_here(text: &str) -> Result<SceneDescription, SceneError> {
        parse(text, &Files::disk(Path::new("/nonexistent")), "s.toml")
    }

    fn err(text: &str) -> String {
        let message = parse_here(text).unwrap_err().to_string();
        assert!(!message.contains('\n'), "{message}");
        message
    }

    #[test]
    fn full_scene_parses() {
        let text = r#"
[render]
width = 320
height = 200
spp = 4
seed = 17
tonemap = "reinhard"
fresnel = "schlick"
exposure = 1.5

[camera]
type = "thin_lens"
eye = [0, 1, 5]
target = [0, 1, 0]
fov = 30
aperture_radius = 0.1

[[light]]
type = "spot"
position = [0, 5, 0]
direction = [0, -2, 0]
inner_angle = 10
outer_angle = 20

[environment]
color = [0.1, 0.2, 0.3]

[[material]]
name = "glass"
transmission = 1.0
ior = 1.5
attenuation_color = [0.5, 0.9, 0.5]
attenuation_distance = 2

[[sphere]]
center = [0, 1, 0]
radius = 1
material = "glass"
"#;
        let s = parse_here(text).unwrap();
        assert_eq!(
            (s.settings.width, s.settings.height, s.settings.spp),
            (320, 200, Some(4))
        );
        assert_eq!(s.settings.tonemap, ToneMap::Reinhard);
        assert_eq!(s.settings.fresnel, FresnelMode::Schlick);
        assert_eq!(s.settings.seed, 17);
        let cam = s.camera.unwrap();
        assert_eq!(
            cam.projection,
            Projection::ThinLens {
                vfov_degrees: 30.0,
                aperture_radius: 0.1,
                focus_distance: 5.0
            }
        );
        let Light::Spot {
            direction,
            inner_angle,
            ..
        } = s.lights[0]
        else {
            panic!("not a spot light")
        };
        assert_eq!(direction, Vec3::NEG_Y);
        assert!((inner_angle - 10f32.to_radians()).abs() < 1e-6);
        assert_eq!(s.environment, Environment::Color(Vec3::new(0.1, 0.2, 0.3)));
        assert_eq!(s.materials[s.spheres[0].material].attenuation_distance, 2.0);
    }

    #[test]
    fn syntax_errors_report_line_and_column() {
        let e = err("[render]\nwidth = = 3\n");
        assert!(e.starts_with("s.toml:2:"), "{e}");
    }

    #[test]
    fn values_below_the_smallest_normal_float_are_refused() {
        // 1e-38 is subnormal in f32; renders flush it to zero, so it rendered black.
        let e = err("[[material]]\nname = 'm'\nemission = [1e-38, 0, 0]\n");
        assert!(
            e.starts_with("s.toml:3:") && e.contains("smallest normal"),
            "{e}"
        );
        let e = err("[environment]\ncolor = [1, 1, 1]\nintensity = 1e-39\n");
        assert!(
            e.contains("intensity") && e.contains("smallest normal"),
            "{e}"
        );
        // The smallest normal float itself is accepted.
        let scene = parse_here("[[material]]\nname = 'm'\nemission = [1.1754944e-38, 0, 0]\n")
            .expect("smallest normal accepted");
        assert_eq!(scene.materials[0].emission.x, f32::MIN_POSITIVE);
    }

    #[test]
    fn unknown_keys_are_errors() {
        let e = err("[render]\nwidht = 3\n");
        assert!(e.starts_with("s.toml:2:1:") && e.contains("widht"), "{e}");
        let e = err("[[sphere]]\ncenter = [0,0,0]\nradius = 1\nmaterial_name = 'x'\n");
        assert!(e.contains("material_name"), "{e}");
    }

    #[test]
    fn unknown_material_lists_the_known_ones() {
        let text = "[[material]]\nname = 'mirror'\n[[material]]\nname = 'glass'\n[[sphere]]\ncenter = [0,0,0]\nradius = 1\nmaterial = 'glas'\n";
        let e = err(text);
        assert_eq!(
            e,
            "s.toml:8:12: unknown material 'glas' (known: glass, mirror)"
        );
    }

    #[test]
    fn unknown_texture_is_an_error() {
        let e = err("[[material]]\nname = 'm'\nbase_color_texture = 'wood'\n");
        assert!(
            e.starts_with("s.toml:3:") && e.contains("unknown texture 'wood'"),
            "{e}"
        );
    }

    #[test]
    fn nan_and_inf_are_rejected_with_location() {
        let e = err("[[sphere]]\ncenter = [0, nan, 0]\nradius = 1\n");
        assert!(
            e.starts_with("s.toml:2:") && e.contains("not finite"),
            "{e}"
        );
        let e = err("[[light]]\ntype = 'point'\nposition = [0,0,0]\nintensity = inf\n");
        assert!(
            e.starts_with("s.toml:4:") && e.contains("not finite"),
            "{e}"
        );
        let e = err("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1e40\n");
        assert!(
            e.starts_with("s.toml:3:10:") && e.contains("too large"),
            "{e}"
        );
        let e = err("[render]\nexposure = -inf\n");
        assert!(e.contains("not finite"), "{e}");
    }

    #[test]
    fn zero_image_size_negative_radius_and_bad_ior_are_errors() {
        let e = err("[render]\nwidth = 0\n");
        assert!(e.starts_with("s.toml:2:9:") && e.contains("width"), "{e}");
        let e = err("[[sphere]]\ncenter = [0,0,0]\nradius = -2\n");
        assert!(e.starts_with("s.toml:3:10:") && e.contains("radius"), "{e}");
        let e = err("[[material]]\nname = 'g'\nior = 0\n");
        assert!(e.starts_with("s.toml:3:7:") && e.contains("ior"), "{e}");
        let e = err("[[material]]\nname = 'g'\nior = -1.5\n");
        assert!(e.contains("ior"), "{e}");
    }

    /// Geometry that cannot be read is an error at its reference; an image is left out with
    /// a note there, as MTL maps and glTF images are (`files::note_not_loaded`).
    #[test]
    fn missing_files_follow_the_referenced_file_policy() {
        let e = err("[[mesh]]\nfile = 'missing.obj'\n");
        assert!(
            e.starts_with("s.toml:2:8:") && e.contains("missing.obj"),
            "{e}"
        );
        let dir = tempfile::tempdir().unwrap();
        std::fs::copy(
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/textures/checker.png"),
            dir.path().join("here.png"),
        )
        .unwrap();
        let text = "[[texture]]\nname = 'gone'\nfile = 'missing.png'\n\
                    [[texture]]\nname = 'here'\nfile = 'here.png'\n\
                    [[texture]]\nname = 'sky'\nfile = 'no_sky.exr'\n\
                    [[material]]\nname = 'm'\nbase_color = [1, 0, 0]\n\
                    base_color_texture = 'gone'\nemission_texture = 'here'\n\
                    [environment]\ntexture = 'sky'\n";
        let s = parse(text, &Files::disk(dir.path()), "s.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.textures.len(), 1);
        assert_eq!(s.textures[0].name, "here");
        let m = &s.materials[0];
        assert!(m.base_color_texture.is_none());
        assert_eq!(m.emission_texture.as_ref().unwrap().texture, 0);
        assert_eq!(m.base_color, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(s.environment, Environment::Color(Vec3::ZERO));
        assert_eq!(
            s.notes,
            [
                "s.toml:3:8: texture 'gone' file 'missing.png' not loaded (no such file): \
                 rendered without it",
                "s.toml:9:8: texture 'sky' file 'no_sky.exr' not loaded (no such file): \
                 rendered without it"
            ]
        );
        // A reference to a left-out texture is still checked.
        let e = parse(
            "[[texture]]\nname = 'gone'\nfile = 'missing.png'\n\
             [[material]]\nname = 'm'\nalpha_texture = 'gone'\n",
            &Files::disk(dir.path()),
            "s.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("must be declared with color_space"), "{e}");
    }

    #[test]
    fn wrong_enum_values_are_errors() {
        let e = err("[camera]\ntype = 'fisheye'\neye = [0,0,1]\ntarget = [0,0,0]\n");
        assert!(e.contains("fisheye"), "{e}");
        let e = err("[render]\ntonemap = 'aces'\n");
        assert!(e.starts_with("s.toml:2:") && e.contains("aces"), "{e}");
    }

    #[test]
    fn textured_input_keys() {
        let dir = tempfile::tempdir().unwrap();
        for f in ["glow.png", "n.png"] {
            std::fs::write(dir.path().join(f), b"x").unwrap();
        }
        let textures = "[[texture]]\nname = 'glow'\nfile = 'glow.png'\n\
                        [[texture]]\nname = 'n'\nfile = 'n.png'\ncolor_space = 'linear'\n";
        let text = format!(
            "{textures}[[material]]\nname = 'm'\nemission = [2, 2, 2]\nemission_texture = 'glow'\n\
             normal_texture = 'n'\nnormal_scale = 0.25\ntexture_scale = [2, 2]\n"
        );
        let s = parse(&text, &Files::disk(dir.path()), "s.toml").unwrap_or_else(|e| panic!("{e}"));
        let m = &s.materials[0];
        assert_eq!(m.emission_texture.as_ref().unwrap().texture, 0);
        let normal = m.normal_texture.as_ref().unwrap();
        assert_eq!(normal.texture, 1);
        assert_eq!(
            normal.transform.transform_point2(Vec2::ONE),
            Vec2::splat(2.0)
        );
        assert_eq!(m.normal_scale, 0.25);
        for (material, expected) in [
            (
                "normal_texture = 'glow'",
                "s.toml:10:18: normal_texture 'glow' must be declared with color_space = \"linear\"",
            ),
            ("normal_scale = nan", "s.toml:10:"),
            ("emission_texture = 'nothere'", "unknown texture 'nothere'"),
        ] {
            let text = format!("{textures}[[material]]\nname = 'm'\n{material}\n");
            let e = parse(&text, &Files::disk(dir.path()), "s.toml").unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
        }
    }

    #[test]
    fn texture_transform_and_wrap_modes() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("c.png"), b"x").unwrap();
        let text = "[[texture]]\nname = 'c'\nfile = 'c.png'\nwrap = 'clamp'\nwrap_t = 'mirror'\n\
                    [[material]]\nname = 'm'\nbase_color_texture = 'c'\ntexture_scale = [4, 2]\ntexture_offset = [0.5, 0]\ntexture_rotation = 90\n";
        let s = parse(text, &Files::disk(dir.path()), "s.toml").unwrap();
        let t = &s.textures[0];
        assert_eq!(
            (t.wrap_s, t.wrap_t, t.color_space),
            (WrapMode::Clamp, WrapMode::Mirror, None)
        );
        assert!(
            matches!(&t.source, crate::scene::TextureSource::File(p) if *p == dir.path().join("c.png"))
        );
        let binding = s.materials[0].base_color_texture.as_ref().unwrap();
        // (1, 0) -> scale (4, 0) -> rotate 90 deg (0, -4) -> offset (0.5, -4).
        let st = binding.transform.transform_point2(Vec2::X);
        assert!((st - Vec2::new(0.5, -4.0)).length() < 1e-5, "{st}");
    }

    #[test]
    fn texture_rotation_is_gltf_rotation_in_degrees() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("c.png"), b"x").unwrap();
        for degrees in [30.0f32, -75.0, 90.0, 200.0] {
            let text = format!(
                "[[texture]]\nname = 'c'\nfile = 'c.png'\n[[material]]\nname = 'm'\n\
                 base_color_texture = 'c'\ntexture_scale = [2, 3]\n\
                 texture_offset = [0.25, -0.5]\ntexture_rotation = {degrees}\n"
            );
            let s = parse(&text, &Files::disk(dir.path()), "s.toml").unwrap();
            let toml = s.materials[0]
                .base_color_texture
                .as_ref()
                .unwrap()
                .transform;
            // The same sign as KHR_texture_transform's `rotation`, in degrees.
            let gltf = super::super::gltf::texture_transform(
                [0.25, -0.5],
                degrees.to_radians(),
                [2.0, 3.0],
            );
            assert!(
                toml.abs_diff_eq(gltf, 1e-6),
                "{degrees}: {toml:?} vs {gltf:?}"
            );
            // Written out: (1, 0) turns to (cos, -sin), towards -t (up on the image).
            let (sin, cos) = degrees.to_radians().sin_cos();
            let turned = toml.transform_vector2(Vec2::X) / 2.0;
            assert!(
                (turned - Vec2::new(cos, -sin)).length() < 1e-5,
                "{degrees}: {turned}"
            );
        }
    }

    #[test]
    fn environment_textures_default_to_clamp_in_t() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("sky.png"), b"x").unwrap();
        let scene = |texture_keys: &str, material: &str| {
            let text = format!(
                "[[texture]]\nname = 'sky'\nfile = 'sky.png'\n{texture_keys}\n{material}\n\
                 [environment]\ntexture = 'sky'\n"
            );
            parse(&text, &Files::disk(dir.path()), "s.toml").unwrap()
        };
        let environment_wrap = |s: &SceneDescription| match s.environment {
            Environment::LatLong { texture, .. } => {
                (s.textures[texture].wrap_s, s.textures[texture].wrap_t)
            }
            Environment::Color(_) => panic!("not a lat-long environment"),
        };
        // Unset: periodic around the azimuth, clamped at the poles.
        let s = scene("", "");
        assert_eq!(environment_wrap(&s), (WrapMode::Periodic, WrapMode::Clamp));
        assert_eq!(s.textures.len(), 1);
        // Set explicitly, by `wrap_t` or by `wrap`: as written.
        let s = scene("wrap_t = 'mirror'", "");
        assert_eq!(environment_wrap(&s), (WrapMode::Periodic, WrapMode::Mirror));
        let s = scene("wrap = 'periodic'", "");
        assert_eq!(
            environment_wrap(&s),
            (WrapMode::Periodic, WrapMode::Periodic)
        );
        // A material sharing the image keeps the texture's own (periodic) wrap.
        let s = scene("", "[[material]]\nname = 'm'\nbase_color_texture = 'sky'\n");
        let material_texture = s.materials[0].base_color_texture.as_ref().unwrap().texture;
        assert_eq!(s.textures[material_texture].wrap_t, WrapMode::Periodic);
        assert_eq!(environment_wrap(&s), (WrapMode::Periodic, WrapMode::Clamp));
    }

    #[test]
    fn alpha_textures_must_be_linear() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.png"), b"x").unwrap();
        let base = "[[texture]]\nname = 'a'\nfile = 'a.png'\n";
        let material = "[[material]]\nname = 'leaf'\nalpha_texture = 'a'\n";
        let srgb = format!("{base}{material}");
        let e = parse(&srgb, &Files::disk(dir.path()), "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("linear"), "{e}");
        let linear = format!("{base}color_space = 'linear'\n{material}");
        let s = parse(&linear, &Files::disk(dir.path()), "s.toml").unwrap();
        assert_eq!(s.materials[0].alpha_cutoff, Some(0.5));
    }

    #[test]
    fn meshes_are_placed_and_materials_overridden() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("t.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let text = "[[material]]\nname = 'red'\nbase_color = [1, 0, 0]\n\
                    [[mesh]]\nfile = 't.obj'\nmaterial = 'red'\ntranslate = [0, 0, 5]\nscale = 2\n\
                    [[mesh]]\nfile = 't.obj'\nrotate = [0, 0, 90]\n";
        let s = parse(text, &Files::disk(dir.path()), "s.toml").unwrap();
        assert_eq!(s.meshes.len(), 2);
        assert_eq!(s.meshes[0].material, 0);
        assert_eq!(s.meshes[0].positions[1], Vec3::new(2.0, 0.0, 5.0));
        assert!((s.meshes[1].positions[1] - Vec3::Y).length() < 1e-6);
        assert_ne!(s.meshes[1].material, 0);
        let e = parse(
            "[[mesh]]\nfile = 't.obj'\nscale = 0\n",
            &Files::disk(dir.path()),
            "s.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("s.toml:3:9:"), "{e}");
    }

    #[test]
    fn metallic_roughness_keys_are_read_and_checked() {
        let scene = |keys: &str| {
            format!(
                "[camera]\ntype = \"pinhole\"\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n\n\
                 [[material]]\nname = \"brass\"\n{keys}\n"
            )
        };
        let s = parse_here(&scene("roughness = 0.3\nmetallic = 1.0")).unwrap();
        let factors = |s: &SceneDescription| {
            s.materials[0]
                .model
                .metallic_roughness()
                .map(|mr| (mr.roughness, mr.metallic))
        };
        assert_eq!(factors(&s), Some((0.3, 1.0)));
        // `metallic` alone selects the model with glTF's default roughness, as MTL's `Pm`.
        let s = parse_here(&scene("metallic = 1.0")).unwrap();
        assert_eq!(factors(&s), Some((1.0, 1.0)));
        let classic = parse_here(&scene("base_color = [0.5, 0.5, 0.5]")).unwrap();
        assert_eq!(classic.materials[0].model, MaterialModel::default());
        for (keys, key) in [
            ("roughness = 1.5", "roughness"),
            ("roughness = -0.1", "roughness"),
            ("roughness = nan", "roughness"),
            ("metallic = 2", "metallic"),
            ("metallic = nan", "metallic"),
        ] {
            let e = err(&scene(keys));
            assert!(e.starts_with("s.toml:"), "{e}");
            assert!(e.contains("material 'brass'") && e.contains(key), "{e}");
        }
    }
}
