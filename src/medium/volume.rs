//! Fog volumes as a scene holds them, and what a segment through all of them amounts to:
//! the summed optical depth, the colour its in-scattering blends towards, its transmittance
//! under either fog model, and free-flight distances for a path tracer.

use std::sync::Arc;

use glam::{DVec3, Vec3};

use super::integration::FogIntegration;
use super::mesh_bounds::ClosedMesh;
use super::segment::{FogBox, Line};
use super::Density;

/// What a bounded fog volume fills.
#[derive(Clone, Debug, PartialEq)]
pub enum FogBounds {
    /// An axis-aligned box (`bounds = { min, max }`).
    Box(FogBox),
    /// The inside of a closed mesh (`bounds = { mesh = ... }`), shared between clones.
    Mesh(Arc<ClosedMesh>),
}

impl FogBounds {
    /// Whether `p` lies inside (on the boundary counts as inside).
    pub fn contains(&self, p: DVec3) -> bool {
        match self {
            FogBounds::Box(b) => b.contains(p),
            FogBounds::Mesh(m) => m.contains(p),
        }
    }
}

/// The parts of a segment inside a volume, in order along the line: at most one for a box
/// or unbounded fog, any number for a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum InsideParts {
    One(Option<(f64, f64)>),
    Many(Vec<(f64, f64)>),
}

impl InsideParts {
    /// The parts, as `(start, end)` distances.
    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (one, many) = match self {
            InsideParts::One(part) => (*part, &[][..]),
            InsideParts::Many(parts) => (None, &parts[..]),
        };
        one.into_iter().chain(many.iter().copied())
    }

    /// Whether the segment misses the volume.
    pub fn is_empty(&self) -> bool {
        match self {
            InsideParts::One(part) => part.is_none(),
            InsideParts::Many(parts) => parts.is_empty(),
        }
    }
}

/// One `[[fog]]` volume.
#[derive(Clone, Debug, PartialEq)]
pub struct FogVolume {
    pub density: Density,
    /// The box or mesh the fog fills; `None` for fog everywhere.
    pub bounds: Option<FogBounds>,
    /// What in-scattered light blends towards (Whitted, seed 004): linear RGB radiance.
    pub color: Vec3,
    /// Single-scattering albedo `sigma_s / sigma_t` per channel, in [0, 1] (path tracer).
    pub albedo: Vec3,
    /// Henyey-Greenstein asymmetry in (-1, 1) (path tracer).
    pub g: f32,
}

impl FogVolume {
    /// The parts of `[t0, t1]` inside this volume's box or mesh (all of it when
    /// unbounded).
    #[inline]
    pub fn parts(&self, line: &Line, t0: f64, t1: f64) -> InsideParts {
        match &self.bounds {
            None => InsideParts::One((t1 > t0).then_some((t0, t1))),
            Some(FogBounds::Box(b)) => InsideParts::One(b.clip(line, t0, t1)),
            Some(FogBounds::Mesh(m)) => InsideParts::Many(m.inside_parts(line, t0, t1)),
        }
    }

    /// Whether `p` lies in the volume's box or mesh (everywhere when unbounded).
    pub fn contains(&self, p: DVec3) -> bool {
        self.bounds.as_ref().is_none_or(|b| b.contains(p))
    }

    /// The exact optical depth of `[t0, t1]` along `line` inside this volume.
    pub fn optical_depth(&self, line: &Line, t0: f64, t1: f64) -> f64 {
        self.parts(line, t0, t1)
            .iter()
            .map(|(u0, u1)| self.density.optical_depth(line, u0, u1))
            .sum()
    }
}

/// How optical depth becomes the blend towards the fog colour (Whitted).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FogModel {
    /// Transmittance `exp(-tau)` (Beer-Lambert), blend `1 - exp(-tau)`.
    #[default]
    Exact,
    /// Seed 004's clamped fog amount: blend `min(1, tau)`, transmittance `1 - min(1, tau)`
    /// ("clamp the fog amount to be between 0 and 1").
    LinearBlend,
}

