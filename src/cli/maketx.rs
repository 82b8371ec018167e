//! `conetrace maketx IN OUT.tx`: converts an untiled image (PNG, JPEG, scanline OpenEXR or
//! TIFF) into a tiled, mip-mapped TIFF that renders read tile by tile on demand, under the
//! texture cache's cap, instead of decoding it whole before the first ray.
//!
//! The levels are the ones a render builds in memory from IN (`MipPyramid::build`, in IN's
//! precision), so a render from OUT equals a render from IN bit for bit when the scene
//! gives OUT the colour space it gave IN. OUT is written to a temporary file beside it and
//! renamed into place when complete; IN is never written, and OUT naming the same file as
//! IN (through a symbolic or hard link too) is refused.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::cli::CommandError;
use crate::film::OutputSet;
use crate::texture::{ColorSpace, Texture, TxCompression, TxOptions};

#[derive(clap::Args, Debug)]
pub struct MaketxArgs {
    /// The image to convert: PNG, JPEG, OpenEXR or TIFF.
    pub input: PathBuf,
    /// The tiled, mip-mapped TIFF to write (by convention `.tx`).
    pub output: PathBuf,
    /// Colour space of 8-bit colour, as the scene will declare it (srgb, linear): the
    /// levels average the decoded values. Float images are always used as stored.
    #[arg(long, default_value = "srgb")]
    pub colorspace: ColorSpace,
    /// Tile compression: deflate (as maketx writes) or none (larger, fastest to read).
    #[arg(long, default_value = "deflate")]
    pub compression: TxCompression,
}

pub fn run(args: &MaketxArgs) -> Result<(), CommandError> {
    let started = Instant::now();
    refuse_same_file(&args.input, &args.output)?;
    // Decoded whole, every level built as a render builds it (a tiled input keeps its own).
    let texture = Texture::from_file_whole(&args.input, args.colorspace)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let options = TxOptions {
        compression: args.compression,
        color_space: args.colorspace,
        software: format!(
            "conetrace {} maketx {}",
            env!("CARGO_PKG_VERSION"),
            args.input.display()
        ),
    };
    let mut set = OutputSet::default();
    set.stage(&args.output, |writer| {
        crate::texture::write_tx(texture.pyramid(), writer, &options)
            .map_err(|message| crate::film::OutputError::invalid(&args.output, &message))
    })
    .map_err(|e| CommandError::bad_input(e.to_string()))?;
    // Checked again just before the rename: OUT may have become a link to IN meanwhile.
    refuse_same_file(&args.input, &args.output)?;
    set.commit()
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let written = std::fs::metadata(&args.output).map_or(0, |m| m.len());
    println!(
        "wrote {}: {}x{}, {} levels in 64x64 tiles, {:.1} MiB, in {:.2} s",
        args.output.display(),
        texture.width(),
        texture.height(),
        texture.level_count(),
        written as f64 / (1024.0 * 1024.0),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Refuses an OUT that is IN: the same path once links are followed, or another name (a
/// hard link) of the same file (same device and inode).
fn refuse_same_file(input: &Path, output: &Path) -> Result<(), CommandError> {
    let same = || {
        CommandError::bad_input(format!(
            "{}: the output is the input file {}; choose another output name",
            output.display(),
            input.display()
        ))
    };
    let (Ok(input_meta), Ok(output_meta)) = (std::fs::metadata(input), std::fs::metadata(output))
    else {
        // A missing IN is reported when it is read; a missing OUT cannot be IN. A dangling
        // link OUT would be created at its target, which is not IN (IN exists).
        if let (Ok(a), Ok(b)) = (
            std::fs::canonicalize(input),
            std::fs::canonicalize(crate::film::atomic_file::resolve_symlinks(output)),
        ) {
            if a == b {
                return Err(same());
            }
        }
        return Ok(());
    };
    use std::os::unix::fs::MetadataExt;
    let same_inode = input_meta.dev() == output_meta.dev() && input_meta.ino() == output_meta.ino();
    let same_path = matches!(
        (std::fs::canonicalize(input), std::fs::canonicalize(output)),
        (Ok(a), Ok(b)) if a == b
    );
    if same_inode || same_path {
        return Err(same());
    }
    Ok(())
}
