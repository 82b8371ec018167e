//! Point probes on one mip level: nearest texel and bilinear interpolation
//! (reference note, step 8). Every other filter is a weighted sum of these probes.
//!
//! Texel space follows OpenImageIO: x = s * width - 0.5 in f32, so texel i's centre
//! sits at s = (i + 0.5) / width; the integer part picks the upper-left texel and
//! the fraction is the interpolation weight.

use glam::Vec4;

use super::micro_cache::ThreadTiles;
use super::mip_pyramid::MipLevel;
use super::texels::{with_texel_source, TexelSource};
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

/// Reads texel (x, y) of the level (both in range), a demand-loaded level's tile through
/// `tiles` (`None`: through the thread's micro-cache, found here).
///
/// A lookup of a single texel finds the thread's micro-cache here rather than in
/// `Texture::sample`: the thread-local access, out of line, then holds this fetch alone, and
/// the texel's load is reached in fewer steps (measured in docs/texture-filtering.md).
#[inline(always)]
fn fetch_inside<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    x: usize,
    y: usize,
    tiles: Option<ThreadTiles<'_>>,
    obs: &mut O,
) -> Vec4 {
    obs.touch(level_index, x, y);
    let layout = level.layout();
    match tiles {
        Some(tiles) => {
            with_texel_source!(&level.texels, tiles, |texels| texels.texel_at(layout, x, y))
        }
        None => with_texel_source!(&level.texels, |texels| texels.texel_at(layout, x, y)),
    }
}

/// The texel nearest to (s, t); a fraction of exactly 0.5 picks the lower texel, as in OIIO.
/// A demand-loaded level reads its tile through `tiles` (`None`: the thread's micro-cache,
/// found for this one fetch).
///
/// The common case, the nearest texel inside the level, is found in integers and read
/// directly; only a texel outside goes through [`wrap_texel`]. Both give the same texel:
/// where the integer floor lies in the level it equals the float floor, and a NaN position
/// fails the first test.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn closest<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    tiles: Option<ThreadTiles<'_>>,
    obs: &mut O,
) -> Vec4 {
    let x = s * level.width as f32 - 0.5;
    let y = t * level.height as f32 - 0.5;
    let (i, j) = (floor_i32(x), floor_i32(y));
    let i = i.saturating_add((x - i as f32 > 0.5) as i32);
    let j = j.saturating_add((y - j as f32 > 0.5) as i32);
    // A texel inside has x > -0.5, so the first test only turns NaN away.
    if x > -1.0 && y > -1.0 && (i as u32) < level.width && (j as u32) < level.height {
        return fetch_inside(level, level_index, i as usize, j as usize, tiles, obs);
    }
    closest_wrapped(level, level_index, s, t, wrap, tiles, obs)
}

/// [`closest`] of a texel outside the level: wrapped, or black for [`WrapMode::Black`].
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn closest_wrapped<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    tiles: Option<ThreadTiles<'_>>,
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
    match (
        wrap_texel(i, level.width, wrap.0),
        wrap_texel(j, level.height, wrap.1),
    ) {
        (Some(x), Some(y)) => fetch_inside(level, level_index, x, y, tiles, obs),
        _ => Vec4::ZERO,
    }
}

/// floor(x) as an integer for |x| < 2^31 (saturating beyond, 0 for NaN): truncate,
/// then step down when truncation went up. Agrees with [`floor_f32`] wherever the
/// result is a valid texel index.
#[inline(always)]
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    t.saturating_sub((t as f32 > x) as i32)
}

/// Bilinear interpolation of the four texels around (s, t): [`bilinear_from`] with the
/// level's storage kind picked here, a demand-loaded level read through `tiles` (`None`:
/// the thread's micro-cache, found here, as [`closest`] finds it).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn bilinear<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    tiles: Option<ThreadTiles<'_>>,
    obs: &mut O,
) -> Vec4 {
    match tiles {
        Some(tiles) => with_texel_source!(&level.texels, tiles, |texels| bilinear_from(
            level,
            texels,
            level_index,
            s,
            t,
            wrap,
            obs
        )),
        None => with_texel_source!(&level.texels, |texels| bilinear_from(
            level,
            texels,
            level_index,
            s,
            t,
            wrap,
            obs
        )),
    }
}

/// [`bilinear`] kept out of line, for the rare level whose storage kind differs from the
/// one a mip-mapped filter was compiled for.
#[allow(clippy::too_many_arguments)]
#[cold]
#[inline(never)]
pub(crate) fn bilinear_other_kind<O: TexelObserver>(
    level: &MipLevel,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    bilinear(level, level_index, s, t, wrap, Some(tiles), obs)
}

