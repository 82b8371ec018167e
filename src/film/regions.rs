//! Disjoint writable parts of a film, so render workers write finished work tiles straight
//! into the image in parallel: no lock, no second whole-image buffer, no serial copy.
//!
//! The film's planes are cut with safe slice splitting: [`Film::bands_mut`] cuts every
//! channel plane into bands of whole rows ([`FilmBand`]), and [`FilmBand::split_columns`]
//! cuts a band's rows into column ranges ([`FilmRegion`]). Each region borrows only its own
//! rows, so any number of threads can fill regions at once. The slices of a band are made
//! when the band is split, so the bookkeeping alive at a time is a few rows' worth, not the
//! image's.
//!
//! [`Film::bands_mut`]: super::Film::bands_mut

use rayon::prelude::*;

use super::channels::Layer;
use super::film::{FilmLayout, PixelRect};

/// Rows `y0 .. y0 + height` of every channel plane of a film, writable on their own.
pub struct FilmBand<'a> {
    pub(super) y0: u32,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) layout: FilmLayout,
    /// One slice of `width * height` values per channel, in channel order.
    pub(super) planes: Vec<&'a mut [f32]>,
}

impl<'a> FilmBand<'a> {
    /// The pixels covered, in image coordinates.
    pub fn rect(&self) -> PixelRect {
        PixelRect {
            x0: 0,
            y0: self.y0,
            width: self.width,
            height: self.height,
        }
    }

    /// The band cut into regions of `region_width` columns, left to right (the last one
    /// narrower when the width is not a multiple), held by one [`BandRegions`]: the row
    /// slices of all its regions are made in one allocation per band, not one per region.
    pub fn split_columns(self, region_width: u32) -> BandRegions<'a> {
        let region_width = region_width.max(1);
        let count = self.width.div_ceil(region_width) as usize;
        let height = self.height as usize;
        let per_region = self.planes.len() * height;
        // Row `r` of channel `c` of region `i` goes to `i * per_region + c * height + r`:
        // each region's rows are one run, channel-major inside it.
        let mut keyed: Vec<(usize, &'a mut [f32])> = Vec::with_capacity(count * per_region);
        if self.width > 0 {
            for (c, plane) in self.planes.into_iter().enumerate() {
                for (r, row) in plane.chunks_mut(self.width as usize).enumerate() {
                    for (i, part) in row.chunks_mut(region_width as usize).enumerate() {
                        keyed.push((i * per_region + c * height + r, part));
                    }
                }
            }
        }
        // The keys are the positions 0..n, each once: every swap puts one row where it
        // belongs, so n swaps at most order them (a sort cost 1.3 % of a 1-spp render).
        for position in 0..keyed.len() {
            while keyed[position].0 != position {
                let target = keyed[position].0;
                keyed.swap(position, target);
            }
        }
        // The same allocation, reused in place without the keys.
        let rows: Vec<&'a mut [f32]> = keyed.into_iter().map(|(_, row)| row).collect();
        BandRegions {
            y0: self.y0,
            width: self.width,
            height: self.height,
            region_width,
            layout: self.layout,
            per_region,
            rows,
        }
    }
}

/// A band's rows regrouped into column regions (see [`FilmBand::split_columns`]).
pub struct BandRegions<'a> {
    y0: u32,
    width: u32,
    height: u32,
    region_width: u32,
    layout: FilmLayout,
    /// Rows per region (`channels * height`).
    per_region: usize,
    /// Every region's rows, region by region.
    rows: Vec<&'a mut [f32]>,
}

impl<'a> BandRegions<'a> {
    /// How many regions the band has.
    pub fn len(&self) -> usize {
        self.width.div_ceil(self.region_width) as usize
    }

