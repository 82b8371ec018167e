//! Exact, order-independent sums of a pixel's samples, so that a render split by sample
//! ranges and merged equals a single render bit for bit.
//!
//! Floating-point addition is not associative: `(a + b) + c` and `a + (b + c)` may differ
//! in the last bit, so summing samples 0..4 and 4..8 separately and adding the two sums
//! would not reproduce a sequential sum over 0..8. Instead, every sample's radiance (one
//! `f32` per colour channel) is converted to a signed fixed-point integer and the integers
//! are added in `i128`. Integer addition is associative and commutative, so any split of the
//! sample indices, in any order, gives the same sum; the single-machine render accumulates
//! the same way, and the pixel's final value is one rounding of that exact sum
//! ([`mean_of_sum`]).
//!
//! The fixed-point scale, and why the sum never overflows:
//! - a sample value `v` becomes `round(v * 2^FRACTION_BITS)` with `FRACTION_BITS = 64`:
//!   every `f32` of magnitude at least `2^-40` converts exactly (its last mantissa bit is
//!   worth at least `2^-64`), smaller ones are rounded to a multiple of `2^-64` (`5.4e-20`);
//! - values are clamped to `|v| <= 2^31` first (radiance beyond two billion is not light a
//!   camera records), and NaN counts as 0, so one sample is at most `2^95` in magnitude;
//! - a pixel has fewer than `2^32` samples (`spp` is a `u32`), so the sum stays below
//!   `2^127`, inside `i128`: no addition can overflow, none saturates, and the sum is exact.
//!
//! A partial render over a sample range stores the exact sums in the film's
//! [`Layer::SampleSum`](super::Layer::SampleSum) channels, each `i128` as six 24-bit
//! digits in `f32` channels (every integer below `2^24` is an exact `f32`), which
//! `conetrace merge` adds up and removes.

/// Binary digits after the point of the fixed-point sample values.
pub const FRACTION_BITS: i32 = 64;
/// Sample values are clamped to this magnitude before conversion (`2^31`).
pub const MAX_SAMPLE_MAGNITUDE: f64 = 2_147_483_648.0;
/// Bits per stored digit of an encoded sum: integers below `2^24` are exact in `f32`.
const DIGIT_BITS: u32 = 24;
/// Digits per encoded sum: `6 * 24 = 144 >= 128` bits.
pub const DIGITS: usize = 6;

/// One sample's value as a fixed-point integer (see the module doc for the scale):
/// `round(clamp(value, ±2^31) * 2^64)`, halves rounded away from zero, NaN as 0.
///
/// Computed from the float's bits: an `f32` is `m * 2^e` with an integer mantissa
/// `m < 2^24`, so the scaled value is `m` shifted by `e + 64` places, exact when shifting up
/// and rounded once when shifting down. (The same number as rounding the scaled `f64` and
/// converting it, `to_fixed_via_f64` in the tests, without the two library calls that
/// conversion costs on every sample of every pixel.)
#[inline]
pub fn to_fixed(value: f32) -> i128 {
    let bits = value.to_bits();
    let negative = bits >> 31 != 0;
    let biased_exponent = (bits >> 23) & 0xff;
    let fraction = bits & 0x7f_ffff;
    if biased_exponent == 0xff && fraction != 0 {
        return 0; // NaN
    }
    let magnitude: i128 = if f32::from_bits(bits & 0x7fff_ffff) >= MAX_SAMPLE_MAGNITUDE as f32 {
        // Clamped (infinities too): 2^31 * 2^64.
        1i128 << (31 + FRACTION_BITS)
    } else {
        // value = mantissa * 2^exponent (subnormals have no implicit bit and exponent -149).
        let (mantissa, exponent) = if biased_exponent == 0 {
            (fraction, -149)
        } else {
            (fraction | 0x80_0000, biased_exponent as i32 - 150)
        };
        let shift = exponent + FRACTION_BITS;
        if shift >= 0 {
            // Below 2^31, so the shift is at most 31 - 24 + 1 + 64 = 72: under 2^96, exact.
            (mantissa as i128) << shift
        } else {
            let down = -shift as u32;
            if down > 25 {
                0 // below half of 2^-64 (mantissa < 2^24 < 2^(down - 1))
            } else {
                // Round half away from zero on the magnitude: add half, drop the bits.
                ((mantissa as u64 + (1u64 << (down - 1))) >> down) as i128
            }
        }
    };
    if negative {
        -magnitude
    } else {
        magnitude
    }
}