/// Bilinear interpolation of the four texels around (s, t), reading `texels` (the
/// level's own texels, of a storage kind the caller has picked).
///
/// The common case, all four texels inside the level, is decided with two unsigned
/// compares on the integer texel coordinates and reads the texels directly; footprints
/// across an edge go to [`bilinear_wrapped`], kept out of line so the loops of the
/// mip-mapped filters stay small.
#[inline(always)]
pub(crate) fn bilinear_from<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let x = s * level.width as f32 - 0.5;
    let y = t * level.height as f32 - 0.5;
    let (i, j) = (floor_i32(x), floor_i32(y));
    // Negative i wraps to a huge u32, so one compare per axis tests 0 <= i < width - 1.
    if (i as u32) < level.width - 1 && (j as u32) < level.height - 1 {
        let (fs, ft) = (x - i as f32, y - j as f32);
        let (xi, yi) = (i as usize, j as usize);
        obs.touch(level_index, xi, yi);
        obs.touch(level_index, xi + 1, yi);
        obs.touch(level_index, xi, yi + 1);
        obs.touch(level_index, xi + 1, yi + 1);
        let blend = |a: Vec4, b: Vec4, c: Vec4, d: Vec4| {
            let top = a * (1.0 - fs) + b * fs;
            let bottom = c * (1.0 - fs) + d * fs;
            top * (1.0 - ft) + bottom * ft
        };
        return match texels.bilinear_block(level.layout(), xi, yi, blend) {
            Some(v) => v,
            None => bilinear_wrapped(level, texels, level_index, s, t, wrap, obs),
        };
    }
    bilinear_wrapped(level, texels, level_index, s, t, wrap, obs)
}

/// [`bilinear`] for footprints that reach past an edge: every texel goes through
/// [`wrap_texel`]; texels outside under [`WrapMode::Black`] count as zero. Reads `texels`,
/// the level's own.
#[inline(never)]
fn bilinear_wrapped<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    if wrap == (WrapMode::Periodic, WrapMode::Periodic) {
        if let Some(v) = bilinear_periodic(level, texels, level_index, s, t, obs) {
            return v;
        }
    }
    bilinear_any_wrap(level, texels, level_index, s, t, wrap, obs)
}

/// Bilinear interpolation with every texel mapped by [`wrap_texel`]: any wrap mode,
/// any coordinate.
#[inline(always)]
fn bilinear_any_wrap<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    level_index: usize,
    s: f32,
    t: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let (i, fs) = to_texel(s, level.width);
    let (j, ft) = to_texel(t, level.height);
    let xs = [
        wrap_texel(i, level.width, wrap.0),
        wrap_texel(i + 1.0, level.width, wrap.0),
    ];
    let ys = [
        wrap_texel(j, level.height, wrap.1),
        wrap_texel(j + 1.0, level.height, wrap.1),
    ];
    let layout = level.layout();
    // For a demand-loaded level, one tile fetch when all four are inside and share a tile.
    let corner = {
        match (xs, ys) {
            ([Some(x0), Some(x1)], [Some(y0), Some(y1)]) => {
                obs.touch(level_index, x0, y0);
                obs.touch(level_index, x1, y0);
                obs.touch(level_index, x0, y1);
                obs.touch(level_index, x1, y1);
                texels.corner_texels(layout, [x0, x1], [y0, y1])
            }
            _ => {
                let mut corner = [Vec4::ZERO; 4];
                for (row, y) in ys.iter().enumerate() {
                    let Some(y) = *y else { continue };
                    for (col, x) in xs.iter().enumerate() {
                        if let Some(x) = *x {
                            obs.touch(level_index, x, y);
                            corner[2 * row + col] = texels.texel_at(layout, x, y);
                        }
                    }
                }
                corner
            }
        }
    };
    let top = corner[0] * (1.0 - fs) + corner[1] * fs;
    let bottom = corner[2] * (1.0 - fs) + corner[3] * fs;
    top * (1.0 - ft) + bottom * ft
}

