//! The film: the image being rendered, as named channel planes, and its output files.
//!
//! A [`Film`] holds one `f32` plane per channel, grouped into [`Layer`]s (colour, depth,
//! normals, albedo, texture-coordinate and footprint diagnostics) with the conventional
//! OpenEXR channel names (`R G B A`, `Z`, `N.X N.Y N.Z`, `albedo.R` ...). Render workers
//! write finished work tiles straight into the film, in parallel and without a lock: the
//! film is cut into disjoint writable [`FilmRegion`]s ([`regions`]), one per work tile:
//!
//! ```ignore
//! let mut film = Film::new(w, h, &[Layer::Color, Layer::Depth]);
//! film.bands_mut(WORK_TILE_SIZE).into_par_iter().for_each(|band| {
//!     // One allocation per band for the row slices of all its regions.
//!     let mut regions = band.split_columns(WORK_TILE_SIZE);
//!     regions.par_regions().for_each(|mut region| {
//!         for (x, y) in region.rect().pixels() {
//!             region.set(Layer::Color, x, y, &[r, g, b, 1.0]);
//!         }
//!     });
//! }); // bands top to bottom, regions left to right: `render::work_tiles(w, h)`'s order
//! ```
//! (`regions.rs` has this as a test.) A [`FilmTile`] is a small film of its own, copied in
//! with [`Film::merge_tile`].
//!
//! Output: [`write_exr`] stores every channel as 32-bit float with custom header attributes
//! (software, an "incomplete render" flag and finished-tile count for `--resume`, free-form
//! strings); [`write_png`] stores 8-bit sRGB after exposure and tone mapping (seed 004,
//! "Gamma Correction" and "HDR vs LDR", with the exact sRGB curve instead of a 2.2 power).
//! [`read_exr`] reads a film back. Every file is written atomically ([`atomic_file`]): a
//! failed write never damages an existing file.
//!
//! An integrator fills a [`TileImage`] per work tile with colour and the AOVs an
//! [`AovSelection`] asks for; the render copies it into the film.
//! A render split across machines writes partial films: a region of the image placed by the
//! EXR's data and display windows, or a range of samples with their exact sums
//! ([`partial`], [`sample_sum`]).
//!
//! The film does not know about cameras, sampling or shading: it stores what it is given.

pub mod atomic_file;
pub mod channels;
pub mod error;
pub mod exr_header_order;
pub mod exr_input;
pub mod exr_output;
#[allow(clippy::module_inception)]
pub mod film;
pub mod partial;
pub mod png_output;
pub mod regions;
pub mod sample_sum;
pub mod tile_image;

pub use atomic_file::OutputSet;
pub use channels::Layer;
pub use error::OutputError;
pub use exr_input::read_exr;
pub use exr_output::{stage_exr, write_exr, ExrAttributes};
pub use film::{Film, FilmLayout, FilmTile, PixelRect};
pub use png_output::{display_value, stage_png, tonemap_to_srgb8, write_png};
pub use regions::{BandRegions, FilmBand, FilmRegion};
pub use tile_image::{block_order, AovSelection, TileImage};
