//! The film: the image being rendered, as named channel planes, and its output files.
//!
//! A [`Film`] holds one `f32` plane per channel, grouped into [`Layer`]s (colour, depth,
//! normals, albedo, texture-coordinate and footprint diagnostics) with the conventional
//! OpenEXR channel names (`R G B A`, `Z`, `N.X N.Y N.Z`, `albedo.R` ...). Render workers fill
//! small [`FilmTile`]s independently and the film copies finished tiles in with
//! [`Film::merge_tile`], so tiles can be rendered on many threads without sharing the film:
//!
//! ```ignore
//! let film = Film::new(w, h, &[Layer::Color, Layer::Depth]);
//! let (layout, rects) = (film.layout(), film.tiles(4));
//! let film = Mutex::new(film);
//! rects.par_iter().for_each_init(FilmTile::default, |tile, rect| {
//!     tile.reset(layout, *rect); // reuses the tile's buffer: no allocation per tile
//!     for (x, y) in rect.pixels() {
//!         tile.set(Layer::Color, x, y, &[r, g, b, 1.0]);
//!     }
//!     film.lock().unwrap().merge_tile(tile); // a few row copies under the lock
//! });
//! ```
//! (`film.rs` has this as a test.)
//!
//! Output: [`write_exr`] stores every channel as 32-bit float with custom header attributes
//! (software, an "incomplete render" flag and finished-tile count for `--resume`, free-form
//! strings); [`write_png`] stores 8-bit sRGB after exposure and tone mapping (seed 004,
//! "Gamma Correction" and "HDR vs LDR", with the exact sRGB curve instead of a 2.2 power).
//! [`read_exr`] reads a film back. Every file is written atomically ([`atomic_file`]): a
//! failed write never damages an existing file.
//!
//! A render split across machines writes partial films: a region of the image placed by the
//! EXR's data and display windows, or a range of samples with their exact sums
//! ([`region`], [`sample_sum`]).
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
pub mod png_output;
pub mod region;
pub mod sample_sum;

pub use atomic_file::OutputSet;
pub use channels::Layer;
pub use error::OutputError;
pub use exr_input::read_exr;
pub use exr_output::{stage_exr, write_exr, ExrAttributes};
pub use film::{Film, FilmLayout, FilmTile, TileRect};
pub use png_output::{display_value, linear_to_srgb, stage_png, tonemap_to_srgb8, write_png};