/// Periodic wrap of both axes in integer arithmetic, for footprints within one period
/// of the texture (all a filter produces from a reduced coordinate unless the
/// footprint is larger than the texture, then `None`). Same texels and weights as
/// [`wrap_texel`].
#[inline(always)]
fn bilinear_periodic<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    level_index: usize,
    s: f32,
    t: f32,
    obs: &mut O,
) -> Option<Vec4> {
    let (w, h) = (level.width as i32, level.height as i32);
    let x = s * level.width as f32 - 0.5;
    let y = t * level.height as f32 - 0.5;
    let (i, j) = (floor_i32(x), floor_i32(y));
    if !(-w..w).contains(&i) || !(-h..h).contains(&j) || x.is_nan() || y.is_nan() {
        return None;
    }
    let (fs, ft) = (x - i as f32, y - j as f32);
    // i in [-n, n): one step of n brings i and i + 1 into [0, n).
    let wrap = |k: i32, n: i32| -> usize {
        let k = if k < 0 { k + n } else { k };
        (if k >= n { k - n } else { k }) as usize
    };
    let (x0, x1) = (wrap(i, w), wrap(i + 1, w));
    let (y0, y1) = (wrap(j, h), wrap(j + 1, h));
    obs.touch(level_index, x0, y0);
    obs.touch(level_index, x1, y0);
    obs.touch(level_index, x0, y1);
    obs.touch(level_index, x1, y1);
    let layout = level.layout();
    // For a demand-loaded level, one tile fetch when the four texels share a tile (the
    // coarse levels a trilinear lookup reads are mostly edges, and a level of one tile
    // always does).
    let [a, b, c, d] = texels.corner_texels(layout, [x0, x1], [y0, y1]);
    let top = a * (1.0 - fs) + b * fs;
    let bottom = c * (1.0 - fs) + d * fs;
    Some(top * (1.0 - ft) + bottom * ft)
}

#[cfg(test)]
mod tests {
    use super::super::texels::Texels;
    use super::super::tiles::NoTextureTiles;
    use super::*;

    fn ramp() -> MipLevel {
        // 4x2, value = x + 10 y in red.
        let texels = (0..8)
            .map(|k| [(k % 4) as f32 + 10.0 * (k / 4) as f32, 0.0, 0.0, 1.0])
            .collect();
        MipLevel::new(4, 2, texels).unwrap()
    }

    const P: (WrapMode, WrapMode) = (WrapMode::Periodic, WrapMode::Periodic);
    /// Resident levels fetch no tile.
    const NONE: ThreadTiles<'static> = ThreadTiles::none();
    const NO_TILES: Option<ThreadTiles<'static>> = Some(NONE);

    #[test]
    fn bilinear_hits_texel_centres_and_interpolates_between() {
        let l = ramp();
        let at = |s, t, w| bilinear(&l, 0, s, t, w, NO_TILES, &mut NoTextureTiles).x;
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
        assert!(
            (bilinear(&l, 0, 0.0, 0.25, black, NO_TILES, &mut NoTextureTiles).w - 0.5).abs() < 1e-6
        );
    }

    #[test]
    fn bilinear_weights_sum_to_one() {
        let texels = vec![[1.0; 4]; 35];
        let l = MipLevel::new(7, 5, texels).unwrap();
        for k in 0..200 {
            let s = -1.3 + 0.0371 * k as f32;
            let t = 2.1 - 0.0243 * k as f32;
            let v = bilinear(&l, 0, s, t, P, NO_TILES, &mut NoTextureTiles);
            assert!((v - Vec4::ONE).abs().max_element() < 1e-6);
        }
    }

    #[test]
    fn integer_floor_matches_floor() {
        for x in [
            0.0f32, -0.0, 0.25, -0.25, 1.0, -1.0, -1.5, 2.99, -2.99, 1023.5, -0.5, 8388607.5,
        ] {
            assert_eq!(floor_i32(x) as f32, x.floor(), "{x}");
        }
        // Saturating beyond 2^31 on both sides (below, the step down from i32::MIN
        // overflowed), 0 for NaN.
        assert_eq!(floor_i32(-3e9), i32::MIN);
        assert_eq!(floor_i32(f32::NEG_INFINITY), i32::MIN);
        assert_eq!(floor_i32(3e9), i32::MAX);
        assert_eq!(floor_i32(f32::NAN), 0);
    }

    #[test]
    fn closest_inside_the_level_equals_the_wrapped_path() {
        let (w, h) = (13u32, 7u32);
        let texels = (0..w * h).map(|k| [k as f32, 0.0, 0.0, 1.0]).collect();
        let l = MipLevel::new(w, h, texels).unwrap();
        let modes = [
            WrapMode::Periodic,
            WrapMode::Clamp,
            WrapMode::Black,
            WrapMode::Mirror,
        ];
        // Texel edges and centres (fractions of exactly 0.5 included), just past the
        // level's sides, far away, huge and not a number.
        let mut positions: Vec<f32> = (-60..=60).map(|k| k as f32 / (2.0 * w as f32)).collect();
        positions.extend([
            -0.0,
            0.5 / w as f32,
            1.0 - 0.5 / w as f32,
            1.0 + 1e-7,
            -1e-7,
            3e9,
            -3e9,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ]);
        let mut inside = 0;
        for &s in &positions {
            for &t in &positions {
                for wrap in modes.iter().flat_map(|&a| modes.map(|b| (a, b))) {
                    let fast = closest(&l, 0, s, t, wrap, NO_TILES, &mut NoTextureTiles);
                    let wrapped = closest_wrapped(&l, 0, s, t, wrap, NO_TILES, &mut NoTextureTiles);
                    assert_eq!(
                        fast.to_array().map(f32::to_bits),
                        wrapped.to_array().map(f32::to_bits),
                        "s {s} t {t} {wrap:?}"
                    );
                }
                let (x, y) = (s * w as f32 - 0.5, t * h as f32 - 0.5);
                inside += usize::from(
                    (-0.5..w as f32 - 0.5).contains(&x) && (-0.5..h as f32 - 0.5).contains(&y),
                );
            }
        }
        // Both paths were exercised.
        assert!(
            inside > 500 && inside < positions.len() * positions.len() / 2,
            "{inside}"
        );
    }

