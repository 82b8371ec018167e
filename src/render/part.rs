//! One part of a render split across machines: a region of the image and a range of sample
//! indices, and the cost-balanced split behind `--part i/N`.
//!
//! A part renders the work tiles of the whole image that meet its region, whole, with the
//! sample indices of its range, and keeps the region's pixels. Samples are a pure function
//! of (pixel, sample index, dimension) (`render::sampling`), and every pixel is traced in
//! the same work tile, with the same ray packets, as in the whole render, so a part computes
//! exactly the values the whole render computes for its pixels and samples, whatever its
//! edges. Colour is accumulated in exact fixed-point sums
//! (`film::sample_sum`); a part holding only some samples stores those sums, so parts add up
//! to the whole render's bits (`conetrace merge`).
//!
//! `--part i/N` splits the image into N horizontal strips of whole tile rows with about equal
//! work. Work is estimated before rendering from a quick, low-resolution probe: one sample
//! of one pixel in every 8x8 block, traced by the integrator, costed by what it traced (rays,
//! texture lookups, shadow-walk queries). Counts, not clock times, so every machine computes
//! the same split.

use std::ops::Range;

use rayon::prelude::*;

use crate::film::{Layer, PixelRect, TileImage};
use crate::render::context::{RenderContext, RenderOptions, WorkerState};
use crate::render::{film_layers, Integrator, WORK_TILE_SIZE};

/// Probe one pixel in every `PROBE_STRIDE` x `PROBE_STRIDE` block for the cost estimate.
pub const PROBE_STRIDE: u32 = 8;

/// What one machine renders: a region (image coordinates) and a range of sample indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderPart {
    pub region: PixelRect,
    pub samples: Range<u32>,
}

impl RenderPart {
    /// The whole render: every pixel, every sample.
    pub fn whole(options: &RenderOptions) -> RenderPart {
        RenderPart {
            region: PixelRect {
                x0: 0,
                y0: 0,
                width: options.width,
                height: options.height,
            },
            samples: 0..options.spp.max(1),
        }
    }

    /// True when the part holds only some of the render's samples.
    pub fn is_sample_range(&self, options: &RenderOptions) -> bool {
        self.samples != (0..options.spp.max(1))
    }

    /// The layers of the part's film: the render's, plus the exact sample sums when it holds
    /// only some samples.
    pub fn film_layers(&self, options: &RenderOptions) -> Vec<Layer> {
        let mut layers = film_layers(options.aovs);
        if self.is_sample_range(options) {
            layers.push(Layer::SampleSum);
        }
        layers
    }

    /// The smallest rectangle of whole work tiles (clipped to the `width` x `height` image)
    /// that holds the region: what the render traces before keeping the region's pixels.
    pub fn covering_region(&self, width: u32, height: u32) -> PixelRect {
        let r = &self.region;
        let x0 = r.x0 / WORK_TILE_SIZE * WORK_TILE_SIZE;
        let y0 = r.y0 / WORK_TILE_SIZE * WORK_TILE_SIZE;
        let x1 = (r.x0 + r.width).next_multiple_of(WORK_TILE_SIZE).min(width);
        let y1 = (r.y0 + r.height)
            .next_multiple_of(WORK_TILE_SIZE)
            .min(height);
        PixelRect {
            x0,
            y0,
            width: x1 - x0,
            height: y1 - y0,
        }
    }

    /// The whole image's work tiles that meet the region, whole, in row-major order: the
    /// tiles the render traces, indexed as [`RenderPart::tiles`] is.
    pub fn traced_tiles(&self, width: u32, height: u32) -> Vec<PixelRect> {
        crate::render::work_tiles(width, height)
            .into_iter()
            .filter(|tile| tile.intersection(&self.region).is_some())
            .collect()
    }

    /// The whole image's work tiles that meet the region, clipped to it, in row-major order:
    /// the pixels each traced tile contributes to the part.
    pub fn tiles(&self, width: u32, height: u32) -> Vec<PixelRect> {
        crate::render::work_tiles(width, height)
            .into_iter()
            .filter_map(|tile| tile.intersection(&self.region))
            .collect()
    }
}

/// Why `--part` could not be honoured.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PartError {
    #[error("--part {text:?}: expected i/N with 0 <= i < N (e.g. 0/4)")]
    Syntax { text: String },
    #[error("--part {index}/{count}: the image has only {rows} rows of {WORK_TILE_SIZE}-pixel tiles; combine fewer parts with --samples")]
    TooManyParts { index: u32, count: u32, rows: u32 },
}

/// Parses `i/N`.
pub fn parse_part(text: &str) -> Result<(u32, u32), PartError> {
    let syntax = || PartError::Syntax {
        text: text.to_string(),
    };
    let (i, n) = text.split_once('/').ok_or_else(syntax)?;
    let i: u32 = i.trim().parse().map_err(|_| syntax())?;
    let n: u32 = n.trim().parse().map_err(|_| syntax())?;
    if n == 0 || i >= n {
        return Err(syntax());
    }
    Ok((i, n))
}

