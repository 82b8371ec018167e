//! The mip pyramid: level 0 and successively halved levels down to 1x1.
//!
//! Built once on load by the rule of OpenImageIO's `maketx` with its default box
//! filter (reference note, step 9), so that for float input our levels equal the
//! ones `maketx` writes within 1e-6: each level is (w/2, h/2) with integer division
//! and a minimum of 1; when both source sides are even the texel is the exact 2x2
//! average, otherwise it is a bilinear sample of the previous level at the new
//! texel's centre with edge clamping. Everything is computed in f32 from the
//! previous f32 level. Non-power-of-two sizes are handled by the bilinear rule.
//!
//! Levels are stored in the precision of level 0 (see [`Texels`]): an 8-bit texture's
//! levels are rounded to bytes as `maketx` rounds them for 8-bit output, so they equal
//! `maketx`'s levels exactly, and a half texture's levels are rounded to half.

use super::texels::{try_texel_vec, Texels};
use super::tile_layout::TileLayout;
use super::TextureError;

/// Largest accepted side, so every texel coordinate is exact in f32.
const MAX_SIDE: u32 = 1 << 24;

/// One level of the pyramid: RGBA texels in the precision of the source ([`Texels`]),
/// stored in 64x64-texel tiles (see `tile_layout`); read them by coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` texels in tile order.
    pub texels: Texels,
}

impl MipLevel {
    /// A level of linear f32 texels; checks the dimensions against the texel count.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 4]>) -> Result<MipLevel, String> {
        Self::with_texels(width, height, Texels::Float(texels))
    }

    /// A level of any storage, from row-major texels (t = 0 first); checks the dimensions
    /// against the texel count.
    pub fn with_texels(width: u32, height: u32, mut texels: Texels) -> Result<MipLevel, String> {
        if width == 0 || height == 0 {
            return Err(format!("{width}x{height} has no texels"));
        }
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(format!(
                "{width}x{height} exceeds {MAX_SIDE} texels per side"
            ));
        }
        let expected = width as usize * height as usize;
        if texels.len() != expected {
            return Err(format!(
                "{width}x{height} needs {expected} texels but {} were given",
                texels.len()
            ));
        }
        texels.rows_to_tiles(TileLayout::new(width, height))?;
        Ok(MipLevel {
            width,
            height,
            texels,
        })
    }

    /// Where each texel sits in [`MipLevel::texels`].
    #[inline(always)]
    pub(crate) fn layout(&self) -> TileLayout {
        TileLayout::new(self.width, self.height)
    }

    /// The linear RGBA texel at column x, row y (both in range).
    #[inline(always)]
    pub fn texel(&self, x: usize, y: usize) -> [f32; 4] {
        self.texel_vec4(x, y).to_array()
    }

    /// [`MipLevel::texel`] as a vector. The filters do not read through it: they pick the
    /// storage kind once per lookup or footprint (`with_texel_source!`).
    #[inline(always)]
    pub(crate) fn texel_vec4(&self, x: usize, y: usize) -> glam::Vec4 {
        let layout = self.layout();
        super::texels::with_texel_source!(&self.texels, |texels| texels.texel_at(layout, x, y))
    }

    /// The first texel (row-major) with a channel that `bad` flags, as `(x, y, channel,
    /// value)`, channels numbered R, G, B, A = 0..3; `channels` bounds which are looked at.
    /// 8-bit levels hold only values in [0, 1] and are not read.
    pub fn find_texel(
        &self,
        channels: usize,
        bad: impl Fn(f32) -> bool,
    ) -> Option<(u32, u32, usize, f32)> {
        if matches!(self.texels, Texels::Byte { .. }) {
            return None;
        }
        self.coordinates().find_map(|(x, y)| {
            let texel = self.texel(x, y);
            let channel = texel[..channels.min(4)].iter().position(|&v| bad(v))?;
            Some((x as u32, y as u32, channel, texel[channel]))
        })
    }

    /// Every texel as linear RGBA f32, row-major (for tools and tests).
    pub fn to_rgba_f32(&self) -> Vec<[f32; 4]> {
        self.coordinates().map(|(x, y)| self.texel(x, y)).collect()
    }

    /// Every (x, y) of the level, row-major.
    pub fn coordinates(&self) -> impl Iterator<Item = (usize, usize)> {
        let width = self.width as usize;
        (0..self.height as usize).flat_map(move |y| (0..width).map(move |x| (x, y)))
    }

    /// min(width, height) as f32: OIIO's per-level filter-width scale.
    #[inline(always)]
    pub(crate) fn min_side(&self) -> f32 {
        self.width.min(self.height) as f32
    }
}

/// `(a + b) / 2` as `maketx` rounds it, in f32; halved before adding when the sum
/// overflows (texels above `f32::MAX / 2`, which a file may hold, averaged to infinity).
#[inline]
fn midpoint(a: f32, b: f32) -> f32 {
    let sum = a + b;
    if sum.is_infinite() && a.is_finite() && b.is_finite() {
        0.5 * a + 0.5 * b
    } else {
        0.5 * sum
    }
}

