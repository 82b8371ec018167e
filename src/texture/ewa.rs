//! Elliptical weighted average (Heckbert 1989, as in pbrt's high-quality mode):
//! a truncated Gaussian over the footprint ellipse, evaluated texel by texel on the
//! level(s) chosen from the minor axis.
//!
//! The ellipse has the Jacobian's singular values as semi-axes (the derivative
//! vectors reach the neighbouring pixel), clamped to the anisotropy limit like the
//! `aniso` filter. In each level's texel space one texel is added to both axes'
//! squares so the ellipse always contains a texel centre; every weight is then
//! non-negative and their sum positive, which makes the result a convex combination
//! of texels (with black counted as a texel under `WrapMode::Black`) and finite for
//! any finite derivatives. A footprint smaller than one level-0 texel is a
//! bilinear point sample, so zero derivatives give the same result as `bilinear`.

use glam::Vec4;

use super::ellipse;
use super::filter_closest_bilinear::bilinear;
use super::micro_cache::ThreadTiles;
use super::mip_pyramid::{MipLevel, MipPyramid};
use super::texels::{with_texel_source, FlatTexels, TexelSource, TileWork};
use super::tile_layout::TileLayout;
use super::tiles::{TexelObserver, TEXTURE_TILE_SIZE};
use super::wrap::wrap_texel;
use super::{TextureQuery, WrapMode};

/// Gaussian falloff exp(-ALPHA r^2), r = 1 on the ellipse boundary.
const ALPHA: f32 = 2.0;

/// The EWA lookup (kept out of line: it is large and would crowd the other filters'
/// registers in `Texture::sample`); demand-loaded levels read through `tiles`.
#[inline(never)]
pub(crate) fn sample<O: TexelObserver>(
    pyramid: &MipPyramid,
    q: &TextureQuery,
    max_aniso: f32,
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    let f = ellipse::footprint(pyramid, q, max_aniso);
    let l0 = &pyramid.levels[0];
    if f.magnified && f.axes.major * l0.width.max(l0.height) as f32 <= 1.0 {
        // The whole ellipse fits inside one texel: the reconstruction filter
        // (bilinear) is the right kernel, as for a point sample.
        return bilinear(l0, 0, q.s, q.t, wrap, Some(tiles), obs);
    }
    let (sin, cos) = f.axes.theta().sin_cos();
    let major = [cos * f.axes.major, sin * f.axes.major];
    let minor = [-sin * f.axes.minor, cos * f.axes.minor];
    let mut sum = Vec4::ZERO;
    for k in 0..2 {
        let w = f.levels.weights[k];
        if w == 0.0 {
            continue;
        }
        let m = f.levels.levels[k];
        let level = &pyramid.levels[m];
        sum += w * with_texel_source!(&level.texels, tiles, |texels| ewa_on_level(
            level, texels, m, q.s, q.t, major, minor, wrap, obs
        ));
    }
    sum
}

/// The box of texel centres around an ellipse a x^2 + b x y + c y^2 < 1 centred at (x, y)
/// (texel space of one level): `nx` columns from `x0`, `ny` rows from `y0`.
struct EllipseBox {
    x: f32,
    y: f32,
    a: f32,
    b: f32,
    c: f32,
    x0: f32,
    y0: f32,
    nx: usize,
    ny: usize,
}

impl EllipseBox {
    /// The tile (column, row) holding every texel of the box, when the box lies inside
    /// `level` (no texel wrapped, whatever the wrap mode) and in one tile: the footprint
    /// is then read with one fetch of that tile.
    #[inline(always)]
    fn tile(&self, level: &MipLevel) -> Option<(usize, usize)> {
        if self.nx == 0 || self.ny == 0 {
            return None;
        }
        let x_last = self.x0 + (self.nx - 1) as f32;
        let y_last = self.y0 + (self.ny - 1) as f32;
        let inside = self.x0 >= 0.0
            && self.y0 >= 0.0
            && x_last < level.width as f32
            && y_last < level.height as f32;
        if !inside {
            return None;
        }
        let shift = TEXTURE_TILE_SIZE.trailing_zeros();
        let column = |x: f32| (x as usize) >> shift;
        let (tile_x, tile_y) = (column(self.x0), column(self.y0));
        (column(x_last) == tile_x && column(y_last) == tile_y).then_some((tile_x, tile_y))
    }

    /// The sum of weight times texel over the box's texels inside the ellipse, and the sum
    /// of their weights (a texel black outside the level, `None`, still counts its
    /// weight). Row `ty` of the box is `row_of(ty)` on the level; `texel(tx, row)` reads
    /// column `tx` of it.
    #[inline(always)]
    fn weighted_sum(
        &self,
        row_of: impl Fn(f32) -> Option<usize>,
        mut texel: impl FnMut(f32, Option<usize>) -> Option<Vec4>,
    ) -> (Vec4, f32) {
        let edge = (-ALPHA).exp();
        let mut acc = Vec4::ZERO;
        let mut wsum = 0.0f32;
        for row_k in 0..self.ny {
            let ty = self.y0 + row_k as f32;
            let dy = ty - self.y;
            let row = row_of(ty);
            for col_k in 0..self.nx {
                let tx = self.x0 + col_k as f32;
                let dx = tx - self.x;
                let r2 = self.a * dx * dx + self.b * dx * dy + self.c * dy * dy;
                if r2 < 1.0 {
                    let weight = (-ALPHA * r2).exp() - edge;
                    wsum += weight;
                    if let Some(value) = texel(tx, row) {
                        acc += weight * value;
                    }
                }
            }
        }
        (acc, wsum)
    }
}

