//! Mirror reflection of a ray direction about a surface normal.
//!
//! Implements seed 001, "Reflection Direction": `r_r = r_i - 2 n (n . r_i)`.
//! The formula is symmetric in the sign of `n`, so the caller may pass the normal of either
//! side of the surface.

use glam::Vec3;

/// Reflects the incident direction `d` (pointing towards the surface) about the unit normal
/// `n` (either orientation). The result has the length of `d` and points away from the
/// surface on the side `d` came from (seed 001, "Reflection Direction").
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// The mirror direction of the incident `d` about the shading normal `ns`, unless that
/// would leave below the geometric surface (a shading normal tilted far from the geometric
/// one at a silhouette); then the mirror direction about the geometric normal `ng`. Both
/// normals face the incident side.
#[inline]
pub fn reflect_above(d: Vec3, ns: Vec3, ng: Vec3) -> Vec3 {
    let r = reflect(d, ns);
    if r.dot(ng) > 0.0 {
        r
    } else {
        reflect(d, ng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_mirrors_the_normal_component_and_keeps_the_tangent_one() {
        let n = Vec3::new(0.0, 1.0, 0.0);
        let d = Vec3::new(0.6, -0.8, 0.0);
        let r = reflect(d, n);
        assert!((r - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
        // Angle of incidence equals angle of reflection.
        assert!(((-d).dot(n) - r.dot(n)).abs() < 1e-6);
    }

    #[test]
    fn reflection_does_not_depend_on_the_normal_orientation() {
        let n = Vec3::new(1.0, 2.0, -0.5).normalize();
        let d = Vec3::new(-0.3, -0.9, 0.2).normalize();
        let a = reflect(d, n);
        let b = reflect(d, -n);
        assert!((a - b).length() < 1e-6);
        assert!((a.length() - 1.0).abs() < 1e-6);
        assert!(
            a.dot(n) * d.dot(n) < 0.0,
            "reflected ray leaves on the incident side"
        );
    }

    #[test]
    fn reflection_about_a_tilted_shading_normal_stays_above_the_surface() {
        let ng = Vec3::Z;
        // A grazing ray and a shading normal tilted towards it: the shading mirror direction
        // would go below the surface.
        let d = Vec3::new(0.99, 0.0, -0.141).normalize();
        let ns = Vec3::new(0.5, 0.0, 0.866).normalize();
        assert!(reflect(d, ns).dot(ng) <= 0.0);
        let r = reflect_above(d, ns, ng);
        assert!(r.dot(ng) > 0.0);
        assert_eq!(r, reflect(d, ng));
        // An untilted normal keeps the shading mirror direction.
        let d = Vec3::new(0.6, 0.0, -0.8);
        assert_eq!(reflect_above(d, ng, ng), reflect(d, ng));
    }

    #[test]
    fn head_on_reflection_reverses_the_ray() {
        let n = Vec3::Z;
        assert!((reflect(-Vec3::Z, n) - Vec3::Z).length() < 1e-7);
    }
}
