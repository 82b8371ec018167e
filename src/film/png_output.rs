//! Writing a film's colour as an 8-bit sRGB PNG for viewing.
//!
//! Seed 004 ("Gamma Correction", "HDR vs LDR"): rendered radiance is linear and unbounded,
//! so it is scaled by the exposure `2^stops`, mapped into [0, 1] by the chosen
//! [`ToneMap`] (clamp, or Reinhard `x / (1 + x)`), and encoded with the exact piecewise
//! sRGB transfer function (IEC 61966-2-1: `12.92 x` below `0.0031308`, else
//! `1.055 x^(1/2.4) - 0.055`) rather than seed 004's `x^(1/2.2)` approximation.
//!
//! The film's colour is premultiplied by alpha (OpenEXR convention). When every alpha is 1
//! the PNG is RGB; otherwise it is RGBA with colour divided by alpha (PNG stores straight
//! alpha) and alpha stored linearly. The file is written atomically.

use std::path::Path;

use image::{codecs::png::PngEncoder, ExtendedColorType, ImageEncoder};

use super::atomic_file::OutputSet;
use super::channels::Layer;
use super::error::OutputError;
use super::film::Film;
use crate::scene::ToneMap;
use crate::srgb::{linear_to_srgb, srgb_byte};

/// One linear radiance value to its display value in [0, 1]: exposure scale, tone map and
/// the sRGB transfer function. Negative values and NaN give 0.
#[inline]
pub fn display_value(linear: f32, tonemap: ToneMap, exposure_scale: f32) -> f32 {
    linear_to_srgb(tone_mapped(linear, tonemap, exposure_scale))
}

/// One linear radiance value scaled by the exposure and tone mapped into [0, 1], before
/// the sRGB encoding. Negative values and NaN give 0.
#[inline]
fn tone_mapped(linear: f32, tonemap: ToneMap, exposure_scale: f32) -> f32 {
    let x = linear * exposure_scale;
    let x = if x > 0.0 { x } else { 0.0 }; // also maps NaN to 0
    match tonemap {
        ToneMap::Clamp => x.min(1.0),
        ToneMap::Reinhard => {
            if x.is_finite() {
                x / (1.0 + x)
            } else {
                1.0
            }
        }
    }
}

/// One linear radiance value to an 8-bit sRGB code: the exposure and the tone map of
/// [`display_value`], then the nearest byte of its sRGB encoding (`srgb::srgb_byte`, the
/// same byte without a `powf`).
#[inline]
pub fn tonemap_to_srgb8(linear: f32, tonemap: ToneMap, exposure_scale: f32) -> u8 {
    srgb_byte(tone_mapped(linear, tonemap, exposure_scale))
}

/// Writes the film's colour layer to `path` as 8-bit sRGB PNG (atomically; the parent
/// directory is created if missing), after multiplying by `2^exposure_stops` and tone
/// mapping. Fails if the film has no [`Layer::Color`].
pub fn write_png(
    film: &Film,
    path: &Path,
    tonemap: ToneMap,
    exposure_stops: f32,
) -> Result<(), OutputError> {
    let mut set = OutputSet::default();
    stage_png(&mut set, film, path, tonemap, exposure_stops)?;
    set.commit()
}