/// The estimated cost of each row of work tiles (top to bottom), from the probe described
/// in the module doc. Deterministic: counts of traced work, independent of threads.
pub fn estimate_tile_row_costs<I: Integrator>(context: &RenderContext, integrator: &I) -> Vec<u64> {
    let (width, height) = (context.options.width, context.options.height);
    let rows: Vec<u32> = (0..height.div_ceil(WORK_TILE_SIZE)).collect();
    rows.par_iter()
        .map(|&row| {
            crate::embree::enable_flush_denormals();
            let mut worker = WorkerState::default();
            let mut state = integrator.thread_state(context);
            let y_end = ((row + 1) * WORK_TILE_SIZE).min(height);
            for y in (row * WORK_TILE_SIZE..y_end).step_by(PROBE_STRIDE as usize) {
                let py = (y + PROBE_STRIDE / 2).min(y_end - 1);
                for x in (0..width).step_by(PROBE_STRIDE as usize) {
                    let px = (x + PROBE_STRIDE / 2).min(width - 1);
                    let probe = PixelRect {
                        x0: px,
                        y0: py,
                        width: 1,
                        height: 1,
                    };
                    let mut image = TileImage::new(probe, Default::default());
                    image.samples = Some(0..1);
                    integrator.render_tile(
                        context,
                        probe,
                        &mut image,
                        &mut worker,
                        &mut state,
                        None,
                    );
                }
            }
            let c = &worker.counters;
            c.total_rays() + c.texture_lookups + c.shadow_walk_queries
        })
        .collect()
}

/// Part `index` of `count` horizontal strips of whole tile rows with about equal summed
/// `row_costs` (one per tile row), for a `width` x `height` image; every part gets at least
/// one row. Strip `k` ends at the first row where the running cost reaches `k/N` of the total
/// (or the row before, whichever is nearer).
pub fn balanced_strip(
    row_costs: &[u64],
    index: u32,
    count: u32,
    width: u32,
    height: u32,
) -> Result<PixelRect, PartError> {
    let rows = row_costs.len() as u32;
    if count > rows {
        return Err(PartError::TooManyParts { index, count, rows });
    }
    // Every row costs at least 1, so empty rows still spread between parts.
    let costs: Vec<u128> = row_costs.iter().map(|&c| u128::from(c.max(1))).collect();
    let mut running = vec![0u128; costs.len() + 1];
    for (i, c) in costs.iter().enumerate() {
        running[i + 1] = running[i] + c;
    }
    let total = running[costs.len()];
    let mut bounds = vec![0u32];
    for k in 1..count {
        let target = total * u128::from(k) / u128::from(count);
        let mut b = running.partition_point(|&r| r < target) as u32;
        if b > 0 && target - running[b as usize - 1] < running[b as usize] - target {
            b -= 1;
        }
        let low = bounds[k as usize - 1] + 1;
        let high = rows - (count - k);
        bounds.push(b.clamp(low, high));
    }
    bounds.push(rows);
    let y0 = bounds[index as usize] * WORK_TILE_SIZE;
    let y1 = (bounds[index as usize + 1] * WORK_TILE_SIZE).min(height);
    Ok(PixelRect {
        x0: 0,
        y0,
        width,
        height: y1 - y0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_covering_region_is_the_work_tiles_a_region_meets() {
        let part = |x0, y0, width, height| RenderPart {
            region: PixelRect {
                x0,
                y0,
                width,
                height,
            },
            samples: 0..1,
        };
        let rect = |r: PixelRect| (r.x0, r.y0, r.width, r.height);
        // 10..100 x 10..100 of a 120x110 image: tiles 0..112 across, 0..110 down (the edge).
        let odd = part(10, 10, 90, 90);
        assert_eq!(rect(odd.covering_region(120, 110)), (0, 0, 112, 110));
        assert_eq!(odd.tiles(120, 110).len(), 7 * 7);
        assert_eq!(rect(odd.tiles(120, 110)[0]), (10, 10, 6, 6));
        // A region on the grid covers itself.
        let aligned = part(16, 32, 32, 16);
        assert_eq!(rect(aligned.covering_region(120, 110)), (16, 32, 32, 16));
        // One pixel inside one tile.
        assert_eq!(
            rect(part(17, 18, 1, 1).covering_region(120, 110)),
            (16, 16, 16, 16)
        );
    }

    #[test]
    fn strips_cover_the_image_once_and_follow_the_cost() {
        // A cheap top and an expensive bottom: the split is not by area.
        let costs = [1u64, 1, 1, 1, 1, 1, 10, 10];
        let (width, height) = (40, 8 * WORK_TILE_SIZE - 5);
        let strips: Vec<PixelRect> = (0..3)
            .map(|i| balanced_strip(&costs, i, 3, width, height).unwrap())
            .collect();
        assert_eq!(strips[0].y0, 0);
        for pair in strips.windows(2) {
            assert_eq!(pair[0].y0 + pair[0].height, pair[1].y0);
        }
        let last = strips[2];
        assert_eq!(last.y0 + last.height, height);
        // The first strip takes the six cheap rows, the other two one expensive row each.
        assert_eq!(strips[0].height, 6 * WORK_TILE_SIZE, "{strips:?}");
        assert!(balanced_strip(&costs, 0, 9, width, height).is_err());
        // Every part gets a row even when all the cost is in one.
        let skewed = [0u64, 0, 0, 1000];
        let strips: Vec<PixelRect> = (0..4)
            .map(|i| balanced_strip(&skewed, i, 4, 16, 64).unwrap())
            .collect();
        assert!(
            strips.iter().all(|s| s.height == WORK_TILE_SIZE),
            "{strips:?}"
        );
    }

    #[test]
    fn parts_parse() {
        assert_eq!(parse_part("2/4"), Ok((2, 4)));
        for bad in ["4/4", "1/0", "1", "a/b"] {
            assert!(parse_part(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn tiles_of_a_region_are_the_whole_images_tiles_clipped() {
        let part = RenderPart {
            region: PixelRect {
                x0: 16,
                y0: 32,
                width: 20,
                height: 16,
            },
            samples: 0..1,
        };
        let tiles = part.tiles(36, 64);
        assert_eq!(
            tiles,
            vec![
                PixelRect {
                    x0: 16,
                    y0: 32,
                    width: 16,
                    height: 16
                },
                PixelRect {
                    x0: 32,
                    y0: 32,
                    width: 4,
                    height: 16
                }
            ]
        );
    }
}
