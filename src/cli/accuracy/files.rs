//! Writing the accuracy outputs: text and RGB PNG files, each atomically (a failed run
//! never leaves a half-written file), and the check that the output directory is usable.

use std::fs;
use std::io::Write;
use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::cli::CommandError;
use crate::film::atomic_file::write_atomically;
use crate::film::OutputError;

/// Writes `text` to `path` atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), CommandError> {
    write_atomically(path, |w| {
        w.write_all(text.as_bytes())
            .map_err(|e| OutputError::io(path, "write", e))
    })
    .map_err(|e| CommandError::bad_input(e.to_string()))
}

/// Writes an RGB8 buffer (`width * height * 3` bytes, top row first) as a PNG, atomically.
pub fn write_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), CommandError> {
    write_atomically(path, |w| {
        PngEncoder::new_with_quality(w, CompressionType::Best, FilterType::Adaptive)
            .write_image(rgb, width, height, ExtendedColorType::Rgb8)
            .map_err(|e| OutputError::invalid(path, format!("PNG encoding failed: {e}")))
    })
    .map_err(|e| CommandError::bad_input(e.to_string()))
}

/// Creates `dir` if needed and checks a file can be created in it (then removes the probe),
/// so a run that would fail at its end fails before rendering instead.
pub fn check_output_dir(dir: &Path) -> Result<(), CommandError> {
    let label = dir.display();
    fs::create_dir_all(dir)
        .map_err(|e| CommandError::bad_input(format!("{label}: cannot create directory: {e}")))?;
    let probe = dir.join(format!(".conetrace-accuracy-probe-{}", std::process::id()));
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| CommandError::bad_input(format!("{label}: cannot write files here: {e}")))?;
    let _ = fs::remove_file(&probe);
    Ok(())
}

/// The four files of one scene of an accuracy mode, named from `stem`: the table as CSV and
/// markdown, the error-against-time plot (RGB8 pixels of [`super::plot::PLOT_SIZE`]) and
/// the crops of every image side by side over `window`.
pub fn write_scene_report(
    out: &Path,
    stem: &str,
    tables: (&str, &str),
    plot: Result<Vec<u8>, String>,
    panels: &[super::crop::Panel],
    window: crate::film::PixelRect,
) -> Result<(), CommandError> {
    let (csv, markdown) = tables;
    write_text(&out.join(format!("{stem}.csv")), csv)?;
    write_text(&out.join(format!("{stem}.md")), markdown)?;
    let plot = plot.map_err(CommandError::internal)?;
    let (plot_width, plot_height) = super::plot::PLOT_SIZE;
    write_rgb_png(
        &out.join(format!("{stem}_error_vs_time.png")),
        plot_width,
        plot_height,
        &plot,
    )?;
    let labels = super::font::labels_available();
    let (crop_width, crop_height, rgb) =
        super::crop::compose(panels, window, labels).map_err(CommandError::internal)?;
    write_rgb_png(
        &out.join(format!("{stem}_crop.png")),
        crop_width,
        crop_height,
        &rgb,
    )
}