    /// Whether the band has no region (an empty film's).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The regions, left to right, each writable on its own: a parallel iterator whose
    /// items borrow this band's rows.
    pub fn par_regions(&mut self) -> impl IndexedParallelIterator<Item = FilmRegion<'_, 'a>> {
        let (y0, width, height, region_width, layout) = (
            self.y0,
            self.width,
            self.height,
            self.region_width,
            self.layout,
        );
        // A band without rows has no regions; a chunk size of zero is not allowed.
        self.rows
            .par_chunks_mut(self.per_region.max(1))
            .enumerate()
            .map(move |(i, rows)| {
                let x0 = i as u32 * region_width;
                FilmRegion {
                    rect: PixelRect {
                        x0,
                        y0,
                        width: region_width.min(width - x0),
                        height,
                    },
                    layout,
                    rows,
                }
            })
    }
}

/// A rectangle of a film, writable on its own (see the module doc); it borrows its rows
/// from the [`BandRegions`] it came from.
pub struct FilmRegion<'r, 'a> {
    rect: PixelRect,
    layout: FilmLayout,
    /// `layout.channel_count() * rect.height` rows of `rect.width` values, channel-major.
    rows: &'r mut [&'a mut [f32]],
}

impl FilmRegion<'_, '_> {
    /// The pixels covered, in image coordinates.
    #[inline]
    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// Whether the film has `layer`.
    #[inline]
    pub fn has(&self, layer: Layer) -> bool {
        self.layout.first_channel(layer).is_some()
    }

    /// Writes `layer` over the whole region: channel `c` of the pixel `i` (counted row by
    /// row from the region's top left) is `value(i)[c]`. Channel by channel and row by row,
    /// so the writes run along the film's rows; nothing happens when the film has no such
    /// layer.
    #[inline]
    pub fn set_all<const N: usize>(&mut self, layer: Layer, value: impl Fn(usize) -> [f32; N]) {
        debug_assert_eq!(N, layer.channel_count());
        let Some(first) = self.layout.first_channel(layer) else {
            return;
        };
        let (width, height) = (self.rect.width as usize, self.rect.height as usize);
        for c in 0..N.min(layer.channel_count()) {
            let rows = &mut self.rows[(first + c) * height..(first + c + 1) * height];
            for (y, row) in rows.iter_mut().enumerate() {
                for (x, out) in row.iter_mut().take(width).enumerate() {
                    *out = value(y * width + x)[c];
                }
            }
        }
    }

