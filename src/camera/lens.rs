//! Sampling points on a thin lens.

use glam::Vec2;

/// Map a sample in [0,1)^2 to the unit disk with Shirley and Chiu's concentric mapping
/// (area preserving, low distortion, so stratified samples stay stratified).
#[inline]
pub fn concentric_disk(sample: Vec2) -> Vec2 {
    let a = 2.0 * sample.x - 1.0;
    let b = 2.0 * sample.y - 1.0;
    if !(a.is_finite() && b.is_finite()) || (a == 0.0 && b == 0.0) {
        return Vec2::ZERO;
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, phi) = if a.abs() > b.abs() {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    let (sin, cos) = phi.sin_cos();
    Vec2::new(r * cos, r * sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_land_in_the_unit_disk() {
        for i in 0..16 {
            for j in 0..16 {
                let p = concentric_disk(Vec2::new(i as f32 / 16.0, j as f32 / 16.0));
                assert!(p.length() <= 1.0 + 1e-6);
            }
        }
        assert_eq!(concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
        assert!((concentric_disk(Vec2::new(1.0, 0.5)) - Vec2::X).length() < 1e-6);
        assert_eq!(concentric_disk(Vec2::splat(f32::NAN)), Vec2::ZERO);
    }
}
