//! One texture read at many places at once, as the shading lanes read a material's texture
//! for all their hits: the filter and the level's storage kind are chosen once per batch,
//! not once per lookup, and the bilinear filter's loop is compiled for the processor's
//! vector level. Every result has the bits of [`Texture::sample`] for its query.

use glam::Vec4;

use crate::simd;

use super::aniso_lanes::{self, lanes, Lanes, PROBE_LANES};
use super::filter_closest_bilinear::bilinear_from;
use super::micro_cache::ThreadTiles;
use super::mip_pyramid::MipLevel;
use super::texels::{with_texel_source, ByteTexels, FlatTexels, TexelSource};
use super::tiles::{NoTextureTiles, TexelObserver, TextureTileRecorder};
use super::{wrap, FilterMode, FilterOptions, Texture, TextureQuery, TextureTileSet, WrapMode};

impl Texture {
    /// [`Texture::sample`] of each of `queries`, into `out` (of the same length); with
    /// `tiles`, the tiles read are recorded as [`Texture::sample_recording`] records them.
    pub fn sample_batch(
        &self,
        queries: &[TextureQuery],
        opts: &FilterOptions,
        tiles: Option<&mut TextureTileSet>,
        out: &mut [Vec4],
    ) {
        self.batch_at(simd::active(), queries, opts, tiles, out);
    }

    /// [`Texture::sample_batch`] with its loop compiled for `level` (the tests run each).
    fn batch_at(
        &self,
        level: simd::Level,
        queries: &[TextureQuery],
        opts: &FilterOptions,
        tiles: Option<&mut TextureTileSet>,
        out: &mut [Vec4],
    ) {
        assert_eq!(queries.len(), out.len(), "one result per query");
        match tiles {
            Some(tiles) => {
                let mut recorder = TextureTileRecorder::new(self.id, tiles);
                self.batch_observed(level, queries, opts, &mut recorder, out);
            }
            None => self.batch_observed(level, queries, opts, &mut NoTextureTiles, out),
        }
    }

    /// [`Texture::batch_at`] told to `obs`, one lookup after the other, the thread's
    /// micro-cache found once for the batch.
    fn batch_observed<O: TexelObserver>(
        &self,
        vector_level: simd::Level,
        queries: &[TextureQuery],
        opts: &FilterOptions,
        obs: &mut O,
        out: &mut [Vec4],
    ) {
        self.with_lookup_tiles(|tiles| self.batch_in(vector_level, queries, opts, tiles, obs, out))
    }

    /// [`Texture::batch_observed`] with the tiles fetched through `tiles`.
    fn batch_in<O: TexelObserver>(
        &self,
        vector_level: simd::Level,
        queries: &[TextureQuery],
        opts: &FilterOptions,
        tiles: ThreadTiles<'_>,
        obs: &mut O,
        out: &mut [Vec4],
    ) {
        if opts.filter != FilterMode::Bilinear {
            for (q, texel) in queries.iter().zip(out) {
                obs.begin_lookup();
                *texel = self.sample_in(q, opts, Some(tiles), obs);
            }
            return;
        }
        // `sample_in`'s bilinear case, with the storage kind matched once.
        let level = &self.pyramid.levels[0];
        let wrap = (opts.wrap_s, opts.wrap_t);
        simd::run_at(
            vector_level,
            #[inline(always)]
            || {
                with_texel_source!(&level.texels, tiles, |texels| {
                    match TexelSource::as_byte_texels(texels) {
                        Some(bytes) if aniso_lanes::addressable(level) => {
                            byte_bilinear_lanes(level, texels, bytes, queries, wrap, obs, out)
                        }
                        _ => {
                            for (q, texel) in queries.iter().zip(out.iter_mut()) {
                                obs.begin_lookup();
                                let s = wrap::reduce_coordinate(q.s, wrap.0);
                                let t = wrap::reduce_coordinate(q.t, wrap.1);
                                *texel = bilinear_from(level, texels, 0, s, t, wrap, obs);
                            }
                        }
                    }
                })
            },
        )
    }
}

