//! Participating media: fog volumes whose density is an analytic function of position, and
//! the exact optical depth of a segment through them (seed 004, "Analytic Fog Density").
//!
//! The amount of fog between two points is the definite integral of the density along the
//! segment, evaluated in closed form (`integration` keeps a ray march of it only to measure
//! the difference). Each density kind has its own file
//! (`constant`, `linear`, `exponential`) with the integral and its inverse (the distance at
//! which a given optical depth is reached, for free-flight sampling); `segment` holds the
//! f64 line and the clipping to a volume's box; `volume` sums over the overlapping volumes
//! of a scene and turns depth into what an integrator uses (transmittance, the blend towards
//! the fog colour, free-flight distances). `phase` is the Henyey-Greenstein phase function
//! of the path tracer's scattering vertices, `tracking` delta tracking against a majorant
//! (for densities without a closed-form inverse). Depths and distances are computed in f64;
//! the phase function, which works on f32 directions, in f32.

pub mod constant;
pub mod exponential;
pub mod integration;
pub mod linear;
pub mod mesh_bounds;
pub mod phase;
pub mod segment;
pub mod tracking;
pub mod volume;

pub use constant::ConstantDensity;
pub use exponential::ExponentialDensity;
pub use integration::FogIntegration;
pub use linear::LinearDensity;
pub use mesh_bounds::{ClosedMesh, MeshBoundsError};
pub use phase::{HenyeyGreenstein, PhaseSample};
pub use segment::{FogBox, Line};
pub use tracking::{delta_tracking, TrackingError};
pub use volume::{
    free_flight, segment_fog, segment_fog_with, FogBounds, FogModel, FogVolume, InsideParts,
    SegmentFog,
};

use glam::DVec3;

/// How a fog volume's extinction varies over space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Density {
    Constant(ConstantDensity),
    Linear(LinearDensity),
    Exponential(ExponentialDensity),
}

impl Density {
    /// Extinction per unit length at `p` (ignoring any bounding box).
    pub fn density_at(&self, p: DVec3) -> f64 {
        match self {
            Density::Constant(c) => c.density_at(),
            Density::Linear(l) => l.density_at(p),
            Density::Exponential(e) => e.density_at(p.y),
        }
    }

    /// The exact integral of the density along `line` over `[t0, t1]` (`t1` may be
    /// infinite).
    pub fn optical_depth(&self, line: &Line, t0: f64, t1: f64) -> f64 {
        match self {
            Density::Constant(c) => c.optical_depth(t0, t1),
            Density::Linear(l) => l.optical_depth(line, t0, t1),
            Density::Exponential(e) => e.optical_depth(line, t0, t1),
        }
    }

    /// The distance in `[t0, t1]` at which the depth from `t0` reaches `tau`, in closed
    /// form, or `None` if the interval holds less.
    pub fn distance_at_optical_depth(
        &self,
        line: &Line,
        t0: f64,
        t1: f64,
        tau: f64,
    ) -> Option<f64> {
        match self {
            Density::Constant(c) => c.distance_at_optical_depth(t0, t1, tau),
            Density::Linear(l) => l.distance_at_optical_depth(line, t0, t1, tau),
            Density::Exponential(e) => e.distance_at_optical_depth(line, t0, t1, tau),
        }
    }

    /// The scale `sigma` of the density.
    pub fn sigma(&self) -> f64 {
        match self {
            Density::Constant(c) => c.sigma,
            Density::Linear(l) => l.sigma,
            Density::Exponential(e) => e.sigma,
        }
    }

    /// The kind's name as the scene format writes it.
    pub fn kind(&self) -> &'static str {
        match self {
            Density::Constant(_) => "constant",
            Density::Linear(_) => "linear",
            Density::Exponential(_) => "exponential",
        }
    }
}

#[cfg(test)]
mod accuracy_tests;
