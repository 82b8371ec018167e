//! The line a ray follows through fog, in f64, and its clipping to a fog volume's box.
//!
//! Optical depths are integrals along a ray's distance parameter. The renderer's rays are
//! f32; their origin and direction are widened to f64 here and the direction normalised in
//! f64, so that a distance `t` is a length in world units and the closed forms of the
//! densities (`constant`, `linear`, `exponential`) lose nothing to a slightly non-unit f32
//! direction or to large coordinates.

use glam::{DVec3, Vec3};

/// A ray's line in f64: points `origin + t * direction`, `direction` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub origin: DVec3,
    pub direction: DVec3,
}

impl Line {
    /// The line of an f32 ray, with its direction normalised in f64. The second value turns
    /// a distance along the f32 ray (`origin + t * direction` with the ray's own, possibly
    /// not quite unit, direction) into the line's unit-speed distance: multiply by it.
    /// `None` for a zero or non-finite direction.
    pub fn from_ray(origin: Vec3, direction: Vec3) -> Option<(Line, f64)> {
        let d = direction.as_dvec3();
        let length = d.length();
        if !(length > 0.0 && length.is_finite() && origin.is_finite()) {
            return None;
        }
        Some((
            Line {
                origin: origin.as_dvec3(),
                direction: d / length,
            },
            length,
        ))
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.direction * t
    }
}

/// An axis-aligned box bounding a fog volume (`bounds = { min, max }`), in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FogBox {
    pub min: DVec3,
    pub max: DVec3,
}

impl FogBox {
    /// The part of `[t0, t1]` (`t1` may be infinite) where `line` is inside the box (its
    /// faces included), or `None` when the line misses the box within the interval.
    ///
    /// The slab method, with the axis the line runs parallel to handled apart: there a
    /// division by zero would give `0 / 0 = NaN` for a line lying exactly on a face.
    pub fn clip(&self, line: &Line, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let mut near = t0;
        let mut far = t1;
        for axis in 0..3 {
            let o = line.origin[axis];
            let d = line.direction[axis];
            let (lo, hi) = (self.min[axis], self.max[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            let (enter, exit) = if a <= b { (a, b) } else { (b, a) };
            near = near.max(enter);
            far = far.min(exit);
            if near > far {
                return None;
            }
        }
        (near < far).then_some((near, far))
    }

    /// Whether `p` lies inside the box or on its faces.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> FogBox {
        FogBox {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        }
    }

    #[test]
    fn a_line_through_the_box_is_clipped_to_its_faces() {
        let line = Line {
            origin: DVec3::new(-5.0, 0.0, 0.0),
            direction: DVec3::X,
        };
        assert_eq!(unit_box().clip(&line, 0.0, f64::INFINITY), Some((4.0, 6.0)));
        assert_eq!(unit_box().clip(&line, 4.5, 5.0), Some((4.5, 5.0)));
        assert_eq!(unit_box().clip(&line, 0.0, 3.0), None);
        assert_eq!(unit_box().clip(&line, 7.0, 9.0), None);
    }

    #[test]
    fn parallel_lines_inside_outside_and_on_a_face() {
        let outside = Line {
            origin: DVec3::new(-5.0, 2.0, 0.0),
            direction: DVec3::X,
        };
        assert_eq!(unit_box().clip(&outside, 0.0, 100.0), None);
        // On the face y = 1: inside by the faces-included rule, no NaN from 0/0.
        let on_face = Line {
            origin: DVec3::new(-5.0, 1.0, 0.0),
            direction: DVec3::X,
        };
        assert_eq!(unit_box().clip(&on_face, 0.0, 100.0), Some((4.0, 6.0)));
    }

    #[test]
    fn from_ray_normalises_in_f64() {
        let (line, scale) = Line::from_ray(Vec3::ZERO, Vec3::new(0.0, 3.0, 4.0)).unwrap();
        assert_eq!(scale, 5.0);
        assert!((line.direction.length() - 1.0).abs() < 1e-15);
        assert!(Line::from_ray(Vec3::ZERO, Vec3::ZERO).is_none());
    }
}
