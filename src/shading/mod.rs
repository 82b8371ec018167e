//! Shading math for the Whitted integrator: pure functions, no scene traversal.
//!
//! What lives here (each file implements one concept and cites its seed equations):
//! - [`reflection`]: mirror directions (seed 001, "Reflection Direction").
//! - [`refraction`]: Snell's-law transmission directions with total internal reflection
//!   (seed 001, "Refraction Direction (1)/(2)"; seed 004, "Total Internal Reflection").
//! - [`mod@fresnel`]: how a dielectric boundary splits energy between the reflected and the
//!   refracted ray (exact unpolarised Fresnel equations, and Schlick's approximation with
//!   total internal reflection as in seed 004, "Fresnel").
//! - [`beer`]: absorption inside a transmissive medium (seed 004, "Beer's Law").
//! - [`brdf`]: the local illumination model of a hit (Lambert plus normalised Blinn-Phong).
//! - [`lights`]: direction, distance and irradiance scale towards each punctual light, for
//!   shadow rays (seed 001, "Shadow Rays").
//! - [`ray_offset`]: spawn points, hit points with a bound on their rounding error, and
//!   ray origins moved just past that bound off the surface they start on (seed 001,
//!   "self intersection"), at any scene scale and camera distance.
//!
//! Conventions: directions are unit `glam::Vec3`; an *incident* direction `d` points
//! towards the surface (the ray's travel direction), `wo`/`wi` point away from it.
//! Nothing here traces rays, reads textures or allocates.

pub mod beer;
pub mod brdf;
pub mod fresnel;
pub mod lights;
pub mod ray_offset;
pub mod reflection;
pub mod refraction;

pub use beer::{sigma_from_attenuation, transmittance};
pub use brdf::eval_surface;
pub use fresnel::{fresnel, fresnel_dielectric, fresnel_schlick, DielectricBoundary};
pub use lights::{light_position, light_sample, LightSample};
pub use ray_offset::{entry_distance, shadow_ray_end, SpawnPoint};
pub use reflection::reflect;
pub use refraction::refract;
