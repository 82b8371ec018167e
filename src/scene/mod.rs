//! Scene description: the plain data every loader produces and the renderer consumes.
//!
//! A [`SceneDescription`] is what a TOML scene, an OBJ file or a glTF file becomes after
//! loading and validation: world-space triangle meshes and spheres, materials, lights,
//! textures (by source, not yet decoded), an optional camera and render settings.
//! Nothing here touches Embree or decodes images; `crate::render` turns a description into
//! an Embree scene and decoded textures.
//!
//! Texture coordinates are stored in OpenImageIO's convention (`s` to the right, `t`
//! downwards, (0,0) at the outer corner of the first texel): loaders map OBJ's v-up and
//! glTF's v-down coordinates onto it.

pub mod load;
pub mod patch;

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec2, Vec3};

pub use crate::texture::{ColorSpace, WrapMode};

/// Everything needed to render one image, after loading and validation.
#[derive(Clone, Debug, Default)]
pub struct SceneDescription {
    /// Where the scene came from (a path, or `<built-in default scene>`); used in messages.
    pub source: String,
    pub camera: Option<CameraDesc>,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureDesc>,
    pub meshes: Vec<TriangleMesh>,
    pub spheres: Vec<Sphere>,
    /// Curved surfaces (Bezier, Hermite and Lagrange rectangles, Bezier triangles), all
    /// converted to bicubic Bezier patches ([`patch`]).
    pub patches: Vec<patch::BezierPatch>,
    /// Height fields `y = H(x, z)` traced by ray marching ([`patch::height`]).
    pub height_patches: Vec<patch::height::HeightPatch>,
    pub environment: Environment,
    /// Fog volumes (`[[fog]]`), with their exact optical depth in `crate::medium`.
    pub fog: Vec<crate::medium::FogVolume>,
    pub settings: RenderSettings,
    /// Every disk file the loaders read or referenced: the scene file, meshes, MTL
    /// libraries, glTF buffers and images, textures, patch files, environment maps and fog
    /// bounds. A render refuses outputs that name any of them.
    pub input_files: Vec<std::path::PathBuf>,
    /// Things the loader decided on the user's behalf ("camera placed to frame the bounds",
    /// "no lights: default light and environment added"); printed in the summary line.
    pub notes: Vec<String>,
}

/// A camera placed by eye/target/up with one of three projections.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub projection: Projection,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Projection {
    /// Vertical field of view in degrees.
    Pinhole { vfov_degrees: f32 },
    /// Vertical field of view in degrees; lens radius and focus distance in world units.
    ThinLens {
        vfov_degrees: f32,
        aperture_radius: f32,
        focus_distance: f32,
    },
    /// Height of the view rectangle in world units.
    Orthographic { height: f32 },
}

/// Punctual lights (seed 001: point and directional sources with shadow rays).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity `color * intensity` (W/sr, or candela for glTF), falling off as 1/r^2.
    Point {
        position: Vec3,
        color: Vec3,
        intensity: f32,
    },
    /// `direction` is the direction the light travels; irradiance `color * intensity`.
    Directional {
        direction: Vec3,
        color: Vec3,
        intensity: f32,
    },
    /// A point light restricted to a cone around `direction` (the direction light travels),
    /// full inside `inner_angle`, smoothly falling to zero at `outer_angle` (radians).
    Spot {
        position: Vec3,
        direction: Vec3,
        color: Vec3,
        intensity: f32,
        inner_angle: f32,
        outer_angle: f32,
    },
}

/// What is seen where rays escape, and what lights diffuse surfaces as an ambient term.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    Color(Vec3),
    /// An equirectangular (lat-long) map; `textures[texture]`, scaled by `intensity`.
    LatLong {
        texture: usize,
        intensity: f32,
    },
}

impl Default for Environment {
    fn default() -> Self {
        Environment::Color(Vec3::ZERO)
    }
}

/// Where a texture's encoded bytes come from.
#[derive(Clone, Debug)]
pub enum TextureSource {
    File(PathBuf),
    /// Encoded image bytes (PNG, JPEG, EXR) held in memory: glTF buffer views and data URIs,
    /// and the built-in default scene's assets. `label` names it in messages.
    Encoded {
        label: String,
        bytes: Arc<Vec<u8>>,
    },
}

impl TextureSource {
    /// A name for messages: the file path or the label.
    pub fn label(&self) -> String {
        match self {
            TextureSource::File(path) => path.display().to_string(),
            TextureSource::Encoded { label, .. } => label.clone(),
        }
    }
}