/// [`EllipseBox::weighted_sum`] of a box inside one tile, read from that tile alone.
struct OneTileSum<'e, O> {
    ellipse: &'e EllipseBox,
    layout: TileLayout,
    level_index: usize,
    obs: &'e mut O,
}

impl<O: TexelObserver> TileWork for OneTileSum<'_, O> {
    type Output = (Vec4, f32);

    #[inline(always)]
    fn run<'t, T: FlatTexels<'t>>(&mut self, texels: T, start: usize) -> (Vec4, f32) {
        let (layout, level_index) = (self.layout, self.level_index);
        let obs = &mut *self.obs;
        self.ellipse.weighted_sum(
            |ty| Some(ty as usize),
            |tx, row| {
                let (ix, iy) = (tx as usize, row?);
                obs.touch(level_index, ix, iy);
                Some(texels.texel(start + layout.locate(ix, iy).2))
            },
        )
    }
}

/// Gaussian-weighted average over the ellipse with semi-axis vectors `major`,
/// `minor` (st units) centred at (s, t), on one level, reading `texels` (the level's own):
/// from one fetch of a tile when the ellipse's box lies in it, else texel by texel.
#[allow(clippy::too_many_arguments)]
fn ewa_on_level<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    level_index: usize,
    s: f32,
    t: f32,
    major: [f32; 2],
    minor: [f32; 2],
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let (w, h) = (level.width as f32, level.height as f32);
    let layout = level.layout();
    // Semi-axes in texels, capped at the level's size (a larger ellipse only
    // revisits the same texels under periodic wrap and costs time).
    let cap = w.max(h).max(2.0);
    let scale_axis = |v: [f32; 2]| -> [f32; 2] {
        let v = [v[0] * w, v[1] * h];
        let len = v[0].hypot(v[1]);
        if len > cap {
            [v[0] * cap / len, v[1] * cap / len]
        } else {
            v
        }
    };
    let e0 = scale_axis(major);
    let e1 = scale_axis(minor);
    // Implicit ellipse a x^2 + b x y + c y^2 < f, widened by one texel.
    let a = e0[1] * e0[1] + e1[1] * e1[1] + 1.0;
    let b = -2.0 * (e0[0] * e0[1] + e1[0] * e1[1]);
    let c = e0[0] * e0[0] + e1[0] * e1[0] + 1.0;
    let f = a * c - 0.25 * b * b;
    let (a, b, c) = (a / f, b / f, c / f);

    // Bounding box of a x^2 + b x y + c y^2 = 1.
    let det = 4.0 * a * c - b * b;
    let half_w = 2.0 * (c / det).sqrt();
    let half_h = 2.0 * (a / det).sqrt();
    let x = s * w - 0.5;
    let y = t * h - 0.5;
    let (x0, x1) = ((x - half_w).ceil(), (x + half_w).floor());
    let (y0, y1) = ((y - half_h).ceil(), (y + half_h).floor());

    // Loop counts from the box size (bounded by the axis cap), not by stepping an
    // f32 coordinate, which stalls where whole numbers are more than 1 apart.
    let span = |lo: f32, hi: f32| ((hi - lo + 1.0).clamp(0.0, 2.0 * cap + 3.0)) as usize;
    let ellipse = EllipseBox {
        x,
        y,
        a,
        b,
        c,
        x0,
        y0,
        nx: span(x0, x1),
        ny: span(y0, y1),
    };
    let in_one_tile = ellipse.tile(level).and_then(|(tile_x, tile_y)| {
        let mut work = OneTileSum {
            ellipse: &ellipse,
            layout,
            level_index,
            obs: &mut *obs,
        };
        texels.with_tile_texels(layout, tile_x, tile_y, &mut work)
    });
    let (acc, wsum) = match in_one_tile {
        Some(sums) => sums,
        None => ellipse.weighted_sum(
            |ty| wrap_texel(ty, level.height, wrap.1),
            |tx, row| {
                let (ix, iy) = (wrap_texel(tx, level.width, wrap.0)?, row?);
                obs.touch(level_index, ix, iy);
                Some(texels.texel_at(layout, ix, iy))
            },
        ),
    };
    if wsum > 0.0 {
        acc / wsum
    } else {
        // Unreachable for finite input (the widened ellipse holds a texel centre);
        // kept so a non-finite coordinate still yields a finite texel value.
        let ix = wrap_texel(x.round(), level.width, wrap.0);
        let iy = wrap_texel(y.round(), level.height, wrap.1);
        match (ix, iy) {
            (Some(ix), Some(iy)) => texels.texel_at(layout, ix, iy),
            _ => Vec4::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::super::tiff_tile_reader::tests::maketx;
    use super::super::tiles::NoTextureTiles;
    use super::super::{ColorSpace, Texture, TileCache};
    use super::*;

    /// Every texel read, in order.
    #[derive(Default)]
    struct Touches(Vec<(usize, usize, usize)>);

    impl TexelObserver for Touches {
        fn touch(&mut self, level: usize, x: usize, y: usize) {
            self.0.push((level, x, y));
        }
    }

    /// Boxes of random ellipses over `level` whose box lies in one tile: the sum read from
    /// that tile alone has the bits and the touched texels of the texel-by-texel sum. The
    /// boxes jump between tiles, so a demand-loaded level under a small cap reads each from
    /// a tile fetched, replaced and evicted in between. How many boxes lay in one tile.
    fn one_tile_sums_equal_texel_by_texel_sums(level: &MipLevel, seed: u64) -> usize {
        let mut state = seed;
        let mut next =
            || (crate::test_rng::xorshift64_star(&mut state) >> 40) as f32 / (1u64 << 24) as f32;
        let layout = level.layout();
        let mut in_one_tile = 0;
        for _ in 0..3000 {
            let (x, y) = (
                next() * level.width as f32 - 0.5,
                next() * level.height as f32 - 0.5,
            );
            let (nx, ny) = (1 + (next() * 12.0) as usize, 1 + (next() * 12.0) as usize);
            let ellipse = EllipseBox {
                x,
                y,
                a: 0.2 + next(),
                b: next() - 0.5,
                c: 0.2 + next(),
                x0: (x - nx as f32 / 2.0).ceil(),
                y0: (y - ny as f32 / 2.0).ceil(),
                nx,
                ny,
            };
            let Some((tile_x, tile_y)) = ellipse.tile(level) else {
                continue;
            };
            in_one_tile += 1;
            let (mut fast_touches, mut slow_touches) = (Touches::default(), Touches::default());
            let fast = with_texel_source!(&level.texels, |texels| {
                let mut work = OneTileSum {
                    ellipse: &ellipse,
                    layout,
                    level_index: 0,
                    obs: &mut fast_touches,
                };
                texels.with_tile_texels(layout, tile_x, tile_y, &mut work)
            })
            .unwrap();
            let slow = with_texel_source!(&level.texels, |texels| ellipse.weighted_sum(
                |ty| wrap_texel(ty, level.height, WrapMode::Black),
                |tx, row| {
                    let (ix, iy) = (wrap_texel(tx, level.width, WrapMode::Black)?, row?);
                    slow_touches.touch(0, ix, iy);
                    Some(texels.texel_at(layout, ix, iy))
                }
            ));
            let bits = |(v, w): (Vec4, f32)| (v.to_array().map(f32::to_bits), w.to_bits());
            assert_eq!(bits(fast), bits(slow), "{x} {y} {nx}x{ny}");
            assert_eq!(fast_touches.0, slow_touches.0);
        }
        in_one_tile
    }

    #[test]
    fn an_ellipse_in_one_tile_read_from_the_tile_equals_the_texel_by_texel_sum() {
        let dir = tempfile::tempdir().unwrap();
        for kind in [&[][..], &["-d", "half"], &["-d", "float"]] {
            let tx = maketx(dir.path(), 300, 200, kind);
            let whole = Texture::from_file_whole(&tx, ColorSpace::Srgb).unwrap();
            // Level 0 is 5x4 tiles; the cap holds 2 f32 tiles and more 8-bit ones.
            let cache = Arc::new(TileCache::new(2 * 64 * 64 * 16));
            let demand = Texture::from_file_in(&tx, ColorSpace::Srgb, &cache).unwrap();
            for texture in [&whole, &demand] {
                let n = one_tile_sums_equal_texel_by_texel_sums(&texture.pyramid().levels[0], 7);
                assert!(n > 1000, "{kind:?}: {n} boxes in one tile");
            }
            assert!(demand.cache_stats().unwrap().tiles_evicted > 0);
            assert!(demand.tile_failure().is_none());
        }
    }

    #[test]
    fn constant_texture_is_reproduced() {
        let p = MipPyramid::build(MipLevel::new(40, 24, vec![[0.3; 4]; 40 * 24]).unwrap(), "t")
            .unwrap();
        for k in 0..40 {
            let a = k as f32 * 0.41;
            let q = TextureQuery {
                s: 0.013 * k as f32,
                t: 0.77,
                dsdx: 0.05 * a.cos(),
                dtdx: 0.05 * a.sin(),
                dsdy: -0.004 * a.sin(),
                dtdy: 0.004 * a.cos(),
            };
            let v = sample(
                &p,
                &q,
                16.0,
                (WrapMode::Clamp, WrapMode::Periodic),
                ThreadTiles::none(),
                &mut NoTextureTiles,
            );
            assert!((v - Vec4::splat(0.3)).abs().max_element() < 1e-5);
        }
    }
}