/// The next coarser level of a `sw` x `sh` level whose texels `texel(x, y)` gives, by the
/// `maketx` box rule, in f32.
fn halve(
    sw: usize,
    sh: usize,
    texel: impl Fn(usize, usize) -> [f32; 4],
    label: &str,
) -> Result<(usize, usize, Vec<[f32; 4]>), TextureError> {
    let dw = (sw / 2).max(1);
    let dh = (sh / 2).max(1);
    let mut texels = try_texel_vec(dw * dh, label)?;
    if sw.is_multiple_of(2) && sh.is_multiple_of(2) {
        // Exact 2x2 box average.
        for y in 0..dh {
            for x in 0..dw {
                let a = texel(2 * x, 2 * y);
                let b = texel(2 * x + 1, 2 * y);
                let c = texel(2 * x, 2 * y + 1);
                let d = texel(2 * x + 1, 2 * y + 1);
                texels.push(std::array::from_fn(|k| {
                    midpoint(midpoint(a[k], b[k]), midpoint(c[k], d[k]))
                }));
            }
        }
    } else {
        // Bilinear sample of this level at each new texel's centre, edges clamped.
        // The centre is (i + 0.5) times the f32 reciprocal of the new size, then
        // scaled to source texels: the same roundings as maketx, for 1e-6 agreement.
        let axis = |i: usize, src: usize, dst: usize| -> (usize, usize, f32) {
            let centre = (i as f32 + 0.5) * (1.0 / dst as f32);
            let x = centre * src as f32 - 0.5;
            let x0 = x.floor();
            let f = x - x0;
            let lo = (x0.max(0.0) as usize).min(src - 1);
            let hi = ((x0 + 1.0).max(0.0) as usize).min(src - 1);
            (lo, hi, f)
        };
        for y in 0..dh {
            let (y0, y1, fy) = axis(y, sh, dh);
            for x in 0..dw {
                let (x0, x1, fx) = axis(x, sw, dw);
                let a = texel(x0, y0);
                let b = texel(x1, y0);
                let c = texel(x0, y1);
                let d = texel(x1, y1);
                texels.push(std::array::from_fn(|k| {
                    (1.0 - fy) * ((1.0 - fx) * a[k] + fx * b[k])
                        + fy * ((1.0 - fx) * c[k] + fx * d[k])
                }));
            }
        }
    }
    Ok((dw, dh, texels))
}

/// All levels, finest first; the last is 1x1.
#[derive(Clone, Debug, PartialEq)]
pub struct MipPyramid {
    /// Level 0 is the full-resolution image.
    pub levels: Vec<MipLevel>,
}

impl MipPyramid {
    /// Builds every level from level 0 by the `maketx` box rule. Each level is computed
    /// in f32 from the previous level's f32 values and then stored in level 0's precision
    /// (8-bit levels rounded to the nearest byte, ties up), the rounded values not fed back: how `maketx`
    /// makes the levels of an 8-bit or half texture (reference note, step 9). `label`
    /// names the texture if a level cannot be allocated.
    pub fn build(base: MipLevel, label: &str) -> Result<MipPyramid, TextureError> {
        let mut previous: Option<(usize, usize, Vec<[f32; 4]>)> = None;
        let mut levels = vec![base];
        loop {
            let last = &levels[levels.len() - 1];
            if last.width == 1 && last.height == 1 {
                break;
            }
            let (sw, sh) = (last.width as usize, last.height as usize);
            let next = match &previous {
                None => halve(sw, sh, |x, y| last.texel(x, y), label)?,
                Some((_, _, values)) => halve(sw, sh, |x, y| values[y * sw + x], label)?,
            };
            let texels = levels[0].texels.same_kind_from(&next.2, label)?;
            let level =
                MipLevel::with_texels(next.0 as u32, next.1 as u32, texels).map_err(|message| {
                    TextureError::Dimensions {
                        label: label.to_string(),
                        message,
                    }
                })?;
            levels.push(level);
            previous = Some(next);
        }
        Ok(MipPyramid { levels })
    }

    /// Uses levels read from a file (e.g. a mip-mapped OpenEXR written by `maketx`).
    /// The caller checks [`MipPyramid::chain_is_valid`] first.
    pub fn from_levels(levels: Vec<MipLevel>) -> MipPyramid {
        MipPyramid { levels }
    }

    /// True when each level halves the previous one (integer division, min 1) down to 1x1.
    pub fn chain_is_valid(levels: &[MipLevel]) -> bool {
        let Some(last) = levels.last() else {
            return false;
        };
        levels.windows(2).all(|w| {
            w[1].width == (w[0].width / 2).max(1) && w[1].height == (w[0].height / 2).max(1)
        }) && last.width == 1
            && last.height == 1
    }

