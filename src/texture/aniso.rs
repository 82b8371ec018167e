//! Anisotropic filtering: bilinear probes spaced along the ellipse's major axis on
//! the level(s) chosen from the minor axis, Gaussian-weighted (reference note,
//! step 7; seed 002, section 4 "anisotropic texture filtering").
//!
//! The probe count n = max(1, int(2 * aspect - 1)) is computed in f32 like
//! OpenImageIO's, because near whole numbers f32 and f64 disagree on it.

use glam::Vec4;

use crate::simd;

use super::aniso_lanes::{self, ProbeStep, PROBE_LANES};
use super::ellipse;
pub(crate) use super::ellipse::footprint;
use super::filter_closest_bilinear::bilinear_from;
use super::micro_cache::ThreadTiles;
use super::mip_pyramid::{MipLevel, MipPyramid};
use super::texels::{with_texel_source, TexelSource};
use super::tiles::TexelObserver;
use super::{TextureQuery, WrapMode};

/// Probe weights for up to this many probes live on the stack (limit 64).
const MAX_STACK_PROBES: usize = 127;

/// Number of probes for an (already clamped) aspect ratio.
#[inline(always)]
pub(crate) fn probe_count(aspect: f32) -> usize {
    ((2.0 * aspect - 1.0) as i32).max(1) as usize
}

/// Fills `weights` (one per probe) with exp(-2 x^2), x = p_i * gauss_scale,
/// p_i = (2i + 1) / n - 1, and returns their sum. p_{n-1-i} = -p_i, so only the first
/// half is evaluated and mirrored: half the `exp` calls. The mirrored p differs from a
/// direct evaluation by at most an ulp, far below the filter's tolerances.
#[inline]
fn symmetric_weights(weights: &mut [f32], inv_n: f32, gauss_scale: f32) -> f32 {
    let n = weights.len();
    let mut sum = 0.0f32;
    for i in 0..n.div_ceil(2) {
        let x = (2.0 * (i as f32 + 0.5) * inv_n - 1.0) * gauss_scale;
        let w = (-2.0 * x * x).exp();
        weights[i] = w;
        weights[n - 1 - i] = w;
        sum += if 2 * i + 1 == n { w } else { 2.0 * w };
    }
    sum
}

/// The anisotropic lookup (out of line for the same reason as `ewa::sample`), compiled
/// once per storage kind (that of level 0, which every level of a pyramid normally
/// shares) and, through [`simd::dispatch`], for the vector level the processor has: the
/// probe steps of [`aniso_lanes`] compile to vector instructions only there. Every level
/// gives the same bits (the lanes do the scalar probe's operations; Rust never contracts
/// to FMA). Demand-loaded levels read through `tiles`, found before the dispatch: the
/// thread-local access is out of line and compiled at the baseline level, so code inlined
/// into it would lose the vector instructions.
#[inline(never)]
pub(crate) fn sample<O: TexelObserver>(
    pyramid: &MipPyramid,
    q: &TextureQuery,
    max_aniso: f32,
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    simd::dispatch(
        #[inline(always)]
        || sample_at_level(pyramid, q, max_aniso, wrap, tiles, obs),
    )
}

/// [`sample`]'s body, inlined into the function of each vector level.
#[inline(always)]
fn sample_at_level<O: TexelObserver>(
    pyramid: &MipPyramid,
    q: &TextureQuery,
    max_aniso: f32,
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    with_texel_source!(&pyramid.levels[0].texels, tiles, |kind| sample_from(
        kind, pyramid, q, max_aniso, wrap, obs
    ))
}

/// The probes along the major axis on each level, for levels of the storage kind of
/// `kind`; a level of another kind goes through [`probes_other_kind`].
#[inline(always)]
fn sample_from<'a, S: TexelSource<'a>, O: TexelObserver>(
    kind: S,
    pyramid: &'a MipPyramid,
    q: &TextureQuery,
    max_aniso: f32,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let f = ellipse::footprint(pyramid, q, max_aniso);
    let line = ProbeLine::of(&f);
    let n = line.n;

    // Gaussian weights exp(-2 x^2), x = p * major / (2 (major - minor)), shared by
    // both levels; kept on the stack up to MAX_STACK_PROBES probes.
    let mut weights = [0.0f32; MAX_STACK_PROBES];
    let mut wsum = 0.0f32;
    if (3..=MAX_STACK_PROBES).contains(&n) {
        wsum = symmetric_weights(&mut weights[..n], line.inv_n, line.gauss_scale);
    }
    let weights = (&weights[..], wsum);

    let mut sum = Vec4::ZERO;
    for k in 0..2 {
        let level_weight = f.levels.weights[k];
        if level_weight == 0.0 {
            continue;
        }
        let m = f.levels.levels[k];
        let level = &pyramid.levels[m];
        let level_sum = match kind.view(&level.texels) {
            Some(texels) => probes(level, texels, m, q, &line, weights, wrap, obs),
            None => probes_other_kind(level, m, q, &line, weights, wrap, kind.thread_tiles(), obs),
        };
        sum += level_weight * level_sum;
    }
    sum
}