/// A texture as the scene refers to it; decoded and mip-mapped by `crate::texture`.
#[derive(Clone, Debug)]
pub struct TextureDesc {
    pub name: String,
    pub source: TextureSource,
    /// `Srgb` for colour (decoded to linear on load), `Linear` for data such as alpha;
    /// `None` when the scene does not state it: the colour space a `.tx` written by
    /// `conetrace maketx` records, else sRGB (see `crate::texture::Texture::from_file`).
    pub color_space: Option<ColorSpace>,
    pub wrap_s: WrapMode,
    pub wrap_t: WrapMode,
}

/// A texture bound to a material slot, with an affine transform of its coordinates
/// (glTF `KHR_texture_transform`, TOML `scale`/`offset`/`rotation`).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureBinding {
    /// Index into [`SceneDescription::textures`].
    pub texture: usize,
    /// `st' = transform * st` (applied to the mesh's st in OpenImageIO convention).
    pub transform: glam::Affine2,
}

/// A surface material: the scattering model of its opaque part ([`MaterialModel`]), the
/// perfect-mirror and dielectric layers every model mixes in, and what every model shares
/// (emission, alpha cut-out, normal map, two-sidedness). Weights are in [0, 1].
///
/// What a material does (its lobes, whether it emits, cuts out or reads textures) is
/// answered in one place, `crate::shading::material_features`.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// The opaque part's scattering model.
    pub model: MaterialModel,
    /// Linear RGB base colour (multiplied by the base-colour texture when present): the
    /// classic model's diffuse albedo, the metallic-roughness model's base colour.
    pub base_color: Vec3,
    pub base_color_texture: Option<TextureBinding>,
    /// Perfect-mirror reflectivity (0 = none).
    pub mirror: f32,
    /// Weight of the dielectric (Fresnel-split reflection + refraction) lobe (0 = opaque).
    /// The boundary is smooth, or rough with the metallic-roughness model's roughness
    /// (`crate::shading::material_bsdf`).
    pub transmission: f32,
    /// Index of refraction of the material's inside (the outside is 1).
    pub ior: f32,
    /// Beer's law: colour remaining after travelling `attenuation_distance` inside
    /// (`sigma = -ln(color) / distance`); `f32::INFINITY` means no absorption.
    pub attenuation_color: Vec3,
    pub attenuation_distance: f32,
    /// Emitted radiance (linear RGB).
    pub emission: Vec3,
    /// Alpha cut-out: a hit is ignored where alpha < cutoff. `None` = opaque.
    pub alpha_cutoff: Option<f32>,
    /// Constant alpha (glTF base colour factor's alpha), multiplied with the alpha texture.
    pub alpha: f32,
    /// Texture whose alpha channel gives coverage (glTF: the base-colour texture).
    pub alpha_texture: Option<TextureBinding>,
    /// Texture multiplying `emission` (sRGB colour, glTF's `emissiveTexture`).
    pub emission_texture: Option<TextureBinding>,
    /// Whether a surface emits from both sides (glTF's `doubleSided`, TOML's
    /// `two_sided`); otherwise only from its front, the side its winding faces (a sphere's
    /// outside).
    pub two_sided: bool,
    /// Tangent-space normal map (linear, +X along increasing s, +Y along decreasing t, as
    /// glTF and OpenGL-style maps store them); see `crate::shading::surface_inputs`.
    pub normal_texture: Option<TextureBinding>,
    /// Scale of the normal map's X and Y components (glTF's `normalTexture.scale`).
    pub normal_scale: f32,
}

/// The scattering model of a material's opaque part.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialModel {
    /// Lambert diffuse plus an energy-normalised Blinn-Phong highlight (seeds 001 and 004),
    /// `crate::shading::brdf`.
    Classic(ClassicModel),
    /// The glTF 2.0 metallic-roughness model (its Appendix B): GGX lobes,
    /// `crate::shading::metallic_roughness`.
    MetallicRoughness(MetallicRoughnessModel),
}

/// The classic model's highlight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassicModel {
    /// Blinn-Phong highlight weight and exponent.
    pub specular: f32,
    pub shininess: f32,
}

impl Default for ClassicModel {
    fn default() -> Self {
        ClassicModel {
            specular: 0.0,
            shininess: 32.0,
        }
    }
}

