//! Image error metrics of `conetrace accuracy`: RMSE, PSNR and FLIP, over the whole image or
//! over a pixel mask (the textured pixels).
//!
//! All three compare *display* images: the film's linear radiance after the scene's exposure
//! and tone mapping and the sRGB transfer function, as the PNG shows it (seed 004, "Gamma
//! Correction"; [`crate::film::png_output`]). Values lie in [0, 1], so
//!
//! - `MSE = mean over pixels and R, G, B of (test - reference)^2`, `RMSE = sqrt(MSE)`;
//! - `PSNR = 10 log10(1 / MSE)` dB (peak value 1; infinite for identical images);
//! - FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images") is
//!   NVIDIA's reference implementation through the `nv-flip` crate, on the 8-bit sRGB images
//!   the PNGs hold, at its default 67 pixels per degree (a 0.7 m wide 4K monitor seen from
//!   0.7 m). It gives a per-pixel error in [0, 1]; the reported value is its mean over the
//!   pixels considered. FLIP is computed on the whole image (its filters look at
//!   neighbours) and then averaged over the mask.

use crate::film::{display_value, tonemap_to_srgb8, Film};
use crate::scene::ToneMap;

/// A display-referred RGB image: values in [0, 1], row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGB display values, `width * height` of them.
    pub pixels: Vec<[f32; 3]>,
    /// The same pixels as 8-bit sRGB (what the PNG would store), `width * height * 3` bytes.
    pub srgb8: Vec<u8>,
}

impl DisplayImage {
    /// The film's colour as display values; `None` when the film has no colour layer.
    pub fn from_film(film: &Film, tonemap: ToneMap, exposure_stops: f32) -> Option<DisplayImage> {
        let scale = exposure_stops.exp2();
        let planes = [film.channel("R")?, film.channel("G")?, film.channel("B")?];
        let n = film.width() as usize * film.height() as usize;
        let mut pixels = Vec::with_capacity(n);
        let mut srgb8 = Vec::with_capacity(n * 3);
        for ((&r, &g), &b) in planes[0].iter().zip(planes[1]).zip(planes[2]).take(n) {
            let linear = [r, g, b];
            pixels.push(linear.map(|v| display_value(v, tonemap, scale)));
            srgb8.extend(linear.map(|v| tonemap_to_srgb8(v, tonemap, scale)));
        }
        Some(DisplayImage {
            width: film.width(),
            height: film.height(),
            pixels,
            srgb8,
        })
    }

    /// An image from display values (clamped to [0, 1]); for the unit tests.
    #[cfg(test)]
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<[f32; 3]>) -> DisplayImage {
        let srgb8 = pixels
            .iter()
            .flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8))
            .collect();
        DisplayImage {
            width,
            height,
            pixels,
            srgb8,
        }
    }
}

/// RMSE, PSNR and mean FLIP over one set of pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Root mean squared error of display values.
    pub rmse: f64,
    /// `10 log10(1 / MSE)` in dB; infinite when the images are identical there.
    pub psnr: f64,
    /// Mean of the per-pixel FLIP error.
    pub flip: f64,
}

/// A test image's error against the reference over the whole image and the masked pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Over every pixel.
    pub all: ErrorMetrics,
    /// `None` when the mask selects no pixel.
    pub masked: Option<ErrorMetrics>,
}