/// Where the probes of one lookup sit: `n` probes at (s, t) + p (ds, dt), p in [-1, 1],
/// Gaussian scale `gauss_scale`.
#[derive(Clone, Copy)]
struct ProbeLine {
    n: usize,
    ds: f32,
    dt: f32,
    inv_n: f32,
    gauss_scale: f32,
}

impl ProbeLine {
    /// The probes of the footprint `f`: offsets p in [-1, 1] map to half the distance
    /// between the ellipse's end-circle centres, (major - minor) / 2, on either side of
    /// (s, t).
    #[inline(always)]
    fn of(f: &ellipse::Footprint) -> ProbeLine {
        let n = probe_count(f.aspect);
        // One probe sits at (s, t): the axis direction is not needed.
        let (sin, cos) = if n > 1 {
            f.axes.direction()
        } else {
            (0.0, 1.0)
        };
        let ll = 2.0 * (f.axes.major - f.axes.minor);
        ProbeLine {
            n,
            ds: cos * ll * 0.5,
            dt: sin * ll * 0.5,
            inv_n: 1.0 / n as f32,
            gauss_scale: f.axes.major / ll,
        }
    }
}

/// Weighted average of the probes of `line` on one level, reading `texels` (the level's
/// own); `weights` are the stacked Gaussian weights and their sum when 3 <= n <=
/// MAX_STACK_PROBES.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn probes<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    m: usize,
    q: &TextureQuery,
    line: &ProbeLine,
    (weights, wsum): (&[f32], f32),
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
) -> Vec4 {
    let ProbeLine {
        n,
        ds,
        dt,
        inv_n,
        gauss_scale,
    } = *line;
    match n {
        1 => bilinear_from(level, texels, m, q.s, q.t, wrap, obs),
        2 => {
            let a = bilinear_from(level, texels, m, q.s - 0.5 * ds, q.t - 0.5 * dt, wrap, obs);
            let b = bilinear_from(level, texels, m, q.s + 0.5 * ds, q.t + 0.5 * dt, wrap, obs);
            0.5 * a + 0.5 * b
        }
        _ if n <= MAX_STACK_PROBES => {
            // The sum is a local of this loop, not of a closure the probes are handed to:
            // captured by reference, it was kept in memory, and every probe waited for the
            // previous one's store.
            let mut acc = Vec4::ZERO;
            let addressable = aniso_lanes::addressable(level);
            for first in (0..n).step_by(PROBE_LANES) {
                let (values, count) =
                    probe_step(level, texels, addressable, m, q, line, wrap, obs, first);
                for (w, v) in weights[first..first + count].iter().zip(&values) {
                    acc += *w * *v;
                }
            }
            acc / wsum
        }
        _ => {
            // Very high anisotropy limits: weights computed on the fly.
            let mut acc = Vec4::ZERO;
            let mut wsum = 0.0f32;
            let addressable = aniso_lanes::addressable(level);
            for first in (0..n).step_by(PROBE_LANES) {
                let (values, count) =
                    probe_step(level, texels, addressable, m, q, line, wrap, obs, first);
                for (lane, v) in values[..count].iter().enumerate() {
                    let p = 2.0 * ((first + lane) as f32 + 0.5) * inv_n - 1.0;
                    let x = p * gauss_scale;
                    let w = (-2.0 * x * x).exp();
                    wsum += w;
                    acc += w * *v;
                }
            }
            acc / wsum
        }
    }
}

