//! Refraction (transmission) directions across a dielectric boundary, by Snell's law.
//!
//! Implements seed 001, "Refraction Direction (2)" in its dot-product form
//! `r_t = eta r_i - n (eta (n . r_i) + sqrt(1 - eta^2 (1 - (n . r_i)^2)))` with
//! `eta = n1 / n2` and `n` facing the incident ray, and returns `None` when the square root's
//! argument is negative: total internal reflection (seed 004, "Total Internal Reflection").

use glam::Vec3;

/// Refracts the unit incident direction `d` (pointing towards the surface) through a
/// boundary with unit normal `n` (either orientation: it is flipped internally to face the
/// incident ray).
///
/// `eta = n_incident / n_transmitted` is the ratio of the refractive indices of the medium
/// the ray travels in and the medium it enters. Returns the unit transmitted direction, or
/// `None` on total internal reflection. `eta == 1` returns `d` unchanged.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    if eta == 1.0 {
        return Some(d);
    }
    // Orient the normal against the incident ray so cos_i >= 0; clamp the rounding of
    // nearly tangent or nearly normal rays into the valid range.
    let d_dot_n = d.dot(n);
    let (n, cos_i) = if d_dot_n > 0.0 {
        (-n, d_dot_n)
    } else {
        (n, -d_dot_n)
    };
    let cos_i = cos_i.min(1.0);
    // Snell (seed 001): sin^2 t = eta^2 sin^2 i.
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t.is_nan() || sin2_t >= 1.0 {
        // Total internal reflection (or a non-finite eta).
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Seed 001, "Refraction Direction (2)", with n . r_i = -cos_i.
    let t = eta * d + (eta * cos_i - cos_t) * n;
    let t = t.normalize_or_zero();
    (t != Vec3::ZERO).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sin_angle(a: Vec3, n: Vec3) -> f32 {
        a.cross(n).length()
    }

    #[test]
    fn snells_law_holds_entering_and_leaving_glass() {
        let n = Vec3::Y;
        for &(n1, n2) in &[(1.0f32, 1.5f32), (1.5, 1.0), (1.0, 1.33), (2.4, 1.0)] {
            for k in 0..40 {
                let theta = (k as f32 / 40.0) * std::f32::consts::FRAC_PI_2;
                let d = Vec3::new(theta.sin(), -theta.cos(), 0.0);
                let eta = n1 / n2;
                match refract(d, n, eta) {
                    Some(t) => {
                        assert!((t.length() - 1.0).abs() < 1e-5);
                        assert!(
                            t.dot(n) < 0.0,
                            "transmitted ray continues through the surface"
                        );
                        let lhs = n1 * sin_angle(d, n);
                        let rhs = n2 * sin_angle(t, n);
                        assert!((lhs - rhs).abs() < 1e-5, "n1 sin1 {lhs} != n2 sin2 {rhs}");
                        // The refracted ray stays in the plane of incidence.
                        assert!(t.z.abs() < 1e-6);
                        assert!(t.x * d.x >= 0.0);
                    }
                    None => {
                        assert!(
                            eta * theta.sin() >= 1.0 - 1e-5,
                            "TIR below the critical angle"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let eta: f32 = 1.5;
        let critical = (1.0 / eta).asin();
        let n = Vec3::Y;
        let just_below = critical - 1e-3;
        let just_above = critical + 1e-3;
        let d_below = Vec3::new(just_below.sin(), -just_below.cos(), 0.0);
        let d_above = Vec3::new(just_above.sin(), -just_above.cos(), 0.0);
        assert!(refract(d_below, n, eta).is_some());
        assert!(refract(d_above, n, eta).is_none());
    }

    #[test]
    fn normal_orientation_does_not_matter() {
        let n = Vec3::new(0.2, 1.0, -0.3).normalize();
        let d = Vec3::new(0.5, -0.7, 0.1).normalize();
        let a = refract(d, n, 1.0 / 1.5).unwrap();
        let b = refract(d, -n, 1.0 / 1.5).unwrap();
        assert!((a - b).length() < 1e-6);
    }

    #[test]
    fn index_matched_boundary_and_head_on_rays_pass_straight_through() {
        let d = Vec3::new(0.3, -0.9, 0.1).normalize();
        assert_eq!(refract(d, Vec3::Y, 1.0), Some(d));
        let t = refract(-Vec3::Y, Vec3::Y, 1.0 / 1.5).unwrap();
        assert!((t + Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn grazing_rays_are_handled() {
        // d almost in the surface plane: |d . n| tiny (and even of the "wrong" sign).
        let n = Vec3::Y;
        for &dy in &[-1e-7f32, 0.0, 1e-7] {
            let d = Vec3::new(1.0, dy, 0.0).normalize();
            let entering = refract(d, n, 1.0 / 1.5).expect("denser medium always transmits");
            assert!(entering.is_finite());
            assert!((entering.length() - 1.0).abs() < 1e-5);
            // The grazing transmitted ray makes the critical angle with the normal.
            assert!((sin_angle(entering, n) - 1.0 / 1.5).abs() < 1e-4);
            assert!(
                refract(d, n, 1.5).is_none(),
                "grazing exit is total internal reflection"
            );
        }
    }

    proptest! {
        #[test]
        fn refracted_directions_are_unit_and_obey_snell(
            dx in -1.0f32..1.0, dy in -1.0f32..1.0, dz in -1.0f32..1.0,
            nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in -1.0f32..1.0,
            eta in 0.2f32..5.0,
        ) {
            let d = Vec3::new(dx, dy, dz);
            let n = Vec3::new(nx, ny, nz);
            prop_assume!(d.length() > 1e-3 && n.length() > 1e-3);
            let d = d.normalize();
            let n = n.normalize();
            if let Some(t) = refract(d, n, eta) {
                prop_assert!((t.length() - 1.0).abs() < 1e-5);
                let lhs = eta * sin_angle(d, n);
                let rhs = sin_angle(t, n);
                prop_assert!((lhs - rhs).abs() < 2e-4 * eta.max(1.0), "{} vs {}", lhs, rhs);
                // Transmission crosses the surface: same side of n as d.
                prop_assert!(t.dot(n) * d.dot(n) >= -1e-6);
            } else {
                prop_assert!(eta * sin_angle(d, n) >= 1.0 - 1e-4);
            }
        }
    }
}
