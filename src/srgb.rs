//! The sRGB transfer functions (IEC 61966-2-1, exact piecewise form), and sRGB bytes encoded
//! without a `powf` each: textures decode and re-encode 8-bit sRGB texels when they build
//! their mip levels, and the PNG output encodes every pixel.

use std::sync::LazyLock;

/// Encoded sRGB to linear: `c / 12.92` up to `0.04045`, else `((c + 0.055) / 1.055)^2.4`.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear to encoded sRGB, the inverse of [`srgb_to_linear`]: `12.92 c` up to `0.0031308`,
/// else `1.055 c^(1/2.4) - 0.055`.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// A value in [0, 1] as the nearest byte, ties upward; outside [0, 1] clamped.
#[inline]
pub fn nearest_byte(v: f32) -> u8 {
    (v * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// A linear value encoded as an sRGB byte: `nearest_byte(linear_to_srgb(c))` for every
/// input, found among the 255 inputs where that byte steps up instead of by a `powf`. The
/// encoding never decreases as `c` grows (a test checks every input where `powf` is used),
/// so the byte is the number of steps at or below `c`.
#[inline]
pub fn srgb_byte(c: f32) -> u8 {
    static STEPS: LazyLock<[f32; 255]> = LazyLock::new(byte_steps);
    if c.is_nan() {
        return nearest_byte(linear_to_srgb(c));
    }
    STEPS.partition_point(|&step| step <= c) as u8
}

/// For each byte 1 to 255, the least input `c` in (0, 1] whose sRGB byte reaches it, by
/// bisection over the positive floats, which order as their bits do.
fn byte_steps() -> [f32; 255] {
    let byte = |bits: u32| nearest_byte(linear_to_srgb(f32::from_bits(bits)));
    std::array::from_fn(|k| {
        let target = k as u8 + 1;
        let (mut below, mut at) = (0u32, 1.0f32.to_bits());
        while at - below > 1 {
            let middle = below + (at - below) / 2;
            if byte(middle) >= target {
                at = middle;
            } else {
                below = middle;
            }
        }
        f32::from_bits(at)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's byte equals the computed one for every float from the end of the linear
    /// segment to 1 (the `powf` branch, about 70 million inputs: the encoding must not
    /// decrease there), across the linear segment by steps, and at the special values.
    #[test]
    fn srgb_byte_equals_the_encoding_for_every_input_where_powf_is_used() {
        let exact = |c: f32| nearest_byte(linear_to_srgb(c));
        let first = 0.003_130_8f32.to_bits();
        let last = 1.0f32.to_bits() + 4096;
        let mut bits = first - 4096;
        while bits <= last {
            let c = f32::from_bits(bits);
            assert_eq!(srgb_byte(c), exact(c), "{c:e} ({bits:#x})");
            bits += 1;
        }
        for bits in (0..first).step_by(997) {
            let c = f32::from_bits(bits);
            assert_eq!(srgb_byte(c), exact(c), "{c:e}");
            assert_eq!(srgb_byte(-c), exact(-c), "{:e}", -c);
        }
        for c in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            f32::MIN,
            -0.0,
            2.5,
            1e20,
        ] {
            assert_eq!(srgb_byte(c), exact(c), "{c}");
        }
        let steps = byte_steps();
        assert!(steps.windows(2).all(|w| w[0] < w[1]), "steps increase");
        assert_eq!(exact(steps[0]), 1);
        assert_eq!(exact(steps[254]), 255);
    }

    #[test]
    fn the_transfer_functions_meet_at_their_breakpoints_and_invert_each_other() {
        assert!((linear_to_srgb(0.003_130_8) - 0.040_45).abs() < 1e-5);
        assert!((linear_to_srgb(0.003_130_9) - linear_to_srgb(0.003_130_8)).abs() < 1e-5);
        assert!((linear_to_srgb(0.5) - 0.735_357).abs() < 1e-5);
        for byte in 0..=255u8 {
            let encoded = f32::from(byte) / 255.0;
            assert_eq!(nearest_byte(linear_to_srgb(srgb_to_linear(encoded))), byte);
        }
    }
}
