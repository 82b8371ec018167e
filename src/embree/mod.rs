//! The one place that knows Embree: a safe layer over Embree 3 (bindgen bindings in `ffi.rs`).
//!
//! The data flow is `Device` -> [`SceneBuilder`] (triangle meshes, spheres, alpha filters,
//! user geometries traced by Rust code)
//! -> [`CommittedScene`] (immutable, `Send + Sync`, shared across rayon threads in an `Arc`)
//! -> traces: 16/8/4-wide SoA [`RayPacket`]s, single rays, and ray streams ([`RayHit`]).
//! Every `unsafe` block of the crate lives under `src/embree/`; nothing above this module
//! touches raw bindings.
//!
//! ```
//! use std::sync::Arc;
//! use conetrace::embree::*;
//! use glam::Vec3;
//! # fn main() -> Result<(), EmbreeError> {
//! let device = Device::new()?;
//! let mut builder = SceneBuilder::new(&device)?;
//! let positions = [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)];
//! let ground = builder.add_triangle_mesh(&positions, &[[0, 1, 2]])?;
//! builder.add_spheres(&[(Vec3::new(0.0, 1.0, 0.0), 0.5)])?;
//! // Alpha cut-out: drop hits whose barycentric u is above 0.9.
//! builder.set_alpha_filter(ground, Arc::new(|c: &FilterCandidate| c.u < 0.9))?;
//! let scene = Arc::new(builder.commit()?);
//!
//! enable_flush_denormals(); // on every tracing thread
//! let mut tile = RayPacket::<16>::new();
//! tile.set_ray(0, &Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y));
//! scene.intersect_tile(&mut tile, TraceOptions::coherent())?;
//! assert_eq!(tile.hit(0).map(|h| h.geom_id), Some(1)); // the sphere, at t = 3.5
//! # Ok(())
//! # }
//! ```
//!
//! Recommended paths (measured in `examples/secondary_rays.rs`, figures in `stream.rs`):
//! camera rays as 4x4 tiles with [`CommittedScene::intersect_tile`] and
//! `TraceOptions::coherent()`; secondary (bounce and shadow) rays as streams with
//! [`CommittedScene::intersect_stream`] / [`CommittedScene::occluded_stream`] and
//! `TraceOptions::incoherent()`.
//!
//! Every trace call reads Embree's device error state afterwards and returns what Embree
//! reported (and any panic of a filter callback) as an [`EmbreeError`]; packet and stream
//! traces fall back to narrower packets or single rays where the device lacks them; scenes
//! are built in Embree's robust (watertight) mode.
//!
//! What this module must not do: shading, footprints or any knowledge of materials; the
//! renderer maps `geom_id` (assigned 0, 1, 2, ... in the order geometries are added) to its
//! own meshes and spheres.

mod context;
mod denormals;
mod device;
mod error;
pub(crate) mod ffi;
mod filter;
mod geometry;
mod packet;
mod ray;
mod scene;
mod stream;
mod user_geometry;

pub use context::{Coherence, RayPayload, TraceOptions};
pub use denormals::{enable_flush_denormals, flush_denormals_enabled};
pub use device::{thread_config, Device};
pub use error::EmbreeError;
pub use filter::{AlphaFilter, FilterCandidate};
pub use packet::RayPacket;
pub use ray::{Hit, Ray, RayHit, INVALID_GEOMETRY_ID};
pub use scene::{Bounds, CommittedScene, SceneBuilder};
pub use user_geometry::{UserGeometry, UserHit, UserRay};