/// The bilinear values of probes `first..first + count` of `line` on one level (count =
/// [`PROBE_LANES`], or fewer at the end of the line), which the caller sums in probe order
/// (the order that gives the same bits). An [`aniso_lanes::addressable`] level's probes are
/// addressed together by [`aniso_lanes::probe_blocks`], wrapped blocks and blocks across
/// tile edges included, and read by the level's texels ([`TexelSource::block_values`]: a
/// resident level from its buffer, a demand-loaded one with one fetch per tile the step's
/// blocks lie in). A probe they leave (more than a period outside a repeating level whose
/// side is not a power of two, 2^22 texels away, or on a demand-loaded level across a tile
/// edge) goes through [`bilinear_from`]. Observers are told of the same texels in the same
/// order either way.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn probe_step<'a, S: TexelSource<'a>, O: TexelObserver>(
    level: &'a MipLevel,
    texels: S,
    addressable: bool,
    m: usize,
    q: &TextureQuery,
    line: &ProbeLine,
    wrap: (WrapMode, WrapMode),
    obs: &mut O,
    first: usize,
) -> ([Vec4; PROBE_LANES], usize) {
    let count = PROBE_LANES.min(line.n - first);
    let scalar = |i: usize, obs: &mut O| {
        let p = 2.0 * (i as f32 + 0.5) * line.inv_n - 1.0;
        bilinear_from(
            level,
            texels,
            m,
            q.s + p * line.ds,
            q.t + p * line.dt,
            wrap,
            obs,
        )
    };
    let mut values = [Vec4::ZERO; PROBE_LANES];
    if !addressable {
        for (lane, value) in values[..count].iter_mut().enumerate() {
            *value = scalar(first + lane, obs);
        }
        return (values, count);
    }
    let step = ProbeStep {
        first,
        count: line.n,
        s: q.s,
        t: q.t,
        ds: line.ds,
        dt: line.dt,
        inv_n: line.inv_n,
    };
    let blocks = aniso_lanes::probe_blocks(level, texels.lane_buffer_len(), &step, wrap);
    let (block_values, served) = texels.block_values(&blocks);
    for (lane, value) in values[..count].iter_mut().enumerate() {
        *value = if served[lane] {
            blocks.touch_texels_read(lane, m, obs);
            block_values[lane]
        } else {
            scalar(first + lane, obs)
        };
    }
    (values, count)
}

/// [`probes`] for the rare level whose storage kind differs from level 0's.
#[allow(clippy::too_many_arguments)]
#[cold]
#[inline(never)]
fn probes_other_kind<O: TexelObserver>(
    level: &MipLevel,
    m: usize,
    q: &TextureQuery,
    line: &ProbeLine,
    weights: (&[f32], f32),
    wrap: (WrapMode, WrapMode),
    tiles: ThreadTiles<'_>,
    obs: &mut O,
) -> Vec4 {
    with_texel_source!(&level.texels, tiles, |texels| probes(
        level, texels, m, q, line, weights, wrap, obs
    ))
}

#[cfg(test)]
mod tests {
    use super::super::mip_pyramid::MipLevel;
    use super::super::tiles::NoTextureTiles;
    use super::*;

    #[test]
    fn probe_counts() {
        assert_eq!(probe_count(1.0), 1);
        assert_eq!(probe_count(1.4), 1);
        assert_eq!(probe_count(1.5), 2);
        assert_eq!(probe_count(16.0), 31);
        assert_eq!(probe_count(15.999), 30);
    }

    #[test]
    fn mirrored_weights_equal_direct_evaluation() {
        for n in [3usize, 4, 7, 30, 31, 127] {
            for gauss_scale in [0.52f32, 0.75, 1.0] {
                let inv_n = 1.0 / n as f32;
                let mut w = vec![0.0f32; n];
                let sum = symmetric_weights(&mut w, inv_n, gauss_scale);
                let mut direct_sum = 0.0f32;
                for (i, wi) in w.iter().enumerate() {
                    let x = (2.0 * (i as f32 + 0.5) * inv_n - 1.0) * gauss_scale;
                    let direct = (-2.0 * x * x).exp();
                    direct_sum += direct;
                    assert!(
                        (wi - direct).abs() <= 1e-6 * direct,
                        "{n} {i}: {wi} vs {direct}"
                    );
                }
                assert!(
                    (sum - direct_sum).abs() <= 1e-5 * direct_sum,
                    "{n}: {sum} vs {direct_sum}"
                );
            }
        }
    }

