//! The in-memory image: named `f32` channel planes, and tiles that render workers fill.
//!
//! Storage is planar (one contiguous plane per channel, row-major, `y = 0` at the top), the
//! layout OpenEXR writers and tests want. A [`FilmTile`] covers a small rectangle with the
//! same channel layout, also planar, so [`Film::merge_tile`] is one row copy per channel and
//! tile row: merging a 4x4 tile is a few dozen 16-byte copies. Tiles own their memory, so
//! workers never share the film while they shade; a tile's buffer can be reused for the next
//! rectangle with [`FilmTile::reset`] (no allocation per tile).

use super::channels::Layer;
use super::regions::FilmBand;

const ABSENT: u8 = u8::MAX;

/// Which layers a film holds and where each starts in its channel list. Small and `Copy`,
/// so every worker can carry one to build tiles without touching the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FilmLayout {
    /// First channel of each layer (indexed by [`Layer::index`]), or `ABSENT`.
    first_channel: [u8; Layer::COUNT],
    channel_count: u8,
}

impl Default for FilmLayout {
    fn default() -> Self {
        FilmLayout {
            first_channel: [ABSENT; Layer::COUNT],
            channel_count: 0,
        }
    }
}

impl FilmLayout {
    /// The layout holding `layers` (duplicates ignored), channels in the order given.
    pub fn new(layers: &[Layer]) -> Self {
        let mut layout = FilmLayout::default();
        for &layer in layers {
            if layout.first_channel[layer.index()] == ABSENT {
                layout.first_channel[layer.index()] = layout.channel_count;
                layout.channel_count += layer.channel_count() as u8;
            }
        }
        layout
    }

    /// True when the layout holds `layer`.
    #[inline]
    pub fn has(&self, layer: Layer) -> bool {
        self.first_channel[layer.index()] != ABSENT
    }

    /// Index of the first channel of `layer`, if present.
    #[inline]
    pub fn first_channel(&self, layer: Layer) -> Option<usize> {
        let first = self.first_channel[layer.index()];
        (first != ABSENT).then_some(first as usize)
    }

    /// Total number of channels.
    #[inline]
    pub fn channel_count(&self) -> usize {
        self.channel_count as usize
    }

    /// The layers present, in channel order.
    pub fn layers(&self) -> Vec<Layer> {
        let mut layers: Vec<Layer> = Layer::ALL
            .iter()
            .copied()
            .filter(|l| self.has(*l))
            .collect();
        layers.sort_by_key(|l| self.first_channel[l.index()]);
        layers
    }
}

/// A pixel rectangle of the film: columns `x0 .. x0 + width`, rows `y0 .. y0 + height`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub height: u32,
}

impl PixelRect {
    /// Number of pixels covered.
    #[inline]
    pub fn area(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// True when pixel `(x, y)` lies inside.
    #[inline]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        x >= self.x0 && y >= self.y0 && x - self.x0 < self.width && y - self.y0 < self.height
    }

    /// The pixels covered, row by row, as image coordinates.
    pub fn pixels(&self) -> impl Iterator<Item = (u32, u32)> {
        let r = *self;
        (r.y0..r.y0 + r.height).flat_map(move |y| (r.x0..r.x0 + r.width).map(move |x| (x, y)))
    }

    /// The pixels this rectangle shares with `other`, if any.
    pub fn intersection(&self, other: &PixelRect) -> Option<PixelRect> {
        let x0 = self.x0.max(other.x0);
        let y0 = self.y0.max(other.y0);
        let x1 = (self.x0 + self.width).min(other.x0 + other.width);
        let y1 = (self.y0 + self.height).min(other.y0 + other.height);
        (x0 < x1 && y0 < y1).then(|| PixelRect {
            x0,
            y0,
            width: x1 - x0,
            height: y1 - y0,
        })
    }

    /// The part of this rectangle inside a `width` x `height` image.
    pub fn clipped(&self, width: u32, height: u32) -> PixelRect {
        let x0 = self.x0.min(width);
        let y0 = self.y0.min(height);
        PixelRect {
            x0,
            y0,
            width: self.width.min(width - x0),
            height: self.height.min(height - y0),
        }
    }
}

/// The image being rendered: `width` x `height` pixels of the layers it was created with.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    layout: FilmLayout,
    /// `layout.channel_count()` planes of `width * height` values, one after another.
    planes: Vec<f32>,
}