/// The bilinear lookups of a resident 8-bit level, [`PROBE_LANES`] queries at a time:
/// positions, wraps and tile addresses in lanes (`aniso_lanes::blocks`), each value
/// read and blended on its own, and a lookup the lanes cannot address (far outside a level
/// that repeats and is not a power of two wide) by [`bilinear_from`].
#[inline(always)]
fn byte_bilinear_lanes<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    bytes: ByteTexels,
    queries: &[TextureQuery],
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
    out: &mut [Vec4],
) {
    let (w, h) = (level.width as f32, level.height as f32);
    for (chunk, texels_out) in queries.chunks(PROBE_LANES).zip(out.chunks_mut(PROBE_LANES)) {
        // A short last chunk repeats its last query in the lanes it does not use.
        let query = |l: usize| &chunk[l.min(chunk.len() - 1)];
        let s: Lanes<f32> = lanes(|l| wrap::reduce_coordinate(query(l).s, wrap.0));
        let t: Lanes<f32> = lanes(|l| wrap::reduce_coordinate(query(l).t, wrap.1));
        let x = lanes(|l| s[l] * w - 0.5);
        let y = lanes(|l| t[l] * h - 0.5);
        let blocks = aniso_lanes::blocks(level, bytes.len(), x, y, chunk.len(), wrap);
        for (l, texel) in texels_out.iter_mut().enumerate() {
            obs.begin_lookup();
            *texel = if blocks.served(l) {
                blocks.touch_texels_read(l, 0, obs);
                blocks.value(bytes, l)
            } else {
                bilinear_from(level, texels, 0, s[l], t[l], wrap, obs)
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::*;
    use crate::texture::ColorSpace;

    /// Pseudo-random numbers in [0, 1).
    fn uniforms(seed: u32) -> impl FnMut() -> f32 {
        let mut x = seed;
        move || {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (x >> 8) as f32 / (1u32 << 24) as f32
        }
    }

    /// An 8-bit noise texture of `w` x `h` texels, through a PNG as a file would be read.
    fn byte_texture(w: u32, h: u32, colour: ColorSpace) -> Texture {
        let mut u = uniforms(w * 31 + h);
        let image = image::RgbaImage::from_fn(w, h, |_, _| {
            image::Rgba(std::array::from_fn(|_| (u() * 256.0) as u8))
        });
        let mut png = Vec::new();
        image
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        Texture::from_encoded(&png, "noise.png", colour).unwrap()
    }

    fn float_texture(w: u32, h: u32) -> Texture {
        let mut u = uniforms(7);
        let texels = (0..w * h).map(|_| std::array::from_fn(|_| u())).collect();
        Texture::from_rgba_f32(w, h, texels).unwrap()
    }

    /// Places all over and around the texture (texel centres and edges, whole numbers,
    /// far outside), with small and large gradients, in a count that leaves a short last
    /// chunk of lanes.
    fn queries(w: u32, h: u32) -> Vec<TextureQuery> {
        let mut u = uniforms(99);
        let mut places: Vec<(f32, f32)> = (0..600)
            .map(|_| (u() * 5.0 - 2.0, u() * 5.0 - 2.0))
            .collect();
        for k in [0.0, 0.5, 1.0, 63.5, 64.0, 64.5, w as f32 - 0.5, w as f32] {
            places.push((k / w as f32, k / h as f32));
            places.push((-k / w as f32, 1.0 - k / h as f32));
        }
        places.extend([
            (0.0, 0.0),
            (1.0, 1.0),
            (-1.0, 2.0),
            (1.0e6, -3.5),
            (f32::NAN, 0.5),
        ]);
        places
            .into_iter()
            .map(|(s, t)| {
                let scale = 10f32.powf(-4.0 + 4.0 * u());
                TextureQuery {
                    s,
                    t,
                    dsdx: scale * (u() - 0.5),
                    dtdx: scale * (u() - 0.5),
                    dsdy: scale * (u() - 0.5),
                    dtdy: scale * (u() - 0.5),
                }
            })
            .collect()
    }

    const WRAPS: [WrapMode; 4] = [
        WrapMode::Periodic,
        WrapMode::Clamp,
        WrapMode::Black,
        WrapMode::Mirror,
    ];

    fn textures() -> Vec<Texture> {
        vec![
            // Partial tiles on both axes: blocks across tile edges take the scalar path.
            byte_texture(130, 70, ColorSpace::Srgb),
            byte_texture(64, 64, ColorSpace::Linear),
            byte_texture(3, 2, ColorSpace::Srgb),
            float_texture(23, 16),
        ]
    }

    #[test]
    fn a_batch_gives_every_lookup_the_bits_of_a_single_lookup_at_every_vector_level() {
        for texture in textures() {
            let queries = queries(texture.width(), texture.height());
            for filter in FilterMode::ALL {
                for (k, &wrap_s) in WRAPS.iter().enumerate() {
                    let opts = FilterOptions {
                        filter,
                        wrap_s,
                        wrap_t: WRAPS[(k + 1) % WRAPS.len()],
                        max_aniso: 8.0,
                    };
                    let single: Vec<Vec4> =
                        queries.iter().map(|q| texture.sample(q, &opts)).collect();
                    for level in simd::Level::supported() {
                        let mut batch = vec![Vec4::splat(-1.0); queries.len()];
                        texture.batch_at(level, &queries, &opts, None, &mut batch);
                        for (i, (a, b)) in single.iter().zip(&batch).enumerate() {
                            let bits = |v: &Vec4| v.to_array().map(f32::to_bits);
                            assert_eq!(
                                bits(a),
                                bits(b),
                                "{} {filter:?} {opts:?} {level:?} query {i} {:?}: {a} vs {b}",
                                texture.label(),
                                queries[i]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_recording_batch_records_the_tiles_and_touches_of_single_lookups() {
        for texture in textures() {
            let queries = queries(texture.width(), texture.height());
            for filter in FilterMode::ALL {
                let opts = FilterOptions {
                    filter,
                    ..FilterOptions::default()
                };
                let mut single = TextureTileSet::new();
                for q in &queries {
                    texture.sample_recording(q, &opts, &mut single);
                }
                let mut batch = TextureTileSet::new();
                let mut out = vec![Vec4::ZERO; queries.len()];
                texture.sample_batch(&queries, &opts, Some(&mut batch), &mut out);
                assert!(single.count() > 0);
                assert_eq!(
                    (single.count(), single.touches(), single.count_per_level()),
                    (batch.count(), batch.touches(), batch.count_per_level()),
                    "{} {filter:?}",
                    texture.label()
                );
            }
        }
    }
}
