//! Shading: the BSDFs of materials and the lights, for every integrator; pure functions and
//! plain data, no scene traversal.
//!
//! What lives here (each file implements one concept and cites its seed equations):
//! - [`reflection`]: mirror directions (seed 001, "Reflection Direction").
//! - [`refraction`]: Snell's-law transmission directions with total internal reflection
//!   (seed 001, "Refraction Direction (1)/(2)"; seed 004, "Total Internal Reflection").
//! - [`mod@fresnel`]: how a dielectric boundary splits energy between the reflected and the
//!   refracted ray (exact unpolarised Fresnel equations, and Schlick's approximation with
//!   total internal reflection as in seed 004, "Fresnel").
//! - [`beer`]: absorption inside a transmissive medium (seed 004, "Beer's Law").
//! - [`bsdf`]: the BSDF interface (`eval`, `sample`, `pdf`; lobes named by pbrt-style
//!   [`LobeFlags`], samples carrying their lobe and relative index of refraction) and
//!   cosine-weighted hemisphere sampling.
//! - [`brdf`]: the opaque lobe of a hit (Lambert plus normalised Blinn-Phong).
//! - [`microfacet`]: the GGX distribution (visible-normal sampling, Smith masking) of the
//!   rough lobes, which work in a local [`frame`].
//! - [`mirror`] and [`dielectric`]: the smooth mirror and the smooth dielectric boundary
//!   (exact or Schlick Fresnel, total internal reflection), both delta lobes.
//! - [`conductor`]: the rough GGX metal (Schlick Fresnel from `F0`).
//! - [`multiple_scattering`]: the energy a GGX metal loses between its microfacets, given
//!   back as a compensation lobe (Kulla and Conty 2017).
//! - [`rough_dielectric`]: the rough GGX boundary that reflects and transmits (Walter et
//!   al. 2007, exact Fresnel, total internal reflection).
//! - [`metallic_roughness`]: the glTF 2.0 metallic-roughness opaque lobe.
//! - [`material_bsdf`]: a scene material's lobes with their weights, as one BSDF.
//! - [`material_features`]: what a material does (its lobes, emission, absorption, cut-out,
//!   normal map, textures read), the one answer effects, integrator selection, area lights
//!   and the integrators read.
//! - [`lights`]: direction, distance and irradiance scale towards each punctual light, for
//!   shadow rays (seed 001, "Shadow Rays"); punctual lights are delta lights.
//! - [`environment_light`]: the environment as a light (mean radiance, direction sampling).
//! - [`area_lights`]: emissive triangles and spheres as one-sided area lights, sampled by
//!   solid angle (area sampling for triangles too small or too wide for it).
//! - [`spherical_triangle`]: directions uniform in a triangle's solid angle (Arvo 1995).
//! - [`alias_table`]: Walker/Vose alias tables, choosing among many items in constant time.
//! - [`environment_light`]: the environment as a light (mean radiance, direction sampling,
//!   importance sampled for lat-long maps).
//! - [`distribution_2d`]: piecewise-constant 1D and 2D distributions sampled by inversion.
//! - [`light_selection`]: the scene's lights and the choice of one by power.
//! - [`light_interface`]: what every light answers (`sample_li`, `pdf_li`, `le` and whether
//!   it is a delta light), for whichever kind it is.
//! - [`surface_inputs`]: a material's albedo, alpha, metallic, roughness, emission and
//!   normal-mapped shading normal at a hit, from its factors and the texels the caller
//!   filtered (normal mapping in a tangent frame from dP/ds, dP/dt).
//! - [`ray_offset`]: spawn points, hit points with a bound on their rounding error, and
//!   ray origins moved just past that bound off the surface they start on (seed 001,
//!   "self intersection"), at any scene scale and camera distance.
//!
//! Conventions: directions are unit `glam::Vec3`; an *incident* direction `d` points
//! towards the surface (the ray's travel direction), `wo`/`wi` point away from it.
//! Nothing here traces rays, reads textures or allocates (texels are handed in).

pub mod alias_table;
pub mod area_lights;
pub mod beer;
pub mod brdf;
pub mod bsdf;
#[cfg(test)]
mod bsdf_properties;
pub mod conductor;
pub mod dielectric;
pub mod distribution_2d;
pub mod environment_light;
pub mod frame;
pub mod fresnel;
pub mod light_interface;
pub mod light_selection;
pub mod lights;
pub mod material_bsdf;
pub mod material_features;
pub mod metallic_roughness;
pub mod microfacet;
pub mod mirror;
pub mod multiple_scattering;
pub mod ray_offset;
pub mod reflection;
pub mod refraction;
pub mod rough_dielectric;
pub mod spherical_triangle;
pub mod surface_inputs;

pub use alias_table::AliasTable;
pub use area_lights::{AreaLight, AreaLightSample, AreaLights, AreaShape};
pub use beer::{sigma_from_attenuation, transmittance};
pub use brdf::OpaqueBsdf;
pub use bsdf::{concentric_polar, disk_point, lift_to_hemisphere, Bsdf, BsdfSample, LobeFlags};
pub use conductor::RoughConductor;
pub use dielectric::{DielectricSplit, SmoothDielectric};
pub use environment_light::{EnvironmentLight, EnvironmentMap, EnvironmentSample};
pub use fresnel::{fresnel, fresnel_dielectric, fresnel_schlick, DielectricBoundary};
pub use light_interface::{EmissionLookup, LiSample, LightHit, OwnEmission};
pub use light_selection::{LightRef, LightSelection, SceneLights};
pub use lights::{is_delta_light, light_position, pdf_li, sample_li, LightSample};
pub use material_bsdf::{MaterialBsdf, OpaqueLobe, OpaqueOnly};
pub use material_features::MaterialFeatures;
pub use metallic_roughness::MetallicRoughnessBsdf;
pub use mirror::SmoothMirror;
pub use ray_offset::{
    entry_distance, entry_distances, shadow_ray_end, shadow_ray_towards, SpawnPoint,
};
pub use reflection::{reflect, reflect_above};
pub use refraction::refract;
pub use rough_dielectric::RoughDielectric;