    /// Writes one pixel of `layer` at image coordinates `(x, y)`; the rules of
    /// [`super::Film::set`] (absent layers and pixels outside the region are ignored).
    #[inline]
    pub fn set(&mut self, layer: Layer, x: u32, y: u32, values: &[f32]) {
        debug_assert_eq!(values.len(), layer.channel_count());
        let Some(first) = self.layout.first_channel(layer) else {
            return;
        };
        if !self.rect.contains(x, y) {
            return;
        }
        let (row, column) = ((y - self.rect.y0) as usize, (x - self.rect.x0) as usize);
        let height = self.rect.height as usize;
        for (i, v) in values.iter().take(layer.channel_count()).enumerate() {
            self.rows[(first + i) * height + row][column] = *v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Film;
    use super::*;

    fn pattern(x: u32, y: u32, c: usize) -> f32 {
        (x * 1000 + y) as f32 + c as f32 * 0.25
    }

    #[test]
    fn regions_cover_the_work_tiles_and_parallel_writes_equal_serial_ones() {
        let layers = [Layer::Color, Layer::Depth, Layer::TexFootprint];
        let (w, h) = (37, 23);
        let mut serial = Film::new(w, h, &layers);
        for (x, y) in (PixelRect {
            x0: 0,
            y0: 0,
            width: w,
            height: h,
        })
        .pixels()
        {
            for layer in layers {
                let values: Vec<f32> = (0..layer.channel_count())
                    .map(|c| pattern(x, y, c))
                    .collect();
                serial.set(layer, x, y, &values);
            }
        }

        let mut film = Film::new(w, h, &layers);
        let tile = crate::render::WORK_TILE_SIZE;
        let mut bands: Vec<BandRegions> = film
            .bands_mut(tile)
            .into_iter()
            .map(|band| band.split_columns(tile))
            .collect();
        // Row-major like the renderer's one enumeration of work tiles.
        let rects: Vec<PixelRect> = bands
            .iter_mut()
            .flat_map(|band| band.par_regions().map(|r| r.rect()).collect::<Vec<_>>())
            .collect();
        assert_eq!(rects, crate::render::work_tiles(w, h));
        bands
            .par_iter_mut()
            .flat_map(|band| band.par_regions())
            .for_each(|mut region| {
                let mut values = [0.0f32; 6];
                for (x, y) in region.rect().pixels() {
                    for layer in layers {
                        let n = layer.channel_count();
                        for (c, v) in values.iter_mut().enumerate().take(n) {
                            *v = pattern(x, y, c);
                        }
                        region.set(layer, x, y, &values[..n]);
                    }
                }
                // Outside the region and absent layers: ignored.
                region.set(Layer::Depth, w + 5, 0, &[1.0]);
                region.set(Layer::Uv, 0, 0, &[1.0, 1.0]);
            });
        assert_eq!(film, serial);
    }

    #[test]
    fn whole_region_writes_equal_pixel_writes() {
        // `set_all` over every region gives the film that `set` pixel by pixel gives, on a
        // size that leaves narrow and short regions at the edges; an absent layer is skipped.
        let layers = [Layer::Color, Layer::Depth, Layer::TexFootprint];
        let (w, h) = (37, 23);
        let mut by_pixel = Film::new(w, h, &layers);
        let mut by_region = Film::new(w, h, &layers);
        for (film, whole) in [(&mut by_pixel, false), (&mut by_region, true)] {
            let mut bands: Vec<BandRegions> = film
                .bands_mut(16)
                .into_iter()
                .map(|band| band.split_columns(16))
                .collect();
            for band in &mut bands {
                band.par_regions().for_each(|mut region| {
                    let rect = region.rect();
                    let at = |i: usize| {
                        (
                            rect.x0 + i as u32 % rect.width,
                            rect.y0 + i as u32 / rect.width,
                        )
                    };
                    if whole {
                        region.set_all(Layer::Color, |i| {
                            let (x, y) = at(i);
                            std::array::from_fn::<f32, 4, _>(|c| pattern(x, y, c))
                        });
                        region.set_all(Layer::Depth, |i| [pattern(at(i).0, at(i).1, 0)]);
                        region.set_all(Layer::TexFootprint, |i| {
                            let (x, y) = at(i);
                            std::array::from_fn::<f32, 6, _>(|c| pattern(x, y, c))
                        });
                        region.set_all(Layer::Uv, |_| [1.0, 1.0]);
                    } else {
                        for (x, y) in rect.pixels() {
                            for layer in layers {
                                let values: Vec<f32> = (0..layer.channel_count())
                                    .map(|c| pattern(x, y, c))
                                    .collect();
                                region.set(layer, x, y, &values);
                            }
                        }
                    }
                });
            }
        }
        assert_eq!(by_region, by_pixel);
        assert_ne!(by_region, Film::new(w, h, &layers));
    }

    #[test]
    fn an_empty_film_has_no_regions() {
        let mut film = Film::new(0, 5, &[Layer::Color]);
        assert!(film.bands_mut(16).is_empty());
        let mut narrow = Film::new(3, 0, &[Layer::Color]);
        assert!(narrow.bands_mut(16).is_empty());
        let mut one = Film::new(20, 3, &[Layer::Color, Layer::Depth]);
        let mut bands: Vec<BandRegions> = one
            .bands_mut(16)
            .into_iter()
            .map(|band| band.split_columns(16))
            .collect();
        assert_eq!(bands.len(), 1);
        assert_eq!(bands[0].len(), 2);
        assert_eq!(bands[0].par_regions().count(), 2);
    }
}