impl Film {
    /// A film of `width` x `height` pixels holding `layers` (duplicates ignored), all zero.
    pub fn new(width: u32, height: u32, layers: &[Layer]) -> Film {
        let layout = FilmLayout::new(layers);
        let len = layout.channel_count() * width as usize * height as usize;
        Film {
            width,
            height,
            layout,
            planes: vec![0.0; len],
        }
    }

    /// Like [`Film::new`], but a film too large to allocate is an error, not an abort.
    pub fn try_new(width: u32, height: u32, layers: &[Layer]) -> Result<Film, String> {
        let layout = FilmLayout::new(layers);
        let len = (layout.channel_count() as u64)
            .checked_mul(u64::from(width) * u64::from(height))
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| format!("a {width}x{height} film does not fit in memory"))?;
        let mut planes = Vec::new();
        planes.try_reserve_exact(len).map_err(|_| {
            format!(
                "cannot allocate the {width}x{height} film ({} bytes)",
                len as u64 * 4
            )
        })?;
        planes.resize(len, 0.0);
        Ok(Film {
            width,
            height,
            layout,
            planes,
        })
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The channel layout, to build [`FilmTile`]s on worker threads.
    #[inline]
    pub fn layout(&self) -> FilmLayout {
        self.layout
    }

    /// True when the film holds `layer`.
    #[inline]
    pub fn has(&self, layer: Layer) -> bool {
        self.layout.has(layer)
    }

    /// The layers held, in channel order.
    pub fn layers(&self) -> Vec<Layer> {
        self.layout.layers()
    }

    /// All channel names in storage order (e.g. `R G B A Z`).
    pub fn channel_names(&self) -> Vec<String> {
        self.layers()
            .iter()
            .flat_map(|l| l.channel_names().iter().map(|n| n.to_string()))
            .collect()
    }

    #[inline]
    fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    fn channel_index(&self, name: &str) -> Option<usize> {
        self.layers().into_iter().find_map(|layer| {
            let offset = layer.channel_names().iter().position(|n| *n == name)?;
            Some(self.layout.first_channel(layer)? + offset)
        })
    }