    #[test]
    fn weights_sum_to_one_on_constant_texture() {
        let p = MipPyramid::build(
            MipLevel::new(128, 96, vec![[0.7; 4]; 128 * 96]).unwrap(),
            "t",
        )
        .unwrap();
        for k in 0..64 {
            let angle = k as f32 * 0.37;
            let major = 0.002 * (1.0 + k as f32);
            let q = TextureQuery {
                s: 0.1 * k as f32,
                t: -0.05 * k as f32,
                dsdx: major * angle.cos(),
                dtdx: major * angle.sin(),
                dsdy: -0.001 * angle.sin(),
                dtdy: 0.001 * angle.cos(),
            };
            let v = sample(
                &p,
                &q,
                16.0,
                (WrapMode::Periodic, WrapMode::Mirror),
                ThreadTiles::none(),
                &mut NoTextureTiles,
            );
            assert!(
                (v - Vec4::splat(0.7)).abs().max_element() < 1e-5,
                "{k}: {v}"
            );
        }
    }

    #[test]
    fn stretched_footprint_averages_stripes_along_the_major_axis() {
        // Vertical stripes 0/1 one texel wide: a footprint long along s averages them,
        // one long along t does not.
        let texels = (0..64 * 64)
            .map(|i| [(i % 2) as f32, 0.0, 0.0, 1.0])
            .collect();
        let p = MipPyramid::build(MipLevel::new(64, 64, texels).unwrap(), "t").unwrap();
        let centre = 1.5 / 64.0; // centre of column 1 (value 1)
        let along_s = TextureQuery {
            s: centre,
            t: 0.5,
            dsdx: 16.0 / 64.0,
            dtdx: 0.0,
            dsdy: 0.0,
            dtdy: 1.0 / 64.0,
        };
        let along_t = TextureQuery {
            dsdx: 0.0,
            dtdx: 16.0 / 64.0,
            dsdy: 0.25 / 64.0,
            dtdy: 0.0,
            ..along_s
        };
        let wrap = (WrapMode::Periodic, WrapMode::Periodic);
        let a = sample(
            &p,
            &along_s,
            16.0,
            wrap,
            ThreadTiles::none(),
            &mut NoTextureTiles,
        )
        .x;
        let b = sample(
            &p,
            &along_t,
            16.0,
            wrap,
            ThreadTiles::none(),
            &mut NoTextureTiles,
        )
        .x;
        assert!((a - 0.5).abs() < 0.1, "{a}");
        assert!(b > 0.9, "{b}");
    }

    /// Records every texel a lookup reads, in order.
    #[derive(Default)]
    struct TouchLog(Vec<(usize, usize, usize)>);

    impl TexelObserver for TouchLog {
        fn touch(&mut self, level: usize, x: usize, y: usize) {
            self.0.push((level, x, y));
        }
    }

