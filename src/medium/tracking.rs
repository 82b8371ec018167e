//! Delta tracking (Woodcock tracking): free-flight sampling against a majorant, for a
//! density whose optical depth does not invert in closed form.
//!
//! The path tracer samples collisions by inverting each volume's closed-form depth
//! ([`super::free_flight`]), which is exact for the three density kinds and for any number
//! of overlapping volumes. A density without such an inverse (a kind added later, or one
//! whose integral is known only numerically) can still be sampled exactly by delta
//! tracking (Woodcock et al. 1965; pbrt-v4, section 14.2.2, "delta tracking"): add a
//! fictitious, non-scattering medium that brings the extinction up to a constant majorant
//! `sigma_max >= sigma_t(t)` on the segment, step by exponential distances of rate
//! `sigma_max`, and at each tentative collision accept it as real with probability
//! `sigma_t(t) / sigma_max` (else continue: a null collision). The first accepted
//! collision is distributed as `sigma_t(t) T(t)`, with `T` the real transmittance, and the
//! chance of passing the segment is `T(t1)`. Only point evaluations of the density are
//! needed, never its integral.
//!
//! The majorant here is the sum, over the volumes the segment crosses, of each volume's
//! largest density on its clipped parts. Every kind is monotone along a line (constant, an
//! affine function clamped at 0, an exponential), so that maximum is at an end of the
//! part; a part running to infinity with a growing density has no finite majorant
//! ([`TrackingError::UnboundedDensity`]). The majorant is recomputed from each null
//! collision onward, so it tightens as the walk advances and, through fog thinning toward
//! infinity, shrinks to zero and lets the walk end. The tracker is tested against the closed-form
//! sampler below; the renderer keeps the exact inversion, which needs no rejection steps.

use glam::DVec3;

use super::segment::Line;
use super::volume::FogVolume;
use super::Density;

/// Why a segment cannot be tracked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TrackingError {
    /// A volume's density grows without bound along an infinite segment: no majorant.
    #[error("the fog density grows without bound along the segment: no majorant")]
    UnboundedDensity,
}

/// Whether `density` grows along `direction` (each kind is monotone along a line, so the
/// sign of its slope decides; a clamped linear density counts as growing toward its fog
/// even while the clamp holds it at zero).
fn grows_along(density: &Density, direction: DVec3) -> bool {
    match density {
        Density::Constant(_) => false,
        Density::Linear(linear) => -linear.normal.dot(direction) > 0.0,
        Density::Exponential(exponential) => -exponential.falloff * direction.y > 0.0,
    }
}

/// The largest density of `volume` on `[u0, u1]` (already clipped to its box), or `None`
/// when `u1` is infinite and the density grows along the line.
fn max_density_on(volume: &FogVolume, line: &Line, u0: f64, u1: f64) -> Option<f64> {
    let start = volume.density.density_at(line.at(u0));
    if u1.is_infinite() {
        return (!grows_along(&volume.density, line.direction)).then_some(start);
    }
    Some(start.max(volume.density.density_at(line.at(u1))))
}

/// A majorant of the summed extinction on `[t, t1]`: each crossed volume's largest
/// density on its clipped part, summed, with a relative margin so that rounding in a point
/// evaluation never exceeds it.
fn majorant_from(
    volumes: &[FogVolume],
    line: &Line,
    t: f64,
    t1: f64,
) -> Result<f64, TrackingError> {
    let mut majorant = 0.0f64;
    for volume in volumes {
        let mut largest = 0.0f64;
        for (u0, u1) in volume.parts(line, t, t1).iter() {
            largest = largest
                .max(max_density_on(volume, line, u0, u1).ok_or(TrackingError::UnboundedDensity)?);
        }
        majorant += largest;
    }
    Ok(majorant * (1.0 + 1e-9))
}

