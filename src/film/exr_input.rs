//! Reading an OpenEXR file back into a [`Film`], for `--resume` and for tests.
//!
//! Every [`Layer`] whose channels are all present becomes a layer of the film (samples of
//! any type are converted to `f32`); channels that belong to no known layer are ignored,
//! and a layer with only some of its channels is an error. The header's conetrace
//! attributes (see [`super::exr_output`]) are returned as [`ExrAttributes`].

use std::path::Path;

use exr::prelude::{AttributeValue, ReadChannels, ReadLayers};

use super::channels::Layer;
use super::error::OutputError;
use super::exr_output::{ExrAttributes, FINISHED_TILES_ATTRIBUTE, INCOMPLETE_ATTRIBUTE};
use super::film::Film;

/// Reads the first layer of the EXR file at `path` into a film with every complete
/// conetrace layer it contains, plus its header attributes.
pub fn read_exr(path: &Path) -> Result<(Film, ExrAttributes), OutputError> {
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|source| OutputError::Exr {
            path: path.to_path_buf(),
            action: "reading",
            source,
        })?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.0, layer.size.1);
    let (Ok(width), Ok(height)) = (u32::try_from(width), u32::try_from(height)) else {
        return Err(OutputError::invalid(path, "image is too large"));
    };
    let channels: Vec<(String, &exr::prelude::FlatSamples)> = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), &c.sample_data))
        .collect();

    let mut layers = Vec::new();
    for candidate in Layer::ALL {
        let names = candidate.channel_names();
        let found = names
            .iter()
            .filter(|n| channels.iter().any(|(c, _)| c == *n))
            .count();
        if found == names.len() {
            layers.push(candidate);
        } else if found > 0 {
            let missing: Vec<&str> = names
                .iter()
                .copied()
                .filter(|n| !channels.iter().any(|(c, _)| c == n))
                .collect();
            return Err(OutputError::invalid(
                path,
                format!(
                    "layer {candidate:?} is missing channel(s) {}",
                    missing.join(", ")
                ),
            ));
        }
    }
    if layers.is_empty() {
        return Err(OutputError::invalid(
            path,
            "no conetrace channels (R G B A, Z, N.X ...) found",
        ));
    }

    let mut film =
        Film::try_new(width, height, &layers).map_err(|e| OutputError::invalid(path, e))?;
    for (name, samples) in &channels {
        if let Some(plane) = film.channel_mut(name) {
            if samples.len() != plane.len() {
                return Err(OutputError::invalid(
                    path,
                    format!(
                        "channel {name} has {} samples, expected {}",
                        samples.len(),
                        plane.len()
                    ),
                ));
            }
            for (dst, src) in plane.iter_mut().zip(samples.values_as_f32()) {
                *dst = src;
            }
        }
    }

    let mut attributes = ExrAttributes {
        software: layer
            .attributes
            .software_name
            .as_ref()
            .map(|t| t.to_string()),
        ..Default::default()
    };
    // A data window that is not the whole display window: a region of a larger image.
    let display = &image.attributes.display_window;
    let position = layer.attributes.layer_position;
    if display.position != exr::math::Vec2(0, 0) {
        return Err(OutputError::invalid(
            path,
            "the display window does not start at (0, 0)",
        ));
    }
    if position != exr::math::Vec2(0, 0)
        || (display.size.0, display.size.1) != (width as usize, height as usize)
    {
        let window = super::partial::ImageWindow {
            x0: u32::try_from(position.0)
                .map_err(|_| OutputError::invalid(path, "the data window starts left of 0"))?,
            y0: u32::try_from(position.1)
                .map_err(|_| OutputError::invalid(path, "the data window starts above 0"))?,
            full_width: u32::try_from(display.size.0)
                .map_err(|_| OutputError::invalid(path, "the display window is too large"))?,
            full_height: u32::try_from(display.size.1)
                .map_err(|_| OutputError::invalid(path, "the display window is too large"))?,
        };
        window
            .check_fits(width, height)
            .map_err(|problem| OutputError::invalid(path, problem))?;
        attributes.window = Some(window);
    }
    let unflatten = |m: &[f32; 16]| -> [[f32; 4]; 4] {
        std::array::from_fn(|row| std::array::from_fn(|col| m[row * 4 + col]))
    };
    attributes.world_to_camera = layer.attributes.world_to_camera.as_ref().map(unflatten);
    attributes.world_to_ndc = layer
        .attributes
        .world_to_normalized_device
        .as_ref()
        .map(unflatten);
    let others = layer
        .attributes
        .other
        .iter()
        .chain(image.attributes.other.iter());
    for (name, value) in others {
        let name = name.to_string();
        match (name.as_str(), value) {
            (INCOMPLETE_ATTRIBUTE, AttributeValue::I32(v)) => attributes.incomplete = *v != 0,
            (FINISHED_TILES_ATTRIBUTE, AttributeValue::I32(v)) => {
                attributes.finished_tiles = u32::try_from(*v).ok()
            }
            (_, AttributeValue::Text(text)) => {
                attributes.strings.insert(name, text.to_string());
            }
            _ => {}
        }
    }
    Ok((film, attributes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::exr_output::write_exr;

    #[test]
    fn round_trip_preserves_film_and_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("partial.exr");
        let mut film = Film::new(9, 4, &[Layer::Color, Layer::Depth, Layer::Uv]);
        for y in 0..4 {
            for x in 0..9 {
                let v = (x + 10 * y) as f32 / 7.0;
                film.set(Layer::Color, x, y, &[v, -v, v * 1e6, 0.5]);
                film.set(
                    Layer::Depth,
                    x,
                    y,
                    &[if x == 0 { f32::INFINITY } else { v }],
                );
                film.set(Layer::Uv, x, y, &[v, 1.0 - v]);
            }
        }
        let mut attributes = ExrAttributes {
            software: Some("conetrace".into()),
            incomplete: true,
            finished_tiles: Some(3),
            ..Default::default()
        };
        attributes
            .strings
            .insert("conetrace.tiles_done".into(), "0-2".into());
        write_exr(&film, &path, &attributes).unwrap();

        let (back, back_attributes) = read_exr(&path).unwrap();
        assert_eq!(back_attributes, attributes);
        assert_eq!(back.width(), 9);
        assert_eq!(back.height(), 4);
        assert_eq!(back.layers(), vec![Layer::Color, Layer::Depth, Layer::Uv]);
        for name in film.channel_names() {
            let a = film.channel(&name).unwrap();
            let b = back.channel(&name).unwrap();
            assert!(
                a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}"
            );
        }
    }

    #[test]
    fn complete_flag_reads_back_false() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("done.exr");
        write_exr(
            &Film::new(2, 2, &[Layer::Lod]),
            &path,
            &ExrAttributes::default(),
        )
        .unwrap();
        let (_, attributes) = read_exr(&path).unwrap();
        assert!(!attributes.incomplete);
        assert_eq!(attributes.finished_tiles, None);
    }

    #[test]
    fn missing_or_garbage_files_are_reported_with_their_path() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nothing.exr");
        let err = read_exr(&missing).unwrap_err().to_string();
        assert!(err.contains("nothing.exr") && !err.contains('\n'), "{err}");
        let garbage = dir.path().join("garbage.exr");
        std::fs::write(&garbage, b"definitely not an exr file").unwrap();
        let err = read_exr(&garbage).unwrap_err().to_string();
        assert!(err.contains("garbage.exr") && !err.contains('\n'), "{err}");
    }
}
