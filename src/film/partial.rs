//! Partial images: a region of the full image and a range of sample indices, how they are
//! written on the command line and recorded in an EXR header.
//!
//! A render of one region is stored as OpenEXR intends: the data window is the region and
//! the display window is the whole image ([`ImageWindow`]). A render of a sample range
//! records it in text attributes: `conetrace.samples = "START..END"` and
//! `conetrace.sample_weight_sum`, the weight each pixel's samples add up to (every sample
//! weighs 1 under the box pixel filter, so it is `END - START`).

use std::ops::Range;

use super::film::PixelRect;

/// Header attribute holding a partial render's sample range, `START..END`.
pub const SAMPLES_ATTRIBUTE: &str = "conetrace.samples";
/// Header attribute holding the sum of the sample weights of each pixel.
pub const SAMPLE_WEIGHT_ATTRIBUTE: &str = "conetrace.sample_weight_sum";

/// Where a film of `width` x `height` pixels sits in the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageWindow {
    /// Top-left pixel of the film (the EXR data window's position).
    pub x0: u32,
    pub y0: u32,
    /// Size of the whole image (the EXR display window).
    pub full_width: u32,
    pub full_height: u32,
}

impl ImageWindow {
    /// Checks that a `width` x `height` film at this position lies inside the whole image.
    pub fn check_fits(&self, width: u32, height: u32) -> Result<(), String> {
        let fits = u64::from(self.x0) + u64::from(width) <= u64::from(self.full_width)
            && u64::from(self.y0) + u64::from(height) <= u64::from(self.full_height);
        if fits {
            Ok(())
        } else {
            Err(format!(
                "the data window ({},{}) + {width}x{height} lies outside the {}x{} display window",
                self.x0, self.y0, self.full_width, self.full_height
            ))
        }
    }

    /// The film's pixels as a rectangle of the whole image.
    pub fn rect(&self, width: u32, height: u32) -> PixelRect {
        PixelRect {
            x0: self.x0,
            y0: self.y0,
            width,
            height,
        }
    }
}

/// Parses `X0,Y0,X1,Y1` (half-open: columns `X0..X1`, rows `Y0..Y1`) for a `width` x
/// `height` image: any non-empty rectangle inside the image (the render traces the work
/// tiles that cover it and keeps its pixels, `render::part::RenderPart::covering_region`).
pub fn parse_region(text: &str, width: u32, height: u32) -> Result<PixelRect, String> {
    let values: Vec<u32> = text
        .split(',')
        .map(|v| v.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--region {text:?}: expected X0,Y0,X1,Y1 (four whole numbers)"))?;
    let [x0, y0, x1, y1] = values[..] else {
        return Err(format!(
            "--region {text:?}: expected X0,Y0,X1,Y1 (four whole numbers)"
        ));
    };
    if x0 >= x1 || y0 >= y1 {
        return Err(format!(
            "--region {text:?}: empty (X0 < X1 and Y0 < Y1 are needed)"
        ));
    }
    if x1 > width || y1 > height {
        return Err(format!(
            "--region {text:?}: outside the {width}x{height} image"
        ));
    }
    Ok(PixelRect {
        x0,
        y0,
        width: x1 - x0,
        height: y1 - y0,
    })
}

/// Parses `START..END` (half-open) for a render of `spp` samples per pixel.
pub fn parse_sample_range(text: &str, spp: u32) -> Result<Range<u32>, String> {
    let bad = || format!("--samples {text:?}: expected START..END (whole numbers)");
    let (start, end) = text.split_once("..").ok_or_else(bad)?;
    let start: u32 = start.trim().parse().map_err(|_| bad())?;
    let end: u32 = end.trim().parse().map_err(|_| bad())?;
    if start >= end {
        return Err(format!("--samples {text:?}: empty (START < END is needed)"));
    }
    if end > spp {
        return Err(format!(
            "--samples {text:?}: beyond the {spp} samples per pixel of the render"
        ));
    }
    Ok(start..end)
}

/// The text form of a sample range, as [`SAMPLES_ATTRIBUTE`] stores it.
pub fn format_sample_range(range: &Range<u32>) -> String {
    format!("{}..{}", range.start, range.end)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_parse_half_open_anywhere_inside_the_image() {
        let r = parse_region("16,0,40,32", 40, 36).unwrap();
        assert_eq!((r.x0, r.y0, r.width, r.height), (16, 0, 24, 32));
        assert!(parse_region("0,0,40,36", 40, 36).is_ok());
        let off_grid = parse_region("1,3,17,35", 40, 36).unwrap();
        assert_eq!(
            (off_grid.x0, off_grid.y0, off_grid.width, off_grid.height),
            (1, 3, 16, 32)
        );
        for bad in [
            "0,0,41,16",
            "0,0,16,37",
            "16,0,16,16",
            "5,9,4,12",
            "0,0,16",
            "a,b,c,d",
            "-1,0,16,16",
        ] {
            let error = parse_region(bad, 40, 36).unwrap_err();
            assert!(error.starts_with("--region"), "{bad}: {error}");
        }
    }

    #[test]
    fn sample_ranges_parse_and_stay_inside_the_samples() {
        assert_eq!(parse_sample_range("2..6", 8), Ok(2..6));
        assert_eq!(format_sample_range(&(2..6)), "2..6");
        for bad in ["6..2", "0..9", "3", "..4", "x..2"] {
            assert!(parse_sample_range(bad, 8).is_err(), "{bad}");
        }
    }

    #[test]
    fn windows_must_fit_the_whole_image() {
        let window = ImageWindow {
            x0: 16,
            y0: 8,
            full_width: 40,
            full_height: 20,
        };
        assert!(window.check_fits(24, 12).is_ok());
        assert!(window.check_fits(25, 12).is_err());
    }
}