/// Encodes the PNG of [`write_png`] into a file of `set`, replaced when the set commits.
pub fn stage_png(
    set: &mut OutputSet,
    film: &Film,
    path: &Path,
    tonemap: ToneMap,
    exposure_stops: f32,
) -> Result<(), OutputError> {
    let missing = || {
        OutputError::invalid(
            path,
            "the film has no colour layer (R G B A) to write as PNG",
        )
    };
    if !film.has(Layer::Color) {
        return Err(missing());
    }
    let (r, g, b, a) = match (
        film.channel("R"),
        film.channel("G"),
        film.channel("B"),
        film.channel("A"),
    ) {
        (Some(r), Some(g), Some(b), Some(a)) => (r, g, b, a),
        _ => return Err(missing()),
    };
    if film.width() == 0 || film.height() == 0 {
        return Err(OutputError::invalid(
            path,
            "cannot write an empty (0-pixel) image as PNG",
        ));
    }
    let scale = exposure_stops.exp2();
    let opaque = a.iter().all(|v| *v == 1.0);
    let channels = if opaque { 3 } else { 4 };
    let mut bytes = Vec::with_capacity(r.len() * channels);
    for i in 0..r.len() {
        let alpha = a[i];
        // Un-premultiply for PNG's straight alpha; fully transparent pixels stay black.
        let unpremultiply = if opaque || alpha.is_nan() || alpha <= 0.0 {
            1.0
        } else {
            1.0 / alpha
        };
        for c in [r[i], g[i], b[i]] {
            bytes.push(tonemap_to_srgb8(c * unpremultiply, tonemap, scale));
        }
        if !opaque {
            bytes.push((alpha.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
    }
    let color_type = if opaque {
        ExtendedColorType::Rgb8
    } else {
        ExtendedColorType::Rgba8
    };
    set.stage(path, |writer| {
        PngEncoder::new(writer)
            .write_image(&bytes, film.width(), film.height(), color_type)
            .map_err(|source| OutputError::Png {
                path: path.to_path_buf(),
                source,
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_codes_of_known_values() {
        let code = |x: f32| tonemap_to_srgb8(x, ToneMap::Clamp, 1.0);
        assert_eq!(code(0.0), 0);
        // The end of the linear segment: 12.92 * 0.0031308 = 0.040450 -> 10.31.
        assert_eq!(code(0.003_130_8), 10);
        // 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357 -> 187.52.
        assert_eq!(code(0.5), 188);
        assert_eq!(code(1.0), 255);
        assert_eq!(code(1.5), 255);
        assert_eq!(code(1e30), 255);
        assert_eq!(code(f32::INFINITY), 255);
        assert_eq!(code(-1.0), 0);
        assert_eq!(code(f32::NAN), 0);
    }

    /// The PNG's byte is the display value rounded to the nearest code, for both tone maps
    /// and several exposures, over radiances from 1e-6 to 1e4 and the special values.
    #[test]
    fn srgb_codes_are_the_rounded_display_values() {
        let mut radiances = vec![0.0f32, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::MAX];
        let mut x = 1e-6f32;
        while x < 1e4 {
            radiances.push(x);
            x *= 1.0007;
        }
        for tonemap in [ToneMap::Clamp, ToneMap::Reinhard] {
            for scale in [0.25f32, 1.0, 3.0] {
                for &linear in &radiances {
                    let display = display_value(linear, tonemap, scale);
                    let rounded = (display * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
                    assert_eq!(
                        tonemap_to_srgb8(linear, tonemap, scale),
                        rounded,
                        "{linear:e} x {scale}, {tonemap:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn exposure_and_reinhard() {
        // One stop up doubles: 0.25 * 2 = 0.5.
        assert_eq!(tonemap_to_srgb8(0.25, ToneMap::Clamp, 1f32.exp2()), 188);
        // Reinhard maps 1 to 0.5 and never reaches 1 for finite input.
        assert_eq!(tonemap_to_srgb8(1.0, ToneMap::Reinhard, 1.0), 188);
        assert!(tonemap_to_srgb8(100.0, ToneMap::Reinhard, 1.0) < 255);
        assert_eq!(tonemap_to_srgb8(f32::INFINITY, ToneMap::Reinhard, 1.0), 255);
    }

    fn colour_film(values: &[[f32; 4]]) -> Film {
        let mut film = Film::new(values.len() as u32, 1, &[Layer::Color]);
        for (x, v) in values.iter().enumerate() {
            film.set(Layer::Color, x as u32, 0, v);
        }
        film
    }

    #[test]
    fn png_decodes_to_the_expected_srgb_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out/beauty.png");
        let film = colour_film(&[[0.0, 0.003_130_8, 0.5, 1.0], [1.0, 2.0, 0.25, 1.0]]);
        write_png(&film, &path, ToneMap::Clamp, 0.0).unwrap();
        let decoded = image::open(&path).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgb8);
        assert_eq!(
            decoded.to_rgb8().into_raw(),
            vec![0, 10, 188, 255, 255, 137]
        );
    }

    #[test]
    fn transparent_pixels_give_straight_alpha() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("alpha.png");
        // Premultiplied 0.25 at alpha 0.5 is straight 0.5.
        let film = colour_film(&[[0.25, 0.25, 0.25, 0.5], [0.0, 0.0, 0.0, 0.0]]);
        write_png(&film, &path, ToneMap::Clamp, 0.0).unwrap();
        let decoded = image::open(&path).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgba8);
        assert_eq!(
            decoded.to_rgba8().into_raw(),
            vec![188, 188, 188, 128, 0, 0, 0, 0]
        );
    }

    #[test]
    fn failed_png_write_keeps_the_previous_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("beauty.png");
        write_png(
            &colour_film(&[[0.5, 0.5, 0.5, 1.0]]),
            &path,
            ToneMap::Clamp,
            0.0,
        )
        .unwrap();
        let before = std::fs::read(&path).unwrap();
        let no_colour = Film::new(1, 1, &[Layer::Depth]);
        let err = write_png(&no_colour, &path, ToneMap::Clamp, 0.0).unwrap_err();
        assert!(err.to_string().contains("beauty.png"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), before);
    }
}