/// What one segment through the scene's fog amounts to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentFog {
    /// The summed optical depth of every volume (may be infinite).
    pub optical_depth: f64,
    /// The colour in-scattering blends towards: the volumes' colours weighted by their
    /// share of the depth (the colours of the infinitely deep ones, equally, if any).
    pub color: Vec3,
    /// How many volumes the segment crossed (had a non-empty clipped part).
    pub crossed: u32,
}

impl SegmentFog {
    pub const CLEAR: SegmentFog = SegmentFog {
        optical_depth: 0.0,
        color: Vec3::ZERO,
        crossed: 0,
    };

    /// The fraction of light that passes the segment under `model`.
    pub fn transmittance(&self, model: FogModel) -> f32 {
        let tau = self.optical_depth;
        match model {
            FogModel::Exact => (-tau).exp() as f32,
            FogModel::LinearBlend => (1.0 - tau.min(1.0)) as f32,
        }
    }
}

/// The fog along the f32 ray `origin + t * direction` for `t` in `[0, t_end]` (`t_end` may
/// be infinite: an escaping ray), summed over `volumes`, each clipped to its box, with the
/// exact optical depths.
pub fn segment_fog(volumes: &[FogVolume], origin: Vec3, direction: Vec3, t_end: f32) -> SegmentFog {
    segment_fog_with(volumes, origin, direction, t_end, FogIntegration::Exact).0
}

/// [`segment_fog`] with each volume's depth integrated as `integration` says, and the number
/// of density samples that took (0 for the closed form).
pub fn segment_fog_with(
    volumes: &[FogVolume],
    origin: Vec3,
    direction: Vec3,
    t_end: f32,
    integration: FogIntegration,
) -> (SegmentFog, u64) {
    let Some((line, scale)) = Line::from_ray(origin, direction) else {
        return (SegmentFog::CLEAR, 0);
    };
    let mut density_samples = 0u64;
    let t1 = if t_end.is_infinite() {
        f64::INFINITY
    } else {
        f64::from(t_end) * scale
    };
    let mut total = 0.0f64;
    let mut weighted = glam::DVec3::ZERO;
    let mut infinite_colors = glam::DVec3::ZERO;
    let mut infinite_count = 0u32;
    let mut crossed = 0u32;
    for volume in volumes {
        let parts = volume.parts(&line, 0.0, t1);
        if parts.is_empty() {
            continue;
        }
        crossed += 1;
        let mut tau = 0.0;
        for (u0, u1) in parts.iter() {
            let (part_tau, samples) = integration.optical_depth(&volume.density, &line, u0, u1);
            density_samples += samples;
            tau += part_tau;
        }
        if tau.is_infinite() {
            infinite_colors += volume.color.as_dvec3();
            infinite_count += 1;
        } else if tau > 0.0 {
            total += tau;
            weighted += volume.color.as_dvec3() * tau;
        }
    }
    let (optical_depth, color) = if infinite_count > 0 {
        (f64::INFINITY, infinite_colors / f64::from(infinite_count))
    } else if total > 0.0 {
        (total, weighted / total)
    } else {
        (0.0, glam::DVec3::ZERO)
    };
    (
        SegmentFog {
            optical_depth,
            color: color.as_vec3(),
            crossed,
        },
        density_samples,
    )
}

