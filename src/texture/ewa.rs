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
use super::texels::{with_texel_source, TexelSource};
use super::tiles::TexelObserver;
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

/// Gaussian-weighted average over the ellipse with semi-axis vectors `major`,
/// `minor` (st units) centred at (s, t), on one level, reading `texels` (the level's own).
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

    let edge = (-ALPHA).exp();
    // Loop counts from the box size (bounded by the axis cap), not by stepping an
    // f32 coordinate, which stalls where whole numbers are more than 1 apart.
    let span = |lo: f32, hi: f32| ((hi - lo + 1.0).clamp(0.0, 2.0 * cap + 3.0)) as usize;
    let (nx, ny) = (span(x0, x1), span(y0, y1));
    let mut acc = Vec4::ZERO;
    let mut wsum = 0.0f32;
    for row_k in 0..ny {
        let ty = y0 + row_k as f32;
        let dy = ty - y;
        let row = wrap_texel(ty, level.height, wrap.1);
        for col_k in 0..nx {
            let tx = x0 + col_k as f32;
            let dx = tx - x;
            let r2 = a * dx * dx + b * dx * dy + c * dy * dy;
            if r2 < 1.0 {
                let weight = (-ALPHA * r2).exp() - edge;
                wsum += weight;
                if let (Some(ix), Some(iy)) = (wrap_texel(tx, level.width, wrap.0), row) {
                    obs.touch(level_index, ix, iy);
                    acc += weight * texels.texel_at(layout, ix, iy);
                }
            }
        }
    }
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
    use super::super::tiles::NoTextureTiles;
    use super::*;

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
