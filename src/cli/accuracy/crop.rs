//! The crop image of one scene: the square window where the one-sample methods err most,
//! shown for the ground truth and every method side by side, enlarged and labelled.
//!
//! The window is the `side` x `side` square with the largest sum of a per-pixel error image
//! (the squared display error averaged over the one-sample methods), found with a
//! summed-area table. The first panel shows the whole ground truth with the window outlined.

use plotters::prelude::*;

use super::font::FAMILY;
use super::metrics::DisplayImage;
use crate::film::PixelRect;

/// Height of the label strip above each panel, pixels.
pub const LABEL_HEIGHT: u32 = 34;
/// Gap between panels, pixels.
pub const GAP: u32 = 4;
/// Panels per row of the crop image.
pub const COLUMNS: u32 = 5;
/// Smallest on-screen panel width the enlargement aims for, pixels.
pub const PANEL_TARGET: u32 = 176;

/// The side of the crop window for a `width` x `height` image: a quarter of the shorter
/// side, at least 8 pixels, never more than the image.
pub fn window_side(width: u32, height: u32) -> u32 {
    (width.min(height) / 4).max(8).min(width.min(height))
}

/// The `side` x `side` window of a `width` x `height` error image with the largest sum
/// (the first one in row-major order on ties).
pub fn hardest_window(error: &[f64], width: u32, height: u32, side: u32) -> PixelRect {
    let (w, h) = (width as usize, height as usize);
    let side = side.min(width).min(height) as usize;
    // sums[(y) * (w + 1) + x] = sum of error over rows < y and columns < x.
    let mut sums = vec![0.0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0.0;
        for x in 0..w {
            row += error.get(y * w + x).copied().unwrap_or(0.0);
            sums[(y + 1) * (w + 1) + x + 1] = sums[y * (w + 1) + x + 1] + row;
        }
    }
    let at = |x: usize, y: usize| sums[y * (w + 1) + x];
    let mut best = (f64::NEG_INFINITY, 0, 0);
    for y in 0..=h - side {
        for x in 0..=w - side {
            let total = at(x + side, y + side) - at(x, y + side) - at(x + side, y) + at(x, y);
            if total > best.0 {
                best = (total, x, y);
            }
        }
    }
    PixelRect {
        x0: best.1 as u32,
        y0: best.2 as u32,
        width: side as u32,
        height: side as u32,
    }
}

/// One panel: a label (two lines) and the image it shows.
pub struct Panel<'a> {
    /// First label line (the method).
    pub title: String,
    /// Second label line (its error).
    pub subtitle: String,
    /// The whole image; the panel shows its window.
    pub image: &'a DisplayImage,
}

/// The panel's pixels: the window enlarged by `scale` (nearest neighbour), or for the
/// overview the whole image fitted into `size` with the window outlined in red.
fn panel_pixels(image: &DisplayImage, window: PixelRect, scale: u32, overview: bool) -> Vec<u8> {
    let size = window.width * scale;
    let mut out = vec![255u8; (size * size * 3) as usize];
    let texel = |x: u32, y: u32| {
        let i = (y.min(image.height - 1) * image.width + x.min(image.width - 1)) as usize * 3;
        [image.srgb8[i], image.srgb8[i + 1], image.srgb8[i + 2]]
    };
    if overview {
        let fit = (size as f32 / image.width as f32).min(size as f32 / image.height as f32);
        let (ow, oh) = (
            ((image.width as f32 * fit) as u32).max(1),
            ((image.height as f32 * fit) as u32).max(1),
        );
        let y_offset = (size - oh.min(size)) / 2;
        for y in 0..oh.min(size) {
            for x in 0..ow.min(size) {
                let (sx, sy) = ((x as f32 / fit) as u32, (y as f32 / fit) as u32);
                let inside_x = sx >= window.x0 && sx < window.x0 + window.width;
                let inside_y = sy >= window.y0 && sy < window.y0 + window.height;
                let on_edge_x = sx == window.x0 || sx + 1 == window.x0 + window.width;
                let on_edge_y = sy == window.y0 || sy + 1 == window.y0 + window.height;
                let edge = (inside_x && inside_y) && (on_edge_x || on_edge_y);
                let rgb = if edge { [255, 0, 0] } else { texel(sx, sy) };
                let i = (((y + y_offset) * size + x) * 3) as usize;
                out[i..i + 3].copy_from_slice(&rgb);
            }
        }
    } else {
        for y in 0..size {
            for x in 0..size {
                let rgb = texel(window.x0 + x / scale, window.y0 + y / scale);
                let i = ((y * size + x) * 3) as usize;
                out[i..i + 3].copy_from_slice(&rgb);
            }
        }
    }
    out
}

