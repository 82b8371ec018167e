//! The aperture of a glossy surface's specular cone (seed 003: "an aperture based on the
//! roughness of the surface material").
//!
//! The normalised Blinn-Phong highlight `cos^s` of the half-vector angle is, about the
//! mirror direction, close to a Phong lobe `cos^(4s)` of the angle to the mirror direction
//! (the half vector turns half as fast). The cone's half-angle is where that lobe falls to
//! half its peak, `acos(2^(-1 / 4s))`, kept between a hundredth of a radian (a mirror-like
//! cone) and the diffuse cones' pi/6.

/// Half-angle (radians) of the specular cone of Blinn-Phong exponent `shininess`.
pub fn specular_cone_aperture(shininess: f32) -> f32 {
    let phong = 4.0 * shininess.max(1e-3);
    let half_maximum = 0.5f32.powf(1.0 / phong).acos();
    half_maximum.clamp(0.01, std::f32::consts::PI / 6.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aperture_narrows_as_shininess_grows() {
        let a8 = specular_cone_aperture(8.0);
        let a32 = specular_cone_aperture(32.0);
        let a1000 = specular_cone_aperture(1000.0);
        assert!(a8 > a32 && a32 > a1000);
        // Half maximum of cos^128 at acos(2^(-1/128)).
        assert!((a32 - 0.5f32.powf(1.0 / 128.0).acos()).abs() < 1e-6);
        assert_eq!(specular_cone_aperture(0.0), std::f32::consts::PI / 6.0);
        assert_eq!(specular_cone_aperture(1e9), 0.01);
    }
}
