//! Deterministic sample positions: stratified pixel jitter and lens samples.
//!
//! Every sample is a pure function of (pixel, sample index, dimension), so a tile renders the
//! same whichever thread runs it and whenever it runs (a resumed render equals an
//! uninterrupted one). With one sample per pixel the sample sits at the pixel centre.

use glam::Vec2;

/// A 32-bit integer hash with good avalanche (a PCG-style output permutation).
#[inline]
fn hash_u32(mut x: u32) -> u32 {
    x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((x >> ((x >> 28) + 4)) ^ x).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A uniform number in [0, 1) for (pixel, sample, dimension).
#[inline]
pub fn uniform(pixel: u32, sample: u32, dimension: u32) -> f32 {
    let h = hash_u32(
        pixel
            ^ hash_u32(
                sample.wrapping_mul(0x9E37_79B9) ^ hash_u32(dimension.wrapping_add(0x68E3_1DA4)),
            ),
    );
    (h >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The stratification grid for `spp` samples: `columns x rows == spp` exactly, as square as
/// the divisors of `spp` allow (8 -> 2 x 4, 32 -> 4 x 8, a prime -> 1 x spp strips). Every
/// cell has the same area and receives exactly one sample, so the average is unbiased for
/// any count, not only for perfect squares.
#[inline]
fn stratification_grid(spp: u32) -> (u32, u32) {
    let mut columns = (spp as f64).sqrt().floor() as u32;
    while columns > 1 && !spp.is_multiple_of(columns) {
        columns -= 1;
    }
    let columns = columns.max(1);
    (columns, spp / columns)
}

/// The offset inside the pixel, in [0,1)^2, of sample `sample` out of `spp`:
/// the pixel centre for one sample, otherwise a jittered cell of an exact
/// `columns x rows == spp` grid (stratified sampling).
#[inline]
pub fn pixel_offset(pixel: u32, sample: u32, spp: u32) -> Vec2 {
    if spp <= 1 {
        return Vec2::splat(0.5);
    }
    let (columns, rows) = stratification_grid(spp);
    let cell_x = sample % columns;
    let cell_y = (sample / columns) % rows;
    let jx = uniform(pixel, sample, 0);
    let jy = uniform(pixel, sample, 1);
    Vec2::new(
        (cell_x as f32 + jx) / columns as f32,
        (cell_y as f32 + jy) / rows as f32,
    )
}

/// A lens sample in [0,1)^2 for thin-lens cameras.
#[inline]
pub fn lens_sample(pixel: u32, sample: u32) -> Vec2 {
    Vec2::new(uniform(pixel, sample, 2), uniform(pixel, sample, 3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_sample_is_pixel_centre() {
        assert_eq!(pixel_offset(17, 0, 1), Vec2::splat(0.5));
    }

    #[test]
    fn stratified_samples_cover_every_cell_once() {
        let spp = 16;
        let mut cells = [0u32; 16];
        for s in 0..spp {
            let o = pixel_offset(5, s, spp);
            assert!((0.0..1.0).contains(&o.x) && (0.0..1.0).contains(&o.y));
            cells[(o.y * 4.0) as usize * 4 + (o.x * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
    }

    #[test]
    fn every_sample_count_fills_its_grid_exactly_once() {
        for spp in [2u32, 3, 5, 6, 7, 8, 12, 32, 128, 1000, 1024] {
            let (columns, rows) = stratification_grid(spp);
            assert_eq!(columns * rows, spp, "{spp}");
            assert!(columns <= rows, "{spp}: {columns} x {rows}");
            let mut cells = vec![0u32; spp as usize];
            for s in 0..spp {
                let o = pixel_offset(9, s, spp);
                assert!((0.0..1.0).contains(&o.x) && (0.0..1.0).contains(&o.y));
                let cx = ((o.x * columns as f32) as u32).min(columns - 1);
                let cy = ((o.y * rows as f32) as u32).min(rows - 1);
                cells[(cy * columns + cx) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "{spp}: {cells:?}");
        }
        assert_eq!(stratification_grid(8), (2, 4));
        assert_eq!(stratification_grid(16), (4, 4));
        assert_eq!(stratification_grid(7), (1, 7));
    }

    #[test]
    fn uniform_depends_on_every_argument_and_is_spread() {
        // Pixel, sample and dimension each decorrelate the value (a hash ignoring one of them
        // would give equal numbers here), and values stay in [0, 1).
        let base = uniform(3, 4, 5);
        assert!((0.0..1.0).contains(&base), "{base}");
        for other in [uniform(4, 4, 5), uniform(3, 5, 5), uniform(3, 4, 6)] {
            assert!((0.0..1.0).contains(&other), "{other}");
            assert_ne!(base, other);
        }
        let mean: f32 = (0..10_000).map(|i| uniform(i, 0, 0)).sum::<f32>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
    }
}