/// The mean of `count` samples whose fixed-point values add up to `sum`, as the pixel's
/// final `f32`. A pure function of (`sum`, `count`), so equal sums give equal pixels.
#[inline]
pub fn mean_of_sum(sum: i128, count: u32) -> f32 {
    if count == 0 {
        return 0.0;
    }
    // The conversion and the division round once each; the power of two is exact.
    ((to_f64(sum) / count as f64) * 2f64.powi(-FRACTION_BITS)) as f32
}

/// `value as f64` (rounded to nearest, ties to even), without the library call that
/// conversion from `i128` costs on every channel of every pixel. The magnitude's top 64
/// bits, with every bit below them folded into the lowest one, round to the same `f64`: the
/// lowest bit lies below the rounding position (bit 10 of 64) and keeps whether anything
/// nonzero follows it, which is all rounding to nearest reads beyond that position.
#[inline]
pub fn to_f64(value: i128) -> f64 {
    let magnitude = value.unsigned_abs();
    let high = (magnitude >> 64) as u64;
    let rounded = if high == 0 {
        magnitude as u64 as f64
    } else {
        let dropped = 64 - high.leading_zeros();
        let top = (magnitude >> dropped) as u64;
        let sticky = (magnitude & ((1u128 << dropped) - 1) != 0) as u64;
        // 2^dropped, dropped <= 64: exact.
        let scale = f64::from_bits(u64::from(1023 + dropped) << 52);
        (top | sticky) as f64 * scale
    };
    if value < 0 {
        -rounded
    } else {
        rounded
    }
}

/// Adds one sample's RGB to a pixel's fixed-point sum.
#[inline]
pub fn add_sample(sum: &mut [i128; 3], rgb: [f32; 3]) {
    for (s, v) in sum.iter_mut().zip(rgb) {
        // Cannot overflow: see the module doc.
        *s += to_fixed(v);
    }
}

/// A sum as six exact `f32` digits, least significant first (two's complement bits of the
/// `i128`, 24 per digit, the last digit holding the top 8).
pub fn encode(sum: i128) -> [f32; DIGITS] {
    let bits = sum as u128;
    std::array::from_fn(|d| ((bits >> (d as u32 * DIGIT_BITS)) & ((1 << DIGIT_BITS) - 1)) as f32)
}