    /// One channel's plane (`width * height` values, row-major, top row first) by name.
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        let c = self.channel_index(name)?;
        let n = self.pixel_count();
        Some(&self.planes[c * n..(c + 1) * n])
    }

    /// Mutable access to one channel's plane by name.
    pub fn channel_mut(&mut self, name: &str) -> Option<&mut [f32]> {
        let c = self.channel_index(name)?;
        let n = self.pixel_count();
        Some(&mut self.planes[c * n..(c + 1) * n])
    }

    /// Writes one pixel of `layer` (`values` in the layer's channel order). Ignored when the
    /// film does not hold the layer or the pixel is outside; extra values are ignored and
    /// missing ones leave the channel unchanged.
    pub fn set(&mut self, layer: Layer, x: u32, y: u32, values: &[f32]) {
        debug_assert_eq!(values.len(), layer.channel_count());
        let Some(first) = self.layout.first_channel(layer) else {
            return;
        };
        if x >= self.width || y >= self.height {
            return;
        }
        let n = self.pixel_count();
        let pixel = y as usize * self.width as usize + x as usize;
        for (i, v) in values.iter().take(layer.channel_count()).enumerate() {
            self.planes[(first + i) * n + pixel] = *v;
        }
    }

    /// Reads one pixel of `layer` into `out` (layer channel order); false when absent/outside.
    pub fn get(&self, layer: Layer, x: u32, y: u32, out: &mut [f32]) -> bool {
        let Some(first) = self.layout.first_channel(layer) else {
            return false;
        };
        if x >= self.width || y >= self.height {
            return false;
        }
        let n = self.pixel_count();
        let pixel = y as usize * self.width as usize + x as usize;
        for (i, o) in out.iter_mut().take(layer.channel_count()).enumerate() {
            *o = self.planes[(first + i) * n + pixel];
        }
        true
    }

    /// The film cut into bands of `band_height` whole rows (the last one shorter when the
    /// height is not a multiple), top to bottom, each writable on its own; cut them further
    /// with [`FilmBand::split_columns`]. An empty film has no bands.
    pub fn bands_mut(&mut self, band_height: u32) -> Vec<FilmBand<'_>> {
        let n = self.pixel_count();
        if n == 0 {
            return Vec::new();
        }
        let band_height = band_height.max(1);
        let band_values = self.width as usize * band_height as usize;
        let mut bands: Vec<FilmBand<'_>> = (0..self.height.div_ceil(band_height))
            .map(|b| {
                let y0 = b * band_height;
                FilmBand {
                    y0,
                    width: self.width,
                    height: band_height.min(self.height - y0),
                    layout: self.layout,
                    planes: Vec::with_capacity(self.layout.channel_count()),
                }
            })
            .collect();
        for plane in self.planes.chunks_mut(n) {
            for (band, part) in bands.iter_mut().zip(plane.chunks_mut(band_values)) {
                band.planes.push(part);
            }
        }
        bands
    }

    /// An empty (zero) tile covering `rect` (clipped to the film) with this film's layout.
    pub fn new_tile(&self, rect: PixelRect) -> FilmTile {
        let mut tile = FilmTile::default();
        tile.reset(self.layout, rect.clipped(self.width, self.height));
        tile
    }

    /// Copies a finished tile into the film. Layers the tile holds but the film does not are
    /// skipped, as are pixels outside the film.
    pub fn merge_tile(&mut self, tile: &FilmTile) {
        let rect = tile.rect.clipped(self.width, self.height);
        if rect.area() == 0 {
            return;
        }
        let n = self.pixel_count();
        let film_width = self.width as usize;
        let tile_width = tile.rect.width as usize;
        let tile_n = tile.rect.area();
        for layer in Layer::ALL {
            let (Some(film_first), Some(tile_first)) = (
                self.layout.first_channel(layer),
                tile.layout.first_channel(layer),
            ) else {
                continue;
            };
            for c in 0..layer.channel_count() {
                let film_plane = &mut self.planes[(film_first + c) * n..(film_first + c + 1) * n];
                let tile_plane =
                    &tile.data[(tile_first + c) * tile_n..(tile_first + c + 1) * tile_n];
                for row in 0..rect.height as usize {
                    let y = rect.y0 as usize + row;
                    let dst = y * film_width + rect.x0 as usize;
                    let src = (y - tile.rect.y0 as usize) * tile_width
                        + (rect.x0 - tile.rect.x0) as usize;
                    film_plane[dst..dst + rect.width as usize]
                        .copy_from_slice(&tile_plane[src..src + rect.width as usize]);
                }
            }
        }
    }

    /// Copies the pixels of `rect` from `other` (e.g. a film read back for `--resume`) for
    /// every layer both films hold. Does nothing when the sizes differ.
    pub fn copy_region_from(&mut self, other: &Film, rect: PixelRect) {
        if other.width != self.width || other.height != self.height {
            return;
        }
        let rect = rect.clipped(self.width, self.height);
        let n = self.pixel_count();
        let w = self.width as usize;
        for layer in Layer::ALL {
            let (Some(dst_first), Some(src_first)) = (
                self.layout.first_channel(layer),
                other.layout.first_channel(layer),
            ) else {
                continue;
            };
            for c in 0..layer.channel_count() {
                for y in rect.y0 as usize..(rect.y0 + rect.height) as usize {
                    let start = y * w + rect.x0 as usize;
                    let end = start + rect.width as usize;
                    let src = &other.planes[(src_first + c) * n + start..(src_first + c) * n + end];
                    self.planes[(dst_first + c) * n + start..(dst_first + c) * n + end]
                        .copy_from_slice(src);
                }
            }
        }
    }

    /// The pixels of `rect` (inside this film) as a film of their own, with every layer.
    pub fn try_cropped(&self, rect: PixelRect) -> Result<Film, String> {
        let rect = rect.clipped(self.width, self.height);
        let mut cropped = Film::try_new(rect.width, rect.height, &self.layers())?;
        let (n, cropped_n) = (self.pixel_count(), cropped.pixel_count());
        if cropped_n == 0 {
            return Ok(cropped);
        }
        let (w, cropped_w) = (self.width as usize, rect.width as usize);
        for c in 0..self.layout.channel_count() {
            let plane = &self.planes[c * n..(c + 1) * n];
            let cropped_plane = &mut cropped.planes[c * cropped_n..(c + 1) * cropped_n];
            for (row, out) in cropped_plane.chunks_exact_mut(cropped_w).enumerate() {
                let start = (rect.y0 as usize + row) * w + rect.x0 as usize;
                out.copy_from_slice(&plane[start..start + cropped_w]);
            }
        }
        Ok(cropped)
    }
}

/// A rectangle of the film filled by one worker, merged with [`Film::merge_tile`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FilmTile {
    rect: PixelRect,
    layout: FilmLayout,
    /// Planar like the film: `layout.channel_count()` planes of `rect.area()` values.
    data: Vec<f32>,
}

