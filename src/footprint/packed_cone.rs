//! A ray cone packed into 32 bits as two bfloat16 values (seed 000: "bfloat16 is
//! sufficient" for a cone's width and angle).
//!
//! bfloat16 keeps f32's exponent range and 8 significant bits, so packing never overflows
//! and round-to-nearest loses at most a relative 2^-9 of each value.

use half::bf16;

use super::ray_cone::RayCone;

/// A ray cone's (width, angle) as two bfloat16 values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PackedCone {
    /// The cone's width.
    pub width: bf16,
    /// The cone's spread angle in radians.
    pub angle: bf16,
}

impl PackedCone {
    /// Pack a cone (round to nearest).
    #[inline]
    pub fn pack(cone: RayCone) -> PackedCone {
        PackedCone {
            width: bf16::from_f32(cone.width),
            angle: bf16::from_f32(cone.angle),
        }
    }

    /// The cone back in f32.
    #[inline]
    pub fn unpack(self) -> RayCone {
        RayCone::new(self.width.to_f32(), self.angle.to_f32())
    }

    /// Both values in one u32: width in the high half, angle in the low half.
    #[inline]
    pub fn to_bits(self) -> u32 {
        ((self.width.to_bits() as u32) << 16) | self.angle.to_bits() as u32
    }

    /// Inverse of [`Self::to_bits`].
    #[inline]
    pub fn from_bits(bits: u32) -> PackedCone {
        PackedCone {
            width: bf16::from_bits((bits >> 16) as u16),
            angle: bf16::from_bits(bits as u16),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rel_err(a: f32, b: f32) -> f32 {
        if b == 0.0 {
            a.abs()
        } else {
            ((a - b) / b).abs()
        }
    }

    #[test]
    fn round_trip_keeps_eight_bits() {
        for &(w, a) in &[
            (0.0f32, 0.0f32),
            (1.0e-6, -3.0e-4),
            (0.123_456, 0.002_345),
            (1.0e8, -1.0e-20),
        ] {
            let cone = RayCone::new(w, a);
            let back = PackedCone::from_bits(PackedCone::pack(cone).to_bits()).unpack();
            assert!(
                rel_err(back.width, w) <= 1.0 / 256.0,
                "{w} -> {}",
                back.width
            );
            assert!(
                rel_err(back.angle, a) <= 1.0 / 256.0,
                "{a} -> {}",
                back.angle
            );
        }
    }

    proptest! {
        #[test]
        fn round_trip_relative_error_is_at_most_2_pow_minus_8(w in -1.0e9f32..1.0e9, a in -10.0f32..10.0) {
            let back = PackedCone::pack(RayCone::new(w, a)).unpack();
            prop_assert!(rel_err(back.width, w) <= 1.0 / 256.0);
            prop_assert!(rel_err(back.angle, a) <= 1.0 / 256.0);
        }
    }
}
