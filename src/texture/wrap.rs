//! Wrap modes: mapping an integer texel coordinate (held in an f32) to a stored texel.
//!
//! Coordinates arrive as whole numbers in f32 straight from `floor`, so that
//! coordinates up to 1e7 (and beyond) wrap exactly: `rem_euclid` on whole f32 values
//! is exact, and nothing is converted to an integer before it is in range.

use super::WrapMode;

/// The stored texel index for whole-number coordinate `i` on an axis of `n` texels,
/// or `None` when the texel is outside and counts as black.
#[inline(always)]
pub(crate) fn wrap_texel(i: f32, n: u32, mode: WrapMode) -> Option<usize> {
    let nf = n as f32;
    // Callers reduce periodic and mirror coordinates to one or two periods first, so
    // the common cases avoid the division inside `rem_euclid`.
    let wrapped = match mode {
        WrapMode::Periodic if i >= 0.0 && i < nf => i,
        WrapMode::Periodic if i < 0.0 && i >= -nf => i + nf,
        WrapMode::Periodic if i >= nf && i < 2.0 * nf => i - nf,
        WrapMode::Periodic => i.rem_euclid(nf),
        WrapMode::Clamp => i.clamp(0.0, nf - 1.0),
        WrapMode::Black => {
            if i >= 0.0 && i < nf {
                i
            } else {
                return None;
            }
        }
        WrapMode::Mirror => {
            let m = i.rem_euclid(2.0 * nf);
            if m >= nf {
                2.0 * nf - 1.0 - m
            } else {
                m
            }
        }
    };
    // NaN coordinates end here as texel 0 rather than indexing out of bounds.
    // Through u32, which every texel index fits: the conversion to a 64-bit integer costs
    // x86-64 a dozen instructions more, and gives the same index.
    let idx = wrapped as u32 as usize;
    Some(idx.min(n as usize - 1))
}

/// floor() without a libm call on CPUs lacking SSE4.1 (the default x86-64 target):
/// values of magnitude >= 2^23 are already whole, NaN stays NaN.
#[inline(always)]
pub(crate) fn floor_f32(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = (x as i32) as f32;
        if t > x {
            t - 1.0
        } else {
            t
        }
    } else {
        x
    }
}

/// Moves a coordinate by whole periods into [0, 1) (periodic) or [0, 2) (mirror);
/// other modes keep it. The subtraction is exact in f32, so a lookup at s = 1e7 and
/// one at s = 0 read the same texels, and probe offsets added afterwards keep
/// their precision.
#[inline(always)]
pub(crate) fn reduce_coordinate(s: f32, mode: WrapMode) -> f32 {
    match mode {
        WrapMode::Periodic => s - floor_f32(s),
        WrapMode::Mirror => s - 2.0 * floor_f32(s * 0.5),
        WrapMode::Clamp | WrapMode::Black => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_clamp_black_mirror() {
        let n = 4;
        let idx = |i: f32, m| wrap_texel(i, n, m);
        assert_eq!(idx(-1.0, WrapMode::Periodic), Some(3));
        assert_eq!(idx(9.0, WrapMode::Periodic), Some(1));
        assert_eq!(idx(-5.0, WrapMode::Clamp), Some(0));
        assert_eq!(idx(7.0, WrapMode::Clamp), Some(3));
        assert_eq!(idx(-1.0, WrapMode::Black), None);
        assert_eq!(idx(4.0, WrapMode::Black), None);
        assert_eq!(idx(2.0, WrapMode::Black), Some(2));
        // Mirror: 0 1 2 3 | 3 2 1 0 | 0 1 ...
        let mirrored: Vec<_> = (-4..12)
            .map(|i| idx(i as f32, WrapMode::Mirror).unwrap())
            .collect();
        assert_eq!(
            mirrored,
            vec![3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3]
        );
    }

    #[test]
    fn fast_floor_matches_floor() {
        for x in [
            0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, -1.5, 2.99, -2.99, 8388607.5, -8388607.5, 1e7,
            -1e7, 3e9,
        ] {
            assert_eq!(floor_f32(x), x.floor(), "{x}");
        }
        assert!(floor_f32(f32::NAN).is_nan());
    }

    #[test]
    fn coordinates_reduce_by_whole_periods() {
        assert_eq!(reduce_coordinate(1.0e7 + 0.5, WrapMode::Periodic), 0.0);
        assert_eq!(reduce_coordinate(-2.25, WrapMode::Periodic), 0.75);
        assert_eq!(reduce_coordinate(-0.25, WrapMode::Mirror), 1.75);
        assert_eq!(reduce_coordinate(5.5, WrapMode::Mirror), 1.5);
        assert_eq!(reduce_coordinate(-7.0, WrapMode::Clamp), -7.0);
    }

    #[test]
    fn huge_and_nan_coordinates_stay_in_range() {
        for m in [WrapMode::Periodic, WrapMode::Clamp, WrapMode::Mirror] {
            for i in [1.0e7f32, -1.0e7, 3.0e9, -7.0e12, f32::NAN] {
                let k = wrap_texel(i, 5, m).unwrap();
                assert!(k < 5);
            }
        }
        // 1e7 = 5 * 2e6 exactly.
        assert_eq!(wrap_texel(1.0e7, 5, WrapMode::Periodic), Some(0));
        assert_eq!(wrap_texel(1.0e7 + 2.0, 5, WrapMode::Periodic), Some(2));
    }
}
