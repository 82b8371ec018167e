//! Trilinear filtering: one bilinear probe on each of two blended mip levels
//! (reference note, step 6; seed 002, eq. 26 chooses the level from the larger
//! footprint extent, as OIIO's conservative mode does).

use glam::Vec4;

use super::ellipse::{adjust_derivatives, choose_levels, LevelChoice};
use super::filter_closest_bilinear::{bilinear_from, bilinear_other_kind};
use super::micro_cache::ThreadTiles;
use super::mip_pyramid::MipPyramid;
use super::texels::{with_texel_source, TexelSource};
use super::tiles::TexelObserver;
use super::{TextureQuery, WrapMode};

/// Levels and weights for the isotropic filter width max(|ds|, |dt|).
#[inline]
pub(crate) fn level_choice(pyramid: &MipPyramid, q: &TextureQuery) -> LevelChoice {
    let d = adjust_derivatives(q);
    let sfilt = d.dsdx.abs().max(d.dsdy.abs());
    let tfilt = d.dtdx.abs().max(d.dtdy.abs());
    choose_levels(pyramid, sfilt.max(tfilt)).unwrap_or(LevelChoice {
        levels: [0, 0],
        weights: [1.0, 0.0],
    })
}

/// The trilinear lookup, compiled once per storage kind (that of level 0, which every
/// level of a pyramid normally shares); demand-loaded levels read through `tiles`.
#[inline]
pub(crate) fn sample<O: TexelObserver>(
    pyramid: &MipPyramid,
    q: &TextureQuery,
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    with_texel_source!(&pyramid.levels[0].texels, tiles, |kind| sample_from(
        kind, pyramid, q, wrap, obs
    ))
}

/// [`sample`] reading levels of the storage kind of `kind`; a level of another kind
/// goes through [`bilinear_other_kind`], which picks its kind itself.
#[inline(always)]
fn sample_from<'a, S: TexelSource<'a>, O: TexelObserver>(
    kind: S,
    pyramid: &'a MipPyramid,
    q: &TextureQuery,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let choice = level_choice(pyramid, q);
    let mut sum = Vec4::ZERO;
    for k in 0..2 {
        let w = choice.weights[k];
        if w == 0.0 {
            continue;
        }
        let m = choice.levels[k];
        let level = &pyramid.levels[m];
        sum += w * match kind.view(&level.texels) {
            Some(texels) => bilinear_from(level, texels, m, q.s, q.t, wrap, obs),
            None => bilinear_other_kind(level, m, q.s, q.t, wrap, kind.thread_tiles(), obs),
        };
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::super::mip_pyramid::MipLevel;
    use super::super::tiles::NoTextureTiles;
    use super::*;

    #[test]
    fn blends_two_levels_with_weights_summing_to_one() {
        // Level 0 all 1, so every level is 1: any convex blend gives exactly 1.
        let p = MipPyramid::build(MipLevel::new(64, 32, vec![[1.0; 4]; 64 * 32]).unwrap(), "t")
            .unwrap();
        for k in 0..50 {
            let d = 1e-4 * 1.3f32.powi(k);
            let q = TextureQuery {
                s: 0.3,
                t: 0.6,
                dsdx: d,
                dtdx: 0.0,
                dsdy: 0.0,
                dtdy: 0.5 * d,
            };
            let c = level_choice(&p, &q);
            assert!((c.weights[0] + c.weights[1] - 1.0).abs() < 1e-6);
            let v = sample(
                &p,
                &q,
                (WrapMode::Periodic, WrapMode::Periodic),
                ThreadTiles::none(),
                &mut NoTextureTiles,
            );
            assert!((v - Vec4::ONE).abs().max_element() < 1e-5);
        }
    }
}