/// The metallic-roughness model's factors and maps.
#[derive(Clone, Debug, PartialEq)]
pub struct MetallicRoughnessModel {
    /// Perceptual roughness in [0, 1] (GGX alpha = roughness^2).
    pub roughness: f32,
    /// Metalness in [0, 1] (0 = dielectric over diffuse, 1 = conductor with the base colour
    /// as its reflectance at normal incidence).
    pub metallic: f32,
    /// Linear texture whose blue channel scales `metallic` and green channel scales
    /// `roughness` (glTF's `metallicRoughnessTexture`).
    pub metallic_roughness_texture: Option<TextureBinding>,
    /// Separate single-channel maps (MTL's `map_Pr` and `map_Pm`, greyscale images): the
    /// green channel of `roughness_texture` scales `roughness`, the blue channel of
    /// `metallic_texture` scales `metallic` (for a grey image every channel holds the value).
    pub roughness_texture: Option<TextureBinding>,
    pub metallic_texture: Option<TextureBinding>,
}

impl MetallicRoughnessModel {
    /// The model with these factors and no maps.
    pub fn new(roughness: f32, metallic: f32) -> Self {
        MetallicRoughnessModel {
            roughness,
            metallic,
            metallic_roughness_texture: None,
            roughness_texture: None,
            metallic_texture: None,
        }
    }
}

impl MaterialModel {
    /// The metallic-roughness model's factors and maps, if that is the model.
    pub fn metallic_roughness(&self) -> Option<&MetallicRoughnessModel> {
        match self {
            MaterialModel::MetallicRoughness(model) => Some(model),
            MaterialModel::Classic(_) => None,
        }
    }

    /// The classic model's highlight, if that is the model.
    pub fn classic(&self) -> Option<&ClassicModel> {
        match self {
            MaterialModel::Classic(model) => Some(model),
            MaterialModel::MetallicRoughness(_) => None,
        }
    }
}

impl Default for MaterialModel {
    fn default() -> Self {
        MaterialModel::Classic(ClassicModel::default())
    }
}

impl Material {
    /// Every texture the material binds.
    pub fn texture_bindings(&self) -> impl Iterator<Item = &TextureBinding> {
        let model_maps = match &self.model {
            MaterialModel::MetallicRoughness(model) => [
                &model.metallic_roughness_texture,
                &model.roughness_texture,
                &model.metallic_texture,
            ],
            MaterialModel::Classic(_) => [&None, &None, &None],
        };
        [
            &self.base_color_texture,
            &self.alpha_texture,
            &self.emission_texture,
            &self.normal_texture,
        ]
        .into_iter()
        .chain(model_maps)
        .flatten()
    }

    /// Every texture slot of the material, for code that re-indexes or drops textures.
    pub fn texture_slots_mut(&mut self) -> Vec<&mut Option<TextureBinding>> {
        let mut slots = vec![
            &mut self.base_color_texture,
            &mut self.alpha_texture,
            &mut self.emission_texture,
            &mut self.normal_texture,
        ];
        if let MaterialModel::MetallicRoughness(model) = &mut self.model {
            slots.push(&mut model.metallic_roughness_texture);
            slots.push(&mut model.roughness_texture);
            slots.push(&mut model.metallic_texture);
        }
        slots
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            model: MaterialModel::default(),
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            mirror: 0.0,
            transmission: 0.0,
            ior: 1.5,
            attenuation_color: Vec3::ONE,
            attenuation_distance: f32::INFINITY,
            emission: Vec3::ZERO,
            alpha_cutoff: None,
            alpha: 1.0,
            alpha_texture: None,
            emission_texture: None,
            two_sided: false,
            normal_texture: None,
            normal_scale: 1.0,
        }
    }
}

/// An indexed triangle mesh in world space (node transforms already applied).
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, same length as `positions`, or empty for flat shading.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates in OpenImageIO convention, or empty.
    pub st: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Index into [`SceneDescription::materials`].
    pub material: usize,
}

/// An analytic sphere. Its st coordinates are the lat-long parameterisation
/// (s = azimuth / 2pi, t = polar angle / pi, t = 0 at +Y).
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: usize,
}

/// Tone mapping applied when writing PNG (EXR is always linear and untouched).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ToneMap {
    /// Clamp to [0, 1], then the sRGB transfer function.
    #[default]
    Clamp,
    /// Reinhard `x / (1 + x)` per channel, then sRGB.
    Reinhard,
}

/// Fresnel equations used at dielectric boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FresnelMode {
    /// Exact unpolarised Fresnel equations.
    #[default]
    Exact,
    /// Schlick's approximation (with total internal reflection).
    Schlick,
}