impl FilmTile {
    /// A zero tile covering `rect` with `layout` (from [`Film::layout`]).
    pub fn new(layout: FilmLayout, rect: PixelRect) -> FilmTile {
        let mut tile = FilmTile::default();
        tile.reset(layout, rect);
        tile
    }

    /// Re-targets this tile to `rect` and zeroes it, reusing its buffer.
    pub fn reset(&mut self, layout: FilmLayout, rect: PixelRect) {
        self.rect = rect;
        self.layout = layout;
        self.data.clear();
        self.data.resize(layout.channel_count() * rect.area(), 0.0);
    }

    /// The rectangle covered, in image coordinates.
    #[inline]
    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// True when the tile holds `layer`.
    #[inline]
    pub fn has(&self, layer: Layer) -> bool {
        self.layout.has(layer)
    }

    /// Writes one pixel of `layer` at image coordinates `(x, y)`; same rules as
    /// [`Film::set`] (absent layers and pixels outside the tile are ignored).
    #[inline]
    pub fn set(&mut self, layer: Layer, x: u32, y: u32, values: &[f32]) {
        debug_assert_eq!(values.len(), layer.channel_count());
        let Some(first) = self.layout.first_channel(layer) else {
            return;
        };
        if !self.rect.contains(x, y) {
            return;
        }
        let n = self.rect.area();
        let pixel =
            (y - self.rect.y0) as usize * self.rect.width as usize + (x - self.rect.x0) as usize;
        for (i, v) in values.iter().take(layer.channel_count()).enumerate() {
            self.data[(first + i) * n + pixel] = *v;
        }
    }