    #[test]
    fn interior_fast_path_equals_the_wrapped_path() {
        every_storage_fast_path_agrees(13, 7);
    }

    #[test]
    fn fast_path_across_tile_edges_equals_the_wrapped_path() {
        every_storage_fast_path_agrees(150, 70);
    }

    fn every_storage_fast_path_agrees(w: u32, h: u32) {
        let mut state = 99u32;
        let texels = (0..w * h)
            .map(|_| {
                std::array::from_fn(|_| {
                    state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                    (state >> 8) as f32 / (1u32 << 24) as f32
                })
            })
            .collect();
        let float = MipLevel::new(w, h, texels).unwrap();
        // The same level stored as bytes (sRGB) and as halves: each storage's fast path.
        let values = float.to_rgba_f32();
        let stored_as = |kind: Texels| MipLevel {
            texels: kind.same_kind_from(&values, "t").unwrap(),
            ..float.clone()
        };
        for l in [
            float.clone(),
            stored_as(Texels::bytes(vec![], crate::texture::ColorSpace::Srgb)),
            stored_as(Texels::Half(vec![])),
        ] {
            fast_path_agrees(&l, w, h);
        }
    }

    fn fast_path_agrees(l: &MipLevel, w: u32, h: u32) {
        let l = l.clone();
        let mut interior = 0;
        let mut periodic = 0;
        for k in 0..2000 {
            let s = -0.2 + 1.4 * ((k * 37) % 2000) as f32 / 2000.0;
            let t = -0.2 + 1.4 * ((k * 91) % 2000) as f32 / 2000.0;
            for wrap in [P, (WrapMode::Black, WrapMode::Clamp)] {
                let fast = bilinear(&l, 0, s, t, wrap, NO_TILES, &mut NoTextureTiles);
                let slow = with_texel_source!(&l.texels, NONE, |x| bilinear_wrapped(
                    &l,
                    x,
                    0,
                    s,
                    t,
                    wrap,
                    &mut NoTextureTiles
                ));
                assert_eq!(fast, slow, "s {s} t {t}");
            }
            // The integer periodic path against wrap_texel, also a period away.
            for shift in [-1.0f32, 0.0, 0.9] {
                let (ss, ts) = (s + shift, t - shift);
                let generic = with_texel_source!(&l.texels, NONE, |x| bilinear_any_wrap(
                    &l,
                    x,
                    0,
                    ss,
                    ts,
                    P,
                    &mut NoTextureTiles
                ));
                if let Some(v) = with_texel_source!(&l.texels, NONE, |x| bilinear_periodic(
                    &l,
                    x,
                    0,
                    ss,
                    ts,
                    &mut NoTextureTiles
                )) {
                    assert_eq!(v, generic, "s {ss} t {ts}");
                    periodic += 1;
                }
            }
            let (x, y) = (s * w as f32 - 0.5, t * h as f32 - 0.5);
            if x >= 0.0 && x < (w - 1) as f32 && y >= 0.0 && y < (h - 1) as f32 {
                interior += 1;
            }
        }
        // Both paths were exercised.
        assert!(interior > 500 && interior < 1900, "{interior}");
        assert!(periodic > 1500, "{periodic}");
    }

    #[test]
    fn closest_rounds_half_down() {
        let l = ramp();
        let at = |s: f32| closest(&l, 0, s, 0.25, P, NO_TILES, &mut NoTextureTiles).x;
        assert_eq!(at(0.2), 0.0);
        assert_eq!(at(0.26), 1.0);
        // s * 4 = 1 exactly: fraction 0.5 stays on texel 0.
        assert_eq!(at(0.25), 0.0);
        assert_eq!(at(0.99), 3.0);
        assert_eq!(at(1.01), 0.0);
    }
}
