//! The font the accuracy images are labelled with, read from the system at run time.
//!
//! `plotters` draws text with `ab_glyph` from a font registered once per process. The first
//! TrueType file found among [`FONT_PATHS`] (Debian's `fonts-dejavu-core` provides the
//! first; `scripts/setup.sh` installs it) is registered as `sans-serif`. Without one, the
//! images are drawn without text instead of failing.

use std::sync::OnceLock;

/// The font family name labels are drawn with.
pub const FAMILY: &str = "sans-serif";

/// Where to look for a sans-serif TrueType font, in order.
pub const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
];

static REGISTERED: OnceLock<bool> = OnceLock::new();

/// Registers the first usable font of [`FONT_PATHS`] (once); true when labels can be drawn.
pub fn labels_available() -> bool {
    *REGISTERED.get_or_init(|| {
        FONT_PATHS.iter().any(|path| {
            let Ok(bytes) = std::fs::read(path) else {
                return false;
            };
            // plotters keeps a `'static` reference to the font data for the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, bytes)
                .is_ok()
        })
    })
}