    /// Reads one pixel of `layer` at image coordinates into `out`; false when absent/outside.
    pub fn get(&self, layer: Layer, x: u32, y: u32, out: &mut [f32]) -> bool {
        let Some(first) = self.layout.first_channel(layer) else {
            return false;
        };
        if !self.rect.contains(x, y) {
            return false;
        }
        let n = self.rect.area();
        let pixel =
            (y - self.rect.y0) as usize * self.rect.width as usize + (x - self.rect.x0) as usize;
        for (i, o) in out.iter_mut().take(layer.channel_count()).enumerate() {
            *o = self.data[(first + i) * n + pixel];
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use std::sync::Mutex;

    fn pattern(x: u32, y: u32, c: usize) -> f32 {
        (x * 1000 + y) as f32 + c as f32 * 0.25
    }

    #[test]
    fn a_film_too_large_to_allocate_is_an_error() {
        // More bytes than an address space holds: refused without touching memory.
        let message = Film::try_new(u32::MAX, u32::MAX, &Layer::ALL).err();
        let message = message.expect("a film larger than the address space was allocated");
        assert!(message.contains("4294967295x4294967295"), "{message}");
        let small = Film::try_new(3, 2, &[Layer::Color]).unwrap();
        assert_eq!(small.channel("R").unwrap().len(), 6);
    }

    #[test]
    fn a_cropped_film_holds_the_rectangle_of_every_channel() {
        let layers = [Layer::Color, Layer::Depth];
        let mut film = Film::new(7, 5, &layers);
        for (x, y) in (PixelRect {
            x0: 0,
            y0: 0,
            width: 7,
            height: 5,
        })
        .pixels()
        {
            let color = [0, 1, 2, 3].map(|c| pattern(x, y, c));
            film.set(Layer::Color, x, y, &color);
            film.set(Layer::Depth, x, y, &[pattern(x, y, 4)]);
        }
        let rect = PixelRect {
            x0: 2,
            y0: 1,
            width: 4,
            height: 3,
        };
        let cropped = film.try_cropped(rect).unwrap();
        assert_eq!((cropped.width(), cropped.height()), (4, 3));
        assert_eq!(cropped.layers(), film.layers());
        let (mut color, mut depth) = ([0.0f32; 4], [0.0f32; 1]);
        for (x, y) in rect.pixels() {
            assert!(cropped.get(Layer::Color, x - 2, y - 1, &mut color));
            assert!(cropped.get(Layer::Depth, x - 2, y - 1, &mut depth));
            assert_eq!(color, [0, 1, 2, 3].map(|c| pattern(x, y, c)), "({x}, {y})");
            assert_eq!(depth[0], pattern(x, y, 4), "({x}, {y})");
        }
    }

    #[test]
    fn channel_names_follow_layer_order() {
        let film = Film::new(
            3,
            2,
            &[Layer::Color, Layer::Normal, Layer::Depth, Layer::Color],
        );
        assert_eq!(
            film.channel_names(),
            ["R", "G", "B", "A", "N.X", "N.Y", "N.Z", "Z"]
        );
        assert!(film.has(Layer::Depth));
        assert!(!film.has(Layer::Uv));
        assert_eq!(film.channel("Z").unwrap().len(), 6);
        assert!(film.channel("uv.U").is_none());
    }

    #[test]
    fn set_and_get_address_the_right_plane_and_pixel() {
        let mut film = Film::new(4, 3, &[Layer::Depth, Layer::Albedo]);
        film.set(Layer::Albedo, 2, 1, &[0.1, 0.2, 0.3]);
        film.set(Layer::Depth, 3, 2, &[7.0]);
        film.set(Layer::Color, 0, 0, &[1.0, 1.0, 1.0, 1.0]); // absent: ignored
        film.set(Layer::Depth, 4, 0, &[9.0]); // outside: ignored
        assert_eq!(film.channel("albedo.G").unwrap()[4 + 2], 0.2);
        assert_eq!(film.channel("Z").unwrap()[2 * 4 + 3], 7.0);
        assert_eq!(
            film.channel("Z")
                .unwrap()
                .iter()
                .filter(|v| **v != 0.0)
                .count(),
            1
        );
        let mut out = [0.0; 3];
        assert!(film.get(Layer::Albedo, 2, 1, &mut out));
        assert_eq!(out, [0.1, 0.2, 0.3]);
    }

    #[test]
    fn parallel_tiles_merge_into_the_same_image_as_serial_writes() {
        let layers = [Layer::Color, Layer::Depth, Layer::TexFootprint];
        let (w, h) = (37, 23);
        let mut serial = Film::new(w, h, &layers);
        for y in 0..h {
            for x in 0..w {
                for layer in layers {
                    let values: Vec<f32> = (0..layer.channel_count())
                        .map(|c| pattern(x, y, c))
                        .collect();
                    serial.set(layer, x, y, &values);
                }
            }
        }

        let film = Mutex::new(Film::new(w, h, &layers));
        let layout = film.lock().unwrap().layout();
        // The renderer's own tiling (16x16, clipped at the right and bottom edges).
        let rects = crate::render::work_tiles(w, h);
        rects
            .par_iter()
            .for_each_init(FilmTile::default, |tile, rect| {
                tile.reset(layout, *rect);
                let mut values = [0.0f32; 6];
                for (x, y) in rect.pixels() {
                    for layer in layers {
                        for (c, v) in values.iter_mut().enumerate().take(layer.channel_count()) {
                            *v = pattern(x, y, c);
                        }
                        tile.set(layer, x, y, &values[..layer.channel_count()]);
                    }
                }
                film.lock().unwrap().merge_tile(tile);
            });
        assert_eq!(film.into_inner().unwrap(), serial);
    }

    #[test]
    fn merge_skips_layers_the_film_lacks_and_clips_to_the_film() {
        let mut film = Film::new(5, 5, &[Layer::Depth]);
        let layout = FilmLayout::new(&[Layer::Color, Layer::Depth]);
        let mut tile = FilmTile::new(
            layout,
            PixelRect {
                x0: 3,
                y0: 3,
                width: 4,
                height: 4,
            },
        );
        for (x, y) in tile.rect().pixels() {
            tile.set(Layer::Depth, x, y, &[pattern(x, y, 0)]);
            tile.set(Layer::Color, x, y, &[1.0; 4]);
        }
        film.merge_tile(&tile);
        let z = film.channel("Z").unwrap();
        assert_eq!(z[4 * 5 + 4], pattern(4, 4, 0));
        assert_eq!(z[3 * 5 + 3], pattern(3, 3, 0));
        assert_eq!(z[2 * 5 + 3], 0.0);
    }

    #[test]
    fn copy_region_takes_only_the_region() {
        let mut done = Film::new(4, 4, &[Layer::Depth, Layer::Lod]);
        for y in 0..4 {
            for x in 0..4 {
                done.set(Layer::Depth, x, y, &[pattern(x, y, 0)]);
            }
        }
        let mut resumed = Film::new(4, 4, &[Layer::Depth, Layer::Color]);
        resumed.copy_region_from(
            &done,
            PixelRect {
                x0: 2,
                y0: 0,
                width: 2,
                height: 2,
            },
        );
        let z = resumed.channel("Z").unwrap();
        assert_eq!(z[4 + 3], pattern(3, 1, 0));
        assert_eq!(z[2 * 4 + 3], 0.0);
        assert_eq!(z[0], 0.0);
    }
}