/// The summed extinction of `volumes` at distance `t` along `line`, with the index of the
/// volume a real collision there falls in, chosen in proportion to the volumes' densities
/// by `u` in [0, 1).
fn density_at(volumes: &[FogVolume], line: &Line, t: f64, u: f64) -> (f64, Option<usize>) {
    let p = line.at(t);
    let inside = |v: &FogVolume| v.contains(p);
    let total: f64 = volumes
        .iter()
        .filter(|v| inside(v))
        .map(|v| v.density.density_at(p))
        .sum();
    let mut remaining = u * total;
    let mut chosen = None;
    for (index, volume) in volumes.iter().enumerate() {
        if !inside(volume) {
            continue;
        }
        let density = volume.density.density_at(p);
        if density > 0.0 {
            chosen = Some(index);
            if remaining < density {
                break;
            }
            remaining -= density;
        }
    }
    (total, chosen)
}

/// The first real collision along `line` in `[t0, t1]` through `volumes` by delta
/// tracking, with the volume it falls in, or `Ok(None)` if the segment is passed.
/// `uniform` gives independent numbers in [0, 1); each tentative collision uses three.
pub fn delta_tracking(
    volumes: &[FogVolume],
    line: &Line,
    t0: f64,
    t1: f64,
    mut uniform: impl FnMut() -> f64,
) -> Result<Option<(f64, usize)>, TrackingError> {
    let mut t = t0;
    loop {
        // Recomputed from the current point on: over the rest of the segment the bound can
        // only tighten, and along an infinite segment through thinning fog it must shrink
        // for the walk to end.
        let majorant = majorant_from(volumes, line, t, t1)?;
        if majorant <= 0.0 {
            return Ok(None);
        }
        t += -(1.0 - uniform()).ln() / majorant;
        if t >= t1 {
            return Ok(None);
        }
        let accept = uniform() * majorant;
        let (density, volume) = density_at(volumes, line, t, uniform());
        if accept < density {
            if let Some(index) = volume {
                return Ok(Some((t, index)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::{
        free_flight, ConstantDensity, Density, ExponentialDensity, FogBounds, FogBox, LinearDensity,
    };
    use glam::{DVec3, Vec3};

    fn volume(density: Density, bounds: Option<FogBox>) -> FogVolume {
        FogVolume {
            density,
            bounds: bounds.map(FogBounds::Box),
            color: Vec3::ONE,
            albedo: Vec3::ONE,
            g: 0.0,
        }
    }

    /// Three overlapping volumes of the three kinds, the linear one clipped to a box.
    fn mixed() -> Vec<FogVolume> {
        vec![
            volume(Density::Constant(ConstantDensity { sigma: 0.15 }), None),
            volume(
                Density::Exponential(ExponentialDensity {
                    sigma: 0.3,
                    height: 0.0,
                    falloff: 0.8,
                }),
                None,
            ),
            volume(
                Density::Linear(LinearDensity::from_plane(0.2, [1.0, 0.0, 0.0, -3.0]).unwrap()),
                Some(FogBox {
                    min: DVec3::new(-10.0, -10.0, -10.0),
                    max: DVec3::new(10.0, 10.0, 10.0),
                }),
            ),
        ]
    }

    fn generator(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Delta tracking and the closed-form sampler draw the same distribution: the same
    /// pass rate `exp(-tau)` (tau from the closed forms), the same mean collision distance
    /// and the same share of collisions per volume, over 200 000 draws each, on a slanted
    /// segment through all three kinds.
    #[test]
    fn delta_tracking_agrees_with_the_closed_form_inversion() {
        let volumes = mixed();
        let line = Line {
            origin: DVec3::new(0.0, -1.0, 0.5),
            direction: DVec3::new(0.8, 0.6, 0.0),
        };
        let (t0, t1) = (0.0, 7.0);
        let tau: f64 = volumes.iter().map(|v| v.optical_depth(&line, t0, t1)).sum();
        let pass = (-tau).exp();
        let n = 200_000;
        let mut tracked = generator(0x1234_5678_9abc_def1);
        let mut exact = generator(0x0fed_cba9_8765_4321);
        let mut stats = [(0usize, 0.0f64, [0usize; 3]); 2];
        for _ in 0..n {
            let outcomes = [
                delta_tracking(&volumes, &line, t0, t1, &mut tracked).unwrap(),
                free_flight(&volumes, &line, t0, t1, || -(1.0 - exact()).ln()),
            ];
            for (s, outcome) in stats.iter_mut().zip(outcomes) {
                match outcome {
                    None => s.0 += 1,
                    Some((t, index)) => {
                        assert!((t0..=t1).contains(&t));
                        s.1 += t;
                        s.2[index] += 1;
                    }
                }
            }
        }
        let sd = (pass * (1.0 - pass) / n as f64).sqrt();
        for (name, s) in ["delta tracking", "closed form"].iter().zip(&stats) {
            let p = s.0 as f64 / n as f64;
            assert!(
                (p - pass).abs() < 4.0 * sd,
                "{name}: pass {p} vs exp(-tau) {pass}"
            );
        }
        let mean = |s: &(usize, f64, [usize; 3])| s.1 / (n - s.0) as f64;
        let (a, b) = (mean(&stats[0]), mean(&stats[1]));
        assert!((a - b).abs() < 0.03, "mean collision distance {a} vs {b}");
        for k in 0..3 {
            let share = |s: &(usize, f64, [usize; 3])| s.2[k] as f64 / (n - s.0) as f64;
            let (a, b) = (share(&stats[0]), share(&stats[1]));
            assert!((a - b).abs() < 0.01, "volume {k}: share {a} vs {b}");
        }
    }

    #[test]
    fn growing_density_to_infinity_has_no_majorant() {
        let volumes = mixed();
        // Downwards into the height fog, to infinity: the exponential grows without bound.
        let down = Line {
            origin: DVec3::ZERO,
            direction: DVec3::NEG_Y,
        };
        let result = delta_tracking(&volumes, &down, 0.0, f64::INFINITY, generator(1));
        assert_eq!(result, Err(TrackingError::UnboundedDensity));
        // Upwards it thins out: tracking works (the constant fog makes a collision certain).
        let up = Line {
            origin: DVec3::ZERO,
            direction: DVec3::Y,
        };
        let hit = delta_tracking(&volumes, &up, 0.0, f64::INFINITY, generator(2)).unwrap();
        assert!(hit.is_some());
    }

    /// A ray starting far above a linear fog plane and heading into it reads density 0 at
    /// its start and one unit on, yet the fog grows without bound ahead: no majorant.
    #[test]
    fn clamped_linear_fog_ahead_is_unbounded() {
        let volumes = vec![volume(
            Density::Linear(LinearDensity::from_plane(0.2, [0.0, 1.0, 0.0, 0.0]).unwrap()),
            None,
        )];
        let down = Line {
            origin: DVec3::new(0.0, 10.0, 0.0),
            direction: DVec3::NEG_Y,
        };
        let result = delta_tracking(&volumes, &down, 0.0, f64::INFINITY, generator(3));
        assert_eq!(result, Err(TrackingError::UnboundedDensity));
    }

    /// Upwards to infinity through height fog alone a ray escapes with probability
    /// `exp(-tau)`, `tau` finite: tracking must end (the majorant shrinks with the fog) and
    /// pass at that rate.
    #[test]
    fn escaping_through_thinning_fog_ends_and_passes_at_exp_minus_tau() {
        let volumes = vec![volume(
            Density::Exponential(ExponentialDensity {
                sigma: 0.5,
                height: 0.0,
                falloff: 0.8,
            }),
            None,
        )];
        let up = Line {
            origin: DVec3::ZERO,
            direction: DVec3::new(0.6, 0.8, 0.0),
        };
        let tau = volumes[0].optical_depth(&up, 0.0, f64::INFINITY);
        let pass = (-tau).exp();
        let n = 50_000;
        let mut uniform = generator(4);
        let passed = (0..n)
            .filter(|_| {
                delta_tracking(&volumes, &up, 0.0, f64::INFINITY, &mut uniform)
                    .unwrap()
                    .is_none()
            })
            .count();
        let rate = passed as f64 / n as f64;
        let sd = (pass * (1.0 - pass) / n as f64).sqrt();
        assert!(
            (rate - pass).abs() < 4.0 * sd,
            "pass rate {rate} against exp(-tau) = {pass}"
        );
    }
}