/// The inverse of [`encode`]; `None` when a digit is not an integer in `0 .. 2^24` or the
/// top digit has bits beyond the 128th (a damaged or foreign channel).
pub fn decode(digits: &[f32; DIGITS]) -> Option<i128> {
    let mut bits: u128 = 0;
    for (d, &value) in digits.iter().enumerate() {
        let limit = if d == DIGITS - 1 {
            (1u32 << (128 - DIGIT_BITS * (DIGITS as u32 - 1))) as f32
        } else {
            (1u32 << DIGIT_BITS) as f32
        };
        if !(value >= 0.0 && value < limit && value.fract() == 0.0) {
            return None;
        }
        bits |= (value as u128) << (d as u32 * DIGIT_BITS);
    }
    Some(bits as i128)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition [`to_fixed`] computes from the bits: clamp in `f64`, scale by a power
    /// of two (exact), round half away from zero, convert (NaN to 0).
    fn to_fixed_via_f64(value: f32) -> i128 {
        let clamped = (value as f64).clamp(-MAX_SAMPLE_MAGNITUDE, MAX_SAMPLE_MAGNITUDE);
        (clamped * 2f64.powi(FRACTION_BITS)).round() as i128
    }

    #[test]
    fn the_conversion_to_f64_rounds_as_the_language_does() {
        let mut values = vec![0i128, 1, -1, i128::MAX, i128::MIN, i128::MIN + 1];
        for k in 0..127 {
            let p = 1i128 << k;
            // Powers of two, their neighbours, and ties between two f64s at every scale.
            for v in [
                p,
                p - 1,
                p + 1,
                p + (p >> 53),
                p + (p >> 53) + 1,
                p + (p >> 54),
            ] {
                values.extend([v, -v]);
            }
            let tie = p | (p >> 53);
            values.extend([tie, -tie, tie | 1, tie | (p >> 54), tie + (p >> 52)]);
        }
        let mut state = 5u64;
        let mut next = || crate::test_rng::xorshift64(&mut state);
        for _ in 0..200_000 {
            let bits = (u128::from(next()) << 64) | u128::from(next());
            let v = (bits as i128) >> (next() % 127);
            values.extend([v, -v]);
        }
        for v in values {
            assert_eq!(to_f64(v).to_bits(), (v as f64).to_bits(), "{v}");
        }
    }

    #[test]
    fn fixed_point_from_the_bits_equals_the_rounded_f64() {
        let mut special = vec![
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            2_147_483_648.0,
            2_147_483_520.0,
            2_147_483_904.0,
            -2_147_483_648.0,
        ];
        // Values whose scaled form lies exactly on a half: 2^-65, 3 * 2^-65, and the largest
        // that round to zero or to one unit.
        for k in 60..=90 {
            let unit = 2f32.powi(-k);
            special.extend([
                unit,
                3.0 * unit,
                -unit,
                -3.0 * unit,
                1.5 * unit,
                0.75 * unit,
            ]);
        }
        for v in special {
            assert_eq!(
                to_fixed(v),
                to_fixed_via_f64(v),
                "{v:e} ({:#x})",
                v.to_bits()
            );
        }
        // Every exponent, a spread of mantissas, both signs.
        let mut x = 0x2545_f491u32;
        for _ in 0..2_000_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let v = f32::from_bits(x);
            assert_eq!(to_fixed(v), to_fixed_via_f64(v), "{v:e} ({x:#x})");
        }
    }

    #[test]
    fn every_split_of_the_samples_sums_to_the_same_bits() {
        // Values whose float sums depend on the grouping.
        let samples: Vec<f32> = (0..64)
            .map(|i| {
                ((i * 7919 % 1000) as f32 * 0.001 + 1e-3).powi(3)
                    * if i % 5 == 0 { 1e4 } else { 1.0 }
            })
            .collect();
        let whole: i128 = samples.iter().map(|&v| to_fixed(v)).sum();
        let mut float_results = std::collections::HashSet::new();
        for split in [1, 3, 16, 31, 63] {
            let (a, b) = samples.split_at(split);
            let sa: i128 = a.iter().map(|&v| to_fixed(v)).sum();
            let sb: i128 = b.iter().map(|&v| to_fixed(v)).sum();
            assert_eq!(sa + sb, whole, "split at {split}");
            let fa: f32 = a.iter().sum();
            let fb: f32 = b.iter().sum();
            float_results.insert((fa + fb).to_bits());
        }
        // The premise: plain float sums of the same split do disagree.
        assert!(float_results.len() > 1, "{float_results:?}");
        assert_eq!(
            mean_of_sum(whole, 64),
            ((whole as f64 / 64.0) * 2f64.powi(-64)) as f32
        );
    }

    #[test]
    fn one_sample_round_trips_exactly() {
        for v in [0.0f32, 1.0, 0.1, 3.5e-12, 1234.567, -0.25, 2.0e9] {
            assert_eq!(mean_of_sum(to_fixed(v), 1).to_bits(), v.to_bits(), "{v}");
        }
        assert_eq!(to_fixed(f32::NAN), 0);
        assert_eq!(to_fixed(f32::INFINITY), to_fixed(2_147_483_648.0));
        // The largest possible sum still fits.
        let max = to_fixed(f32::MAX);
        assert!(max.checked_mul(i128::from(u32::MAX)).is_some());
    }

    #[test]
    fn encoded_sums_decode_to_the_same_integer() {
        for sum in [
            0i128,
            1,
            -1,
            i128::MAX,
            i128::MIN,
            123_456_789_012_345_678_901_234,
            -98_765_432_109_876_543_210,
        ] {
            let digits = encode(sum);
            assert!(digits.iter().all(|d| d.fract() == 0.0 && *d >= 0.0));
            assert_eq!(decode(&digits), Some(sum), "{sum}");
        }
        let mut bad = encode(5);
        bad[2] = 0.5;
        assert_eq!(decode(&bad), None);
        bad[2] = 16_777_216.0;
        assert_eq!(decode(&bad), None);
        let mut top = encode(0);
        top[5] = 256.0;
        assert_eq!(decode(&top), None);
    }
}