/// Render settings a scene may carry; the command line overrides them.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// `[render] spp`; `None` leaves the count to the integrator
    /// (`crate::integrator::selection::default_spp`).
    pub spp: Option<u32>,
    pub max_depth: u32,
    /// A path whose throughput (max RGB component) falls below this stops (seed 001).
    pub min_throughput: f32,
    pub tonemap: ToneMap,
    /// Exposure in stops applied to PNG output only.
    pub exposure: f32,
    pub fresnel: FresnelMode,
    /// The sampler's seed (`--seed` overrides it).
    pub seed: u32,
    /// Which integrator renders the scene (`[render] integrator`, `--integrator` overrides
    /// it); `auto` picks one from the scene (`crate::integrator::selection`).
    pub integrator: crate::integrator::IntegratorChoice,
    /// `[render] gi = true`: the scene asks for global illumination (`auto` picks the path
    /// tracer).
    pub gi: bool,
    /// `[render] diffuse_bounces`: how many non-delta bounces a path-traced path may take
    /// (`None`: as many as `max_depth` allows; 0 gives Whitted's image in expectation).
    pub diffuse_bounces: Option<u32>,
    /// `[render] vct_resolution`: voxels across the scene's longest side (`None`: the
    /// default rule of `crate::vct::grid::default_resolution`).
    pub vct_resolution: Option<u32>,
    /// `[render] vct_bounces`: bounces held by the voxels (1: direct light only; default
    /// [`crate::vct::build::DEFAULT_BOUNCES`]).
    pub vct_bounces: u32,
    /// What the voxels above level 0 hold (`--vct-voxels`; directional by default).
    pub vct_voxels: crate::vct::VoxelKind,
    /// How fog's optical depth becomes the blend towards its colour (`[render] fog_model`).
    pub fog_model: crate::medium::FogModel,
    /// How fog segments' optical depth is integrated (`[render] fog_march_steps`: ray
    /// marching with that many steps; the closed form by default).
    pub fog_integration: crate::medium::FogIntegration,
    /// `[render] clamp`: the largest colour component a camera sample may keep
    /// (`RenderOptions::sample_clamp`; `--clamp` overrides it). `None`: no clamp.
    pub sample_clamp: Option<f32>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 360,
            spp: None,
            max_depth: 8,
            min_throughput: 1e-3,
            tonemap: ToneMap::Clamp,
            exposure: 0.0,
            fresnel: FresnelMode::Exact,
            seed: 0,
            integrator: crate::integrator::IntegratorChoice::Auto,
            gi: false,
            diffuse_bounces: None,
            vct_resolution: None,
            vct_bounces: crate::vct::build::DEFAULT_BOUNCES,
            vct_voxels: crate::vct::VoxelKind::Directional,
            fog_model: crate::medium::FogModel::Exact,
            fog_integration: crate::medium::FogIntegration::Exact,
            sample_clamp: None,
        }
    }
}

impl SceneDescription {
    /// The material index of every piece of geometry (each mesh, sphere, patch and height
    /// patch once): the one list of what geometry exists, for questions such as "does any
    /// geometry emit" or "which materials are worn".
    pub fn geometry_materials(&self) -> impl Iterator<Item = usize> + '_ {
        let meshes = self.meshes.iter().map(|m| m.material);
        let spheres = self.spheres.iter().map(|s| s.material);
        let patches = self.patches.iter().map(|p| p.material);
        let heights = self.height_patches.iter().map(|p| p.material);
        meshes.chain(spheres).chain(patches).chain(heights)
    }

    /// Which materials some geometry wears (`SceneDescription::materials` order).
    pub fn worn_materials(&self) -> Vec<bool> {
        let mut worn = vec![false; self.materials.len()];
        for material in self.geometry_materials() {
            if let Some(flag) = worn.get_mut(material) {
                *flag = true;
            }
        }
        worn
    }

    /// World-space bounds of all geometry, or `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for mesh in &self.meshes {
            for p in &mesh.positions {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        for sphere in &self.spheres {
            lo = lo.min(sphere.center - Vec3::splat(sphere.radius));
            hi = hi.max(sphere.center + Vec3::splat(sphere.radius));
        }
        for patch in &self.patches {
            let (plo, phi) = patch.bounds();
            lo = lo.min(plo);
            hi = hi.max(phi);
        }
        for patch in &self.height_patches {
            let (plo, phi) = patch.bounds();
            lo = lo.min(plo);
            hi = hi.max(phi);
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }
}