/// Composes the crop image: an overview of `panels[0]`'s image with the window outlined,
/// then every panel's window enlarged, five per row, each under its label (labels only when
/// `labels`). Returns `(width, height, rgb8)`.
pub fn compose(
    panels: &[Panel],
    window: PixelRect,
    labels: bool,
) -> Result<(u32, u32, Vec<u8>), String> {
    let scale = PANEL_TARGET.div_ceil(window.width.max(1)).max(1);
    let size = window.width * scale;
    let cells = panels.len() as u32 + 1;
    let columns = COLUMNS.min(cells);
    let rows = cells.div_ceil(columns);
    let cell_w = size + GAP;
    let cell_h = size + LABEL_HEIGHT + GAP;
    let (width, height) = (columns * cell_w + GAP, rows * cell_h + GAP);
    let mut buffer = vec![255u8; (width * height * 3) as usize];
    let Some(first) = panels.first() else {
        return Ok((width, height, buffer));
    };
    let mut cell_images: Vec<(String, String, Vec<u8>)> = vec![(
        "ground truth, whole image".to_string(),
        format!(
            "window x {}..{}, y {}..{}",
            window.x0,
            window.x0 + window.width,
            window.y0,
            window.y0 + window.height
        ),
        panel_pixels(first.image, window, scale, true),
    )];
    for panel in panels {
        cell_images.push((
            panel.title.clone(),
            panel.subtitle.clone(),
            panel_pixels(panel.image, window, scale, false),
        ));
    }
    for (cell, (_, _, pixels)) in cell_images.iter().enumerate() {
        let (cx, cy) = (cell as u32 % columns, cell as u32 / columns);
        let x0 = GAP + cx * cell_w;
        let y0 = GAP + cy * cell_h + LABEL_HEIGHT;
        for y in 0..size {
            let src = (y * size * 3) as usize;
            let dst = (((y0 + y) * width + x0) * 3) as usize;
            buffer[dst..dst + (size * 3) as usize]
                .copy_from_slice(&pixels[src..src + (size * 3) as usize]);
        }
    }
    if labels {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        let style = (FAMILY, 13).into_font().color(&BLACK);
        for (cell, (title, subtitle, _)) in cell_images.iter().enumerate() {
            let (cx, cy) = (cell as u32 % columns, cell as u32 / columns);
            let x = (GAP + cx * cell_w) as i32;
            let y = (GAP + cy * cell_h) as i32;
            root.draw_text(title, &style.clone().into_text_style(&root), (x, y + 2))
                .map_err(|e| format!("drawing the crop labels: {e:?}"))?;
            root.draw_text(subtitle, &style.clone().into_text_style(&root), (x, y + 17))
                .map_err(|e| format!("drawing the crop labels: {e:?}"))?;
        }
        root.present()
            .map_err(|e| format!("drawing the crop labels: {e:?}"))?;
    }
    Ok((width, height, buffer))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_covers_the_largest_error() {
        let (w, h) = (40u32, 30u32);
        let mut error = vec![0.01; (w * h) as usize];
        // A small hot spot near the bottom right and a weaker, larger one top left.
        for (x, y) in [(33, 25), (34, 25), (33, 26)] {
            error[(y * w + x) as usize] = 5.0;
        }
        for y in 0..4 {
            for x in 0..4 {
                error[(y * w + x) as usize] = 0.5;
            }
        }
        let window = hardest_window(&error, w, h, 8);
        assert_eq!((window.width, window.height), (8, 8));
        for (x, y) in [(33, 25), (34, 25), (33, 26)] {
            assert!(window.contains(x, y), "{window:?}");
        }
        assert!(window.x0 + 8 <= w && window.y0 + 8 <= h);
    }

    #[test]
    fn window_side_fits_small_images() {
        assert_eq!(window_side(320, 180), 45);
        assert_eq!(window_side(48, 27), 8);
        assert_eq!(window_side(5, 40), 5);
        let window = hardest_window(&[1.0; 20], 5, 4, 8);
        assert_eq!((window.width, window.height), (4, 4));
    }

    #[test]
    fn compose_places_every_panel_without_a_font() {
        let image = DisplayImage::from_pixels(16, 12, vec![[0.5, 0.25, 1.0]; 16 * 12]);
        let panels: Vec<Panel> = (0..3)
            .map(|i| Panel {
                title: format!("m{i}"),
                subtitle: String::new(),
                image: &image,
            })
            .collect();
        let window = hardest_window(&[0.0; 16 * 12], 16, 12, 8);
        let (w, h, rgb) = compose(&panels, window, false).unwrap();
        assert_eq!(rgb.len(), (w * h * 3) as usize);
        // Four cells (overview + three) in one row of five columns at most.
        let size = 8 * PANEL_TARGET.div_ceil(8);
        assert_eq!(w, 4 * (size + GAP) + GAP);
        assert_eq!(h, size + LABEL_HEIGHT + GAP + GAP);
        // The centre of the second panel shows the image's colour.
        let (x, y) = (GAP + (size + GAP) + size / 2, GAP + LABEL_HEIGHT + size / 2);
        let i = ((y * w + x) * 3) as usize;
        assert_eq!(&rgb[i..i + 3], &image.srgb8[0..3]);
    }
}
