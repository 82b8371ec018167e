//! Point probes on one mip level: nearest texel and bilinear interpolation
//! (reference note, step 8). Every other filter is a weighted sum of these probes.
//!
//! Texel space follows OpenImageIO: x = s * width - 0.5 in f32, so texel i's centre
//! sits at s = (i + 0.5) / width; the integer part picks the upper-left texel and
//! the fraction is the interpolation weight.

use glam::Vec4;

use super::mip_pyramid::MipLevel;
use super::tiles::TexelObserver;
use super::wrap::{floor_f32, wrap_texel};
use super::WrapMode;

/// Texel-space position split into whole part (kept in f32 so huge values stay exact)
/// and fraction.
#[inline(always)]
fn to_texel(s: f32, n: u32) -> (f32, f32) {
    let x = s * n as f32 - 0.5;
    let i = floor_f32(x);
    (i, x - i)
}

/// Reads texel (i, j) after wrapping; black outside for [`WrapMode::Black`].
#[inline(always)]
fn fetch<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    i: f32,
    j: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    match (
        wrap_texel(i, level.width, wrap.0),
        wrap_texel(j, level.height, wrap.1),
    ) {
        (Some(x), Some(y)) => {
            obs.touch(level_index, x, y);
            Vec4::from_array(level.texel(x, y))
        }
        _ => Vec4::ZERO,
    }
}

/// The texel nearest to (s, t); a fraction of exactly 0.5 picks the lower texel, as in OIIO.
#[inline]
pub(crate) fn closest<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let (mut i, fs) = to_texel(s, level.width);
    let (mut j, ft) = to_texel(t, level.height);
    if fs > 0.5 {
        i += 1.0;
    }
    if ft > 0.5 {
        j += 1.0;
    }
    fetch(level, level_index, i, j, wrap, obs)
}

/// Bilinear interpolation of the four texels around (s, t).
#[inline(always)]
pub(crate) fn bilinear<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let (i, fs) = to_texel(s, level.width);
    let (j, ft) = to_texel(t, level.height);
    let (w, h) = (level.width as f32, level.height as f32);
    if i >= 0.0 && i + 1.0 < w && j >= 0.0 && j + 1.0 < h {
        // All four texels inside: no wrapping needed (the common case).
        let (x, y) = (i as usize, j as usize);
        let row = level.width as usize;
        let k = y * row + x;
        obs.touch(level_index, x, y);
        obs.touch(level_index, x + 1, y);
        obs.touch(level_index, x, y + 1);
        obs.touch(level_index, x + 1, y + 1);
        let t = &level.texels;
        let (a, b) = (Vec4::from_array(t[k]), Vec4::from_array(t[k + 1]));
        let (c, d) = (
            Vec4::from_array(t[k + row]),
            Vec4::from_array(t[k + row + 1]),
        );
        let top = a * (1.0 - fs) + b * fs;
        let bottom = c * (1.0 - fs) + d * fs;
        return top * (1.0 - ft) + bottom * ft;
    }
    let xs = [
        wrap_texel(i, level.width, wrap.0),
        wrap_texel(i + 1.0, level.width, wrap.0),
    ];
    let ys = [
        wrap_texel(j, level.height, wrap.1),
        wrap_texel(j + 1.0, level.height, wrap.1),
    ];
    let mut corner = [Vec4::ZERO; 4];
    for (row, y) in ys.iter().enumerate() {
        let Some(y) = *y else { continue };
        for (col, x) in xs.iter().enumerate() {
            if let Some(x) = *x {
                obs.touch(level_index, x, y);
                corner[2 * row + col] = Vec4::from_array(level.texel(x, y));
            }
        }
    }
    let top = corner[0] * (1.0 - fs) + corner[1] * fs;
    let bottom = corner[2] * (1.0 - fs) + corner[3] * fs;
    top * (1.0 - ft) + bottom * ft
}

#[cfg(test)]
mod tests {
    use super::super::tiles::NoTiles;
    use super::*;

    fn ramp() -> MipLevel {
        // 4x2, value = x + 10 y in red.
        let texels = (0..8)
            .map(|k| [(k % 4) as f32 + 10.0 * (k / 4) as f32, 0.0, 0.0, 1.0])
            .collect();
        MipLevel::new(4, 2, texels).unwrap()
    }

    const P: (WrapMode, WrapMode) = (WrapMode::Periodic, WrapMode::Periodic);

    #[test]
    fn bilinear_hits_texel_centres_and_interpolates_between() {
        let l = ramp();
        let at = |s, t, w| bilinear(&l, 0, s, t, w, &mut NoTiles).x;
        assert_eq!(at(0.125, 0.25, P), 0.0);
        assert_eq!(at(0.375, 0.75, P), 11.0);
        assert!((at(0.25, 0.5, P) - 5.5).abs() < 1e-6);
        // Periodic across the left edge: halfway between texel 3 and texel 0.
        assert!((at(0.0, 0.25, P) - 1.5).abs() < 1e-6);
        let clamp = (WrapMode::Clamp, WrapMode::Clamp);
        assert_eq!(at(0.0, 0.25, clamp), 0.0);
        let black = (WrapMode::Black, WrapMode::Black);
        // Half of texel 0, half of black.
        assert!(at(0.0, 0.25, black).abs() < 1e-6);
        assert!((bilinear(&l, 0, 0.0, 0.25, black, &mut NoTiles).w - 0.5).abs() < 1e-6);
    }

    #[test]
    fn bilinear_weights_sum_to_one() {
        let texels = vec![[1.0; 4]; 35];
        let l = MipLevel::new(7, 5, texels).unwrap();
        for k in 0..200 {
            let s = -1.3 + 0.0371 * k as f32;
            let t = 2.1 - 0.0243 * k as f32;
            let v = bilinear(&l, 0, s, t, P, &mut NoTiles);
            assert!((v - Vec4::ONE).abs().max_element() < 1e-6);
        }
    }

    #[test]
    fn closest_rounds_half_down() {
        let l = ramp();
        let at = |s: f32| closest(&l, 0, s, 0.25, P, &mut NoTiles).x;
        assert_eq!(at(0.2), 0.0);
        assert_eq!(at(0.26), 1.0);
        // s * 4 = 1 exactly: fraction 0.5 stays on texel 0.
        assert_eq!(at(0.25), 0.0);
        assert_eq!(at(0.99), 3.0);
        assert_eq!(at(1.01), 0.0);
    }
}
