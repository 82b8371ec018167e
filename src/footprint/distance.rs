//! The "distance metric" baseline footprint (seed 000's figures 4 and 5; seed 002, section
//! 4.2, figure 3b): the camera pixel's spread times the total distance travelled.
//!
//! Reflection and refraction leave it unchanged, so curved mirrors and lenses are ignored:
//! it over-blurs behind concave mirrors and refractions and under-blurs behind convex
//! reflectors. It exists to be compared against cones and differentials.

use super::robust::finite;

/// Footprint width = `width0 + angle * travelled` along the whole path.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DistanceFootprint {
    /// Width at the camera (0 for perspective cameras, one pixel for orthographic ones).
    pub width0: f32,
    /// The camera's per-pixel spread angle (non-negative).
    pub angle: f32,
    /// Total distance travelled from the camera.
    pub travelled: f32,
}

impl DistanceFootprint {
    /// A footprint starting `width0` wide and spreading at `angle`.
    #[inline]
    pub fn new(width0: f32, angle: f32) -> DistanceFootprint {
        DistanceFootprint {
            width0: finite(width0).abs(),
            angle: finite(angle).abs(),
            travelled: 0.0,
        }
    }

    /// The footprint after `distance` more along the path.
    #[inline]
    pub fn propagate(self, distance: f32) -> DistanceFootprint {
        let d = if distance.is_nan() {
            0.0
        } else {
            distance.max(0.0)
        };
        DistanceFootprint {
            travelled: finite(self.travelled + d),
            ..self
        }
    }

    /// Width at the current position (never negative).
    #[inline]
    pub fn width(&self) -> f32 {
        finite(self.width0 + self.angle * self.travelled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn width_grows_with_total_distance() {
        let f = DistanceFootprint::new(0.0, 0.002)
            .propagate(3.0)
            .propagate(2.0);
        assert!((f.width() - 0.01).abs() < 1e-7);
        let ortho = DistanceFootprint::new(0.5, 0.0).propagate(100.0);
        assert_eq!(ortho.width(), 0.5);
        assert_eq!(
            DistanceFootprint::new(0.0, 1.0).propagate(f32::NAN).width(),
            0.0
        );
    }
}