/// Per-pixel squared error, averaged over R, G and B.
pub fn squared_errors(reference: &DisplayImage, test: &DisplayImage) -> Vec<f64> {
    reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(r, t)| {
            (0..3)
                .map(|c| {
                    let d = t[c] as f64 - r[c] as f64;
                    d * d
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

/// Mean of `values` over the pixels `mask` selects (all pixels without a mask); `None` when
/// no pixel is selected.
pub fn masked_mean<T: Copy + Into<f64>>(values: &[T], mask: Option<&[bool]>) -> Option<f64> {
    let (sum, count) = values
        .iter()
        .enumerate()
        .filter(|(i, _)| mask.is_none_or(|m| m.get(*i) == Some(&true)))
        .fold((0.0f64, 0usize), |(s, n), (_, v)| (s + (*v).into(), n + 1));
    (count > 0).then(|| sum / count as f64)
}

/// PSNR in dB for a mean squared error of display values in [0, 1] (peak 1).
pub fn psnr_from_mse(mse: f64) -> f64 {
    if mse <= 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}

/// The per-pixel FLIP error map of `test` against `reference` (values in [0, 1]).
/// Both images must have the same size.
pub fn flip_map(reference: &DisplayImage, test: &DisplayImage) -> Vec<f32> {
    debug_assert_eq!(
        (reference.width, reference.height),
        (test.width, test.height)
    );
    let reference_image =
        nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &reference.srgb8);
    let test_image = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.srgb8);
    nv_flip::flip(
        reference_image,
        test_image,
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .to_vec()
}

/// RMSE, PSNR and FLIP of `test` against `reference`, over all pixels and over `mask`.
pub fn compare(reference: &DisplayImage, test: &DisplayImage, mask: &[bool]) -> Comparison {
    let squared = squared_errors(reference, test);
    let flip = flip_map(reference, test);
    let metrics = |mask: Option<&[bool]>| -> Option<ErrorMetrics> {
        let mse = masked_mean(&squared, mask)?;
        Some(ErrorMetrics {
            rmse: mse.sqrt(),
            psnr: psnr_from_mse(mse),
            flip: masked_mean(&flip, mask)?,
        })
    };
    let nan = ErrorMetrics {
        rmse: f64::NAN,
        psnr: f64::NAN,
        flip: f64::NAN,
    };
    Comparison {
        all: metrics(None).unwrap_or(nan),
        masked: metrics(Some(mask)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(width: u32, height: u32, value: [f32; 3]) -> DisplayImage {
        DisplayImage::from_pixels(width, height, vec![value; (width * height) as usize])
    }

    #[test]
    fn identical_images_have_zero_error_and_infinite_psnr() {
        let pixels: Vec<[f32; 3]> = (0..24 * 16)
            .map(|i| [(i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0, 0.25])
            .collect();
        let a = DisplayImage::from_pixels(24, 16, pixels);
        let c = compare(&a, &a.clone(), &vec![true; 24 * 16]);
        assert_eq!(c.all.rmse, 0.0);
        assert_eq!(c.all.psnr, f64::INFINITY);
        assert_eq!(c.all.flip, 0.0);
        assert_eq!(c.masked, Some(c.all));
    }

    #[test]
    fn a_uniform_offset_gives_its_rmse_and_psnr() {
        // Every channel off by 0.1: MSE 0.01, RMSE 0.1, PSNR 20 dB.
        let a = uniform(16, 16, [0.2, 0.4, 0.6]);
        let b = uniform(16, 16, [0.3, 0.5, 0.7]);
        let c = compare(&a, &b, &vec![false; 256]);
        assert!((c.all.rmse - 0.1).abs() < 1e-6, "{}", c.all.rmse);
        assert!((c.all.psnr - 20.0).abs() < 1e-4, "{}", c.all.psnr);
        assert!(c.masked.is_none(), "an empty mask has no metrics");
    }

    #[test]
    fn masked_metrics_only_see_the_masked_pixels() {
        // One pixel of 16 is off by 1 in every channel; the mask selects it and one more.
        let a = uniform(4, 4, [0.0; 3]);
        let mut b = a.clone();
        b.pixels[5] = [1.0; 3];
        let mut mask = vec![false; 16];
        mask[5] = true;
        mask[6] = true;
        let errors = squared_errors(&a, &b);
        assert_eq!(masked_mean(&errors, None), Some(1.0 / 16.0));
        assert_eq!(masked_mean(&errors, Some(&mask)), Some(0.5));
        assert_eq!(psnr_from_mse(0.5), 10.0 * 2f64.log10());
    }

    #[test]
    fn flip_grows_with_the_difference_and_stays_in_range() {
        let grey = uniform(32, 32, [0.5; 3]);
        let near = uniform(32, 32, [0.55; 3]);
        let black = uniform(32, 32, [0.0; 3]);
        let white = uniform(32, 32, [1.0; 3]);
        let small = compare(&grey, &near, &[]).all.flip;
        let large = compare(&black, &white, &[]).all.flip;
        assert!(small > 0.0 && small < large, "{small} {large}");
        assert!(large <= 1.0, "{large}");
        // FLIP is symmetric in its colour term for uniform images.
        let reverse = compare(&white, &black, &[]).all.flip;
        assert!((reverse - large).abs() < 1e-3, "{reverse} {large}");
    }

    #[test]
    fn display_values_follow_the_png_mapping() {
        for linear in [0.0f32, 0.001, 0.2, 0.5, 1.0, 3.0] {
            for tonemap in [ToneMap::Clamp, ToneMap::Reinhard] {
                let v = display_value(linear, tonemap, 1.0);
                let code = tonemap_to_srgb8(linear, tonemap, 1.0);
                assert!((v * 255.0 - code as f32).abs() <= 0.5 + 1e-3, "{linear}");
            }
        }
        assert_eq!(display_value(f32::NAN, ToneMap::Clamp, 1.0), 0.0);
        assert!((display_value(2.0, ToneMap::Clamp, 1.0) - 1.0).abs() < 1e-6);
    }
}