    /// An sRGB 8-bit pyramid of random texels and the same pyramid stored as f32 (the
    /// decoded values, exact): the f32 one always takes the scalar probe path.
    fn byte_and_float_pyramids(w: u32, h: u32, seed: u32) -> (MipPyramid, MipPyramid) {
        let mut state = seed;
        let bytes = (0..w * h)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                state.to_le_bytes()
            })
            .collect();
        let texels = super::super::texels::Texels::bytes(bytes, crate::texture::ColorSpace::Srgb);
        let base = MipLevel::with_texels(w, h, texels).unwrap();
        let bytes = MipPyramid::build(base, "t").unwrap();
        let levels = bytes
            .levels
            .iter()
            .map(|l| MipLevel::new(l.width, l.height, l.to_rgba_f32()).unwrap())
            .collect();
        (bytes, MipPyramid { levels })
    }

    /// A query of `n` probes (with `max_aniso` >= its aspect) at a random place and angle,
    /// part of them across the level's edges.
    fn query_with_probes(n: usize, minor: f32, random: &mut impl FnMut() -> f32) -> TextureQuery {
        let aspect = (n as f32 + 1.0) / 2.0 + 0.25;
        let (major, angle) = (minor * aspect, random() * std::f32::consts::TAU);
        TextureQuery {
            s: -0.2 + 1.4 * random(),
            t: -0.2 + 1.4 * random(),
            dsdx: major * angle.cos(),
            dtdx: major * angle.sin(),
            dsdy: -minor * angle.sin(),
            dtdy: minor * angle.cos(),
        }
    }

    /// `float` stored as halves (the values of the tests' pyramids are bytes / 255 or
    /// their sRGB decoding, which round to halves; the probes compare with themselves).
    fn half_pyramid(float: &MipPyramid) -> MipPyramid {
        let levels = float
            .levels
            .iter()
            .map(|l| MipLevel {
                texels: super::super::texels::Texels::Half(vec![])
                    .same_kind_from(&l.to_rgba_f32(), "t")
                    .unwrap(),
                ..l.clone()
            })
            .collect();
        MipPyramid { levels }
    }

    /// On every level of `pyramid` the probes of `q` read by [`probe_step`] at every vector
    /// level have the bits and the texel reads of `bilinear_from` at each probe's position.
    fn probes_match_the_scalar_probe(
        pyramid: &MipPyramid,
        q: &TextureQuery,
        wrap: (WrapMode, WrapMode),
    ) {
        let f = footprint(pyramid, q, 1024.0);
        let line = ProbeLine::of(&f);
        let n = line.n;
        for (m, level) in pyramid.levels.iter().enumerate().step_by(2) {
            with_texel_source!(&level.texels, ThreadTiles::none(), |texels| {
                let mut scalar_log = TouchLog::default();
                let scalar: Vec<u32> = (0..n)
                    .flat_map(|i| {
                        let p = 2.0 * (i as f32 + 0.5) * line.inv_n - 1.0;
                        let (s, t) = (q.s + p * line.ds, q.t + p * line.dt);
                        bilinear_from(level, texels, m, s, t, wrap, &mut scalar_log)
                            .to_array()
                            .map(f32::to_bits)
                    })
                    .collect();
                for vector_level in crate::simd::Level::supported() {
                    let mut log = TouchLog::default();
                    let mut lanes = Vec::new();
                    crate::simd::run_at(
                        vector_level,
                        #[inline(always)]
                        || {
                            let addressable = aniso_lanes::addressable(level);
                            for first in (0..n).step_by(PROBE_LANES) {
                                let (values, count) = probe_step(
                                    level,
                                    texels,
                                    addressable,
                                    m,
                                    q,
                                    &line,
                                    wrap,
                                    &mut log,
                                    first,
                                );
                                assert_eq!(count, PROBE_LANES.min(n - first));
                                for v in &values[..count] {
                                    lanes.extend(v.to_array().map(f32::to_bits));
                                }
                            }
                        },
                    );
                    assert_eq!(lanes, scalar, "{vector_level:?} level {m} n {n} {q:?}");
                    assert!(
                        log.0 == scalar_log.0,
                        "{vector_level:?} level {m}: reads differ"
                    );
                }
            });
        }
    }

    /// The probe steps in lanes give the bits and the texel reads of the scalar probe
    /// (`bilinear_from` at each probe's position) on 8-bit, half and f32 levels, at every
    /// vector level, for every probe count from 1 to past MAX_STACK_PROBES, inside the level
    /// and across its edges and tile edges; whole lookups agree across the kinds holding the
    /// same values.
    #[test]
    fn every_supported_level_gives_the_scalar_probe_bits() {
        let mut state = 7u32;
        let mut random = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut counts = std::collections::BTreeSet::new();
        for (w, h) in [(150, 70), (13, 7), (256, 256)] {
            let (bytes, float) = byte_and_float_pyramids(w, h, w * h);
            let half = half_pyramid(&float);
            for n in (1..=140).chain([200, 257]) {
                for (minor, wrap) in [
                    (0.4 / w as f32, (WrapMode::Periodic, WrapMode::Periodic)),
                    (3.0 / w as f32, (WrapMode::Black, WrapMode::Clamp)),
                    (0.02, (WrapMode::Mirror, WrapMode::Periodic)),
                ] {
                    let q = query_with_probes(n, minor, &mut random);
                    counts.insert(probe_count(footprint(&bytes, &q, 1024.0).aspect));
                    for pyramid in [&bytes, &float, &half] {
                        probes_match_the_scalar_probe(pyramid, &q, wrap);
                    }
                    let none = ThreadTiles::none();
                    let mut float_log = TouchLog::default();
                    let float_value = sample(&float, &q, 1024.0, wrap, none, &mut float_log);
                    for level in crate::simd::Level::supported() {
                        let mut log = TouchLog::default();
                        let lanes = crate::simd::run_at(
                            level,
                            #[inline(always)]
                            || sample_at_level(&bytes, &q, 1024.0, wrap, none, &mut log),
                        );
                        assert_eq!(
                            lanes.to_array().map(f32::to_bits),
                            float_value.to_array().map(f32::to_bits),
                            "{level:?} {w}x{h} n {n} {q:?}"
                        );
                        assert!(
                            log.0 == float_log.0,
                            "{level:?} {w}x{h} n {n}: reads differ"
                        );
                    }
                }
            }
        }
        for n in (1..=130).chain([200]) {
            assert!(counts.contains(&n), "no query of {n} probes");
        }
    }
}