/// A free-flight distance along `line` in `[t0, t1]` through all `volumes`: the first
/// collision of a photon whose extinction is the volumes' summed density, with the volume
/// it collides in, or `None` if it passes the whole interval.
///
/// `optical_depth_draw` gives an independent exponential variate of mean 1 (e.g.
/// `-ln(1 - u)`) per call, one per volume the segment crosses. Each volume's collision
/// distance is found by inverting its own closed-form depth (through a mesh's parts in
/// turn, the draw used up part by part); the nearest of them is distributed as the first
/// collision in the sum of the volumes, because the probability of passing `t` without
/// collision is the product of the volumes' transmittances, `exp(-sum tau_i)`.
pub fn free_flight(
    volumes: &[FogVolume],
    line: &Line,
    t0: f64,
    t1: f64,
    mut optical_depth_draw: impl FnMut() -> f64,
) -> Option<(f64, usize)> {
    let mut nearest: Option<(f64, usize)> = None;
    for (index, volume) in volumes.iter().enumerate() {
        let parts = volume.parts(line, t0, t1);
        if parts.is_empty() {
            continue;
        }
        let mut tau = optical_depth_draw();
        for (u0, u1) in parts.iter() {
            if nearest.is_some_and(|(best, _)| best <= u0) {
                break;
            }
            if let Some(t) = volume.density.distance_at_optical_depth(line, u0, u1, tau) {
                if nearest.is_none_or(|(best, _)| t < best) {
                    nearest = Some((t, index));
                }
                break;
            }
            tau -= volume.density.optical_depth(line, u0, u1);
        }
    }
    nearest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::{ConstantDensity, ExponentialDensity};
    use crate::test_rng::{unit_f64, xorshift64_star};
    use glam::DVec3;

    fn constant(sigma: f64, color: Vec3, bounds: Option<FogBox>) -> FogVolume {
        FogVolume {
            density: Density::Constant(ConstantDensity { sigma }),
            bounds: bounds.map(FogBounds::Box),
            color,
            albedo: Vec3::ONE,
            g: 0.0,
        }
    }

    #[test]
    fn overlapping_volumes_add_and_weight_their_colours() {
        let red = constant(0.1, Vec3::X, None);
        let blue = constant(
            0.3,
            Vec3::Z,
            Some(FogBox {
                min: DVec3::new(2.0, -1.0, -1.0),
                max: DVec3::new(4.0, 1.0, 1.0),
            }),
        );
        let fog = segment_fog(&[red, blue], Vec3::ZERO, Vec3::X * 2.0, 5.0);
        // The f32 ray's t = 5 is 10 units: 0.1 * 10 + 0.3 * 2.
        assert!((fog.optical_depth - 1.6).abs() < 1e-12);
        assert_eq!(fog.crossed, 2);
        let expected = Vec3::new(1.0 / 1.6, 0.0, 0.6 / 1.6);
        assert!((fog.color - expected).abs().max_element() < 1e-6);
        assert_eq!(fog.transmittance(FogModel::LinearBlend), 0.0);
        assert!((fog.transmittance(FogModel::Exact) - (-1.6f32).exp()).abs() < 1e-7);
    }

    #[test]
    fn escaping_rays_through_unbounded_and_height_fog() {
        let everywhere = constant(0.01, Vec3::ONE, None);
        let fog = segment_fog(&[everywhere], Vec3::ZERO, Vec3::X, f32::INFINITY);
        assert_eq!(fog.optical_depth, f64::INFINITY);
        assert_eq!(fog.transmittance(FogModel::Exact), 0.0);
        assert_eq!(fog.color, Vec3::ONE);
        let height = FogVolume {
            density: Density::Exponential(ExponentialDensity {
                sigma: 0.2,
                height: 0.0,
                falloff: 1.0,
            }),
            ..constant(0.0, Vec3::ONE, None)
        };
        let up = segment_fog(&[height], Vec3::ZERO, Vec3::Y, f32::INFINITY);
        assert!((up.optical_depth - 0.2).abs() < 1e-15);
    }

    #[test]
    fn a_segment_missing_the_box_crosses_nothing() {
        let boxed = constant(
            1.0,
            Vec3::ONE,
            Some(FogBox {
                min: DVec3::splat(10.0),
                max: DVec3::splat(11.0),
            }),
        );
        let fog = segment_fog(&[boxed], Vec3::ZERO, Vec3::X, 100.0);
        assert_eq!(fog, SegmentFog::CLEAR);
    }

    /// The nearest of the per-volume collisions is the first collision of the summed
    /// density: with two constant volumes, P(no collision before t) = exp(-(s1 + s2) t).
    #[test]
    fn free_flight_through_two_volumes_has_the_summed_transmittance() {
        let volumes = [
            constant(0.2, Vec3::ONE, None),
            constant(0.3, Vec3::ONE, None),
        ];
        let line = Line {
            origin: DVec3::ZERO,
            direction: DVec3::X,
        };
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || unit_f64(xorshift64_star(&mut state));
        let n = 200_000;
        let mut passed = 0;
        let mut in_second = 0;
        for _ in 0..n {
            match free_flight(&volumes, &line, 0.0, 2.0, || -(1.0 - uniform()).ln()) {
                None => passed += 1,
                Some((t, index)) => {
                    assert!((0.0..=2.0).contains(&t));
                    in_second += usize::from(index == 1);
                }
            }
        }
        let expected = (-0.5f64 * 2.0).exp();
        let p = passed as f64 / n as f64;
        let sd = (expected * (1.0 - expected) / n as f64).sqrt();
        assert!((p - expected).abs() < 4.0 * sd, "{p} vs {expected}");
        // Collisions fall in each volume in proportion to its density.
        let share = in_second as f64 / (n - passed) as f64;
        assert!((share - 0.6).abs() < 0.01, "{share}");
    }

    /// Two separate unit cubes along x, `[1, 2]` and `[4, 5]`, as one closed mesh.
    fn two_cubes() -> FogBounds {
        let mut triangles = Vec::new();
        for x in [1.0, 4.0] {
            let corner = |i: usize| {
                DVec3::new(
                    x + (i & 1) as f64,
                    -0.5 + ((i >> 1) & 1) as f64,
                    -0.5 + ((i >> 2) & 1) as f64,
                )
            };
            for q in [
                [0, 4, 6, 2],
                [1, 3, 7, 5],
                [0, 1, 5, 4],
                [2, 6, 7, 3],
                [0, 2, 3, 1],
                [4, 5, 7, 6],
            ] {
                triangles.push([corner(q[0]), corner(q[1]), corner(q[2])]);
                triangles.push([corner(q[0]), corner(q[2]), corner(q[3])]);
            }
        }
        FogBounds::Mesh(std::sync::Arc::new(
            crate::medium::ClosedMesh::new(&triangles).unwrap(),
        ))
    }

    /// Free flights through fog in a mesh of two parts: collisions only inside the parts,
    /// passing with `exp(-tau)` of both, and the first part taking `1 - exp(-sigma)` of
    /// the flights; delta tracking through the same mesh agrees.
    #[test]
    fn free_flights_through_a_mesh_of_two_parts() {
        let sigma = 0.7;
        let volumes = [FogVolume {
            bounds: Some(two_cubes()),
            ..constant(sigma, Vec3::ONE, None)
        }];
        let line = Line {
            origin: DVec3::new(0.0, 0.1, 0.2),
            direction: DVec3::X,
        };
        let tau = volumes[0].optical_depth(&line, 0.0, 10.0);
        assert!((tau - 2.0 * sigma).abs() < 1e-12, "{tau}");
        let fog = segment_fog(&volumes, Vec3::new(0.0, 0.1, 0.2), Vec3::X, 3.0);
        assert!((fog.optical_depth - sigma).abs() < 1e-6, "{fog:?}");
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 200_000;
        let (mut passed, mut in_first, mut tracked_passed) = (0, 0, 0);
        for _ in 0..n {
            match free_flight(&volumes, &line, 0.0, 10.0, || -(1.0 - uniform()).ln()) {
                None => passed += 1,
                Some((t, _)) => {
                    assert!((1.0..=2.0).contains(&t) || (4.0..=5.0).contains(&t), "{t}");
                    in_first += usize::from(t <= 2.0);
                }
            }
            let tracked =
                crate::medium::delta_tracking(&volumes, &line, 0.0, 10.0, &mut uniform).unwrap();
            match tracked {
                None => tracked_passed += 1,
                Some((t, _)) => {
                    assert!((1.0..=2.0).contains(&t) || (4.0..=5.0).contains(&t), "{t}")
                }
            }
        }
        let expected = (-2.0 * sigma).exp();
        let sd = (expected * (1.0 - expected) / n as f64).sqrt();
        for (what, count) in [("free flight", passed), ("delta tracking", tracked_passed)] {
            let p = count as f64 / n as f64;
            assert!((p - expected).abs() < 4.0 * sd, "{what}: {p} vs {expected}");
        }
        let first = in_first as f64 / n as f64;
        let expected_first = 1.0 - (-sigma).exp();
        let sd = (expected_first * (1.0 - expected_first) / n as f64).sqrt();
        assert!(
            (first - expected_first).abs() < 4.0 * sd,
            "{first} vs {expected_first}"
        );
    }
}