    /// Bytes of texel storage over all levels.
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.texels.memory_bytes()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> MipLevel {
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let v = f(x, y);
                [v, 2.0 * v, 1.0 - v, 1.0]
            })
            .collect();
        MipLevel::new(w, h, texels).unwrap()
    }

    #[test]
    fn sizes_halve_down_to_one_by_one() {
        let sizes = |w, h| -> Vec<(u32, u32)> {
            MipPyramid::build(level(w, h, |_, _| 0.0), "t")
                .unwrap()
                .levels
                .iter()
                .map(|l| (l.width, l.height))
                .collect()
        };
        assert_eq!(sizes(8, 2), vec![(8, 2), (4, 1), (2, 1), (1, 1)]);
        assert_eq!(sizes(13, 7), vec![(13, 7), (6, 3), (3, 1), (1, 1)]);
        assert_eq!(sizes(1, 5), vec![(1, 5), (1, 2), (1, 1)]);
        assert_eq!(sizes(1, 1), vec![(1, 1)]);
        let p = MipPyramid::build(level(13, 7, |_, _| 0.0), "t").unwrap();
        assert!(MipPyramid::chain_is_valid(&p.levels));
        assert!(!MipPyramid::chain_is_valid(&p.levels[..2]));
    }

    #[test]
    fn even_sizes_average_two_by_two_blocks() {
        let p = MipPyramid::build(level(4, 2, |x, y| (x + 4 * y) as f32), "t").unwrap();
        let l1 = &p.levels[1];
        assert_eq!((l1.width, l1.height), (2, 1));
        // (0+1+4+5)/4 and (2+3+6+7)/4
        assert_eq!(l1.texel(0, 0)[0], 2.5);
        assert_eq!(l1.texel(1, 0)[0], 4.5);
        assert_eq!(p.levels[2].texel(0, 0)[0], 3.5);
    }

    #[test]
    fn odd_sizes_resample_bilinearly_at_texel_centres() {
        // 3 -> 1: centre of the new texel is source x = 1.0 exactly.
        let p = MipPyramid::build(level(3, 1, |x, _| [1.0, 5.0, 9.0][x as usize]), "t").unwrap();
        assert_eq!(p.levels[1].texel(0, 0)[0], 5.0);
        // 5 -> 2: centres at source x = 0.75 and 3.25.
        let p = MipPyramid::build(level(5, 1, |x, _| x as f32 * x as f32), "t").unwrap();
        let l1 = &p.levels[1];
        assert!((l1.texel(0, 0)[0] - 0.75).abs() < 1e-6);
        assert!((l1.texel(1, 0)[0] - (9.0 + 0.25 * 7.0)).abs() < 1e-6);
    }

    #[test]
    fn constant_image_stays_constant_and_mean_is_preserved_for_pow2() {
        let p = MipPyramid::build(level(6, 10, |_, _| 0.375), "t").unwrap();
        for l in &p.levels {
            assert!(l.to_rgba_f32().iter().all(|t| (t[0] - 0.375).abs() < 1e-7));
        }
        let p = MipPyramid::build(level(16, 8, |x, y| ((x * 7 + y * 3) % 5) as f32), "t").unwrap();
        let mean = |l: &MipLevel| {
            l.to_rgba_f32().iter().map(|t| t[0] as f64).sum::<f64>() / l.texels.len() as f64
        };
        let m0 = mean(&p.levels[0]);
        for l in &p.levels {
            assert!((mean(l) - m0).abs() < 1e-5);
        }
        assert_eq!(p.memory_bytes(), (128 + 32 + 8 + 2 + 1) * 16);
    }

    #[test]
    fn texels_near_the_largest_float_average_without_overflow() {
        // 3e38 + 3e38 overflows f32; the file's values are finite, so are the levels.
        let texels = (0..16)
            .map(|i| {
                let v = if i % 2 == 0 { 3.0e38 } else { 2.0e38 };
                [v, v, v, 1.0]
            })
            .collect();
        let base = MipLevel::new(4, 4, texels).unwrap();
        let pyramid = MipPyramid::build(base, "huge").unwrap();
        for l in &pyramid.levels[1..] {
            assert!(l.find_texel(4, |v| !v.is_finite()).is_none());
            let t = l.texel(0, 0);
            assert!((t[0] - 2.5e38).abs() < 1e32, "{}", t[0]);
        }
    }

    #[test]
    fn a_tiled_level_reads_back_its_rows() {
        let rows: Vec<[f32; 4]> = (0..200 * 130).map(|i| [i as f32, 0.0, 0.0, 1.0]).collect();
        let level = MipLevel::new(200, 130, rows.clone()).unwrap();
        assert_eq!(level.to_rgba_f32(), rows);
        assert_eq!(level.texel(131, 70)[0], (70 * 200 + 131) as f32);
        assert_ne!(
            level.texels,
            Texels::Float(rows),
            "stored in tiles, not rows"
        );
    }

    #[test]
    fn rejects_bad_dimensions() {
        assert!(MipLevel::new(0, 3, vec![]).is_err());
        assert!(MipLevel::new(2, 2, vec![[0.0; 4]; 3]).is_err());
    }
}
