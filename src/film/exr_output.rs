//! Writing a film as a single-part OpenEXR file with every channel as 32-bit float.
//!
//! Channel names are the conventional ones of [`super::Layer`] (OpenEXR stores them sorted
//! alphabetically; readers find them by name). Scanlines are ZIP-compressed (lossless).
//! Besides the standard `software` attribute, the header carries `conetrace.incomplete`
//! (int, 1 while the render is unfinished) and `conetrace.finished_tiles` (int) so that
//! `--resume` can tell a partial image from a finished one, plus any free-form text
//! attributes, the standard `worldToCamera` and `worldToNDC` camera matrices when known, and
//! plain text attributes. The file is written atomically (see [`super::atomic_file`]).
//!
//! Header attributes are written sorted by name (see [`super::exr_header_order`]), so two
//! renders of the same scene with the same settings give byte-identical files.

use std::collections::BTreeMap;
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, LayerAttributes, Text,
    WritableImage,
};

use super::atomic_file::OutputSet;
use super::error::OutputError;
use super::film::Film;

/// Header attribute name of the "render is incomplete" flag (int 0 or 1).
pub const INCOMPLETE_ATTRIBUTE: &str = "conetrace.incomplete";
/// Header attribute name of the number of finished tiles (int).
pub const FINISHED_TILES_ATTRIBUTE: &str = "conetrace.finished_tiles";

/// Metadata stored in (and read back from) an EXR header.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrAttributes {
    /// The standard `software` attribute, e.g. `conetrace 0.1.0`.
    pub software: Option<String>,
    /// True while the render is unfinished (written as `conetrace.incomplete` = 1).
    pub incomplete: bool,
    /// How many tiles are finished (`conetrace.finished_tiles`), when known.
    pub finished_tiles: Option<u32>,
    /// Free-form text attributes by name; use namespaced names such as `conetrace.scene` so
    /// they cannot collide with standard OpenEXR attributes. Names and values must be
    /// Latin-1 text.
    pub strings: BTreeMap<String, String>,
    /// OpenEXR's standard `worldToCamera` matrix (row-vector convention: `p_camera = p_world
    /// * M`, camera looking down -Z with +Y up), row-major.
    pub world_to_camera: Option<[[f32; 4]; 4]>,
    /// OpenEXR's standard `worldToNDC` matrix (row-vector convention, then divide by w):
    /// normalized device coordinates in [0, 1] with (0, 0) at the image's top-left corner,
    /// as OpenImageIO defines them.
    pub world_to_ndc: Option<[[f32; 4]; 4]>,
    /// Where the film sits in a larger image: the data window's top-left corner and the
    /// display window's size (the whole image), for a render of one region
    /// (`super::region`). `None`: the film is the whole image, at the origin.
    pub window: Option<super::partial::ImageWindow>,
}

/// Names of the standard camera-matrix attributes.
pub const WORLD_TO_CAMERA_ATTRIBUTE: &str = "worldToCamera";
pub const WORLD_TO_NDC_ATTRIBUTE: &str = "worldToNDC";

fn exr_text(path: &Path, what: &str, text: &str) -> Result<Text, OutputError> {
    Text::new_or_none(text)
        .ok_or_else(|| OutputError::invalid(path, format!("{what} {text:?} is not Latin-1 text")))
}

/// Writes every channel of `film` as `f32` to `path` (atomically; the parent directory is
/// created if missing) with the header `attributes`.
pub fn write_exr(film: &Film, path: &Path, attributes: &ExrAttributes) -> Result<(), OutputError> {
    let mut set = OutputSet::default();
    stage_exr(&mut set, film, path, attributes)?;
    set.commit()
}

/// Row-major rows as OpenEXR's 16 floats.
fn flat_matrix(m: &[[f32; 4]; 4]) -> [f32; 16] {
    let mut flat = [0.0f32; 16];
    for (row, values) in m.iter().enumerate() {
        flat[row * 4..row * 4 + 4].copy_from_slice(values);
    }
    flat
}

/// Encodes `film` as [`write_exr`] does into a file of `set`, replaced when the set commits.
pub fn stage_exr(
    set: &mut OutputSet,
    film: &Film,
    path: &Path,
    attributes: &ExrAttributes,
) -> Result<(), OutputError> {
    if film.width() == 0 || film.height() == 0 {
        return Err(OutputError::invalid(
            path,
            "cannot write an empty (0-pixel) image as EXR",
        ));
    }
    let names = film.channel_names();
    if names.is_empty() {
        return Err(OutputError::invalid(
            path,
            "the film has no channels to write",
        ));
    }
    let mut channels = Vec::with_capacity(names.len());
    for name in &names {
        let plane = film.channel(name).unwrap_or(&[]);
        channels.push(AnyChannel::new(
            exr_text(path, "channel name", name)?,
            FlatSamples::F32(plane.to_vec()),
        ));
    }

    let mut layer_attributes = LayerAttributes::default();
    if let Some(software) = &attributes.software {
        layer_attributes.software_name = Some(exr_text(path, "software name", software)?);
    }
    let other = &mut layer_attributes.other;
    other.insert(
        exr_text(path, "attribute name", INCOMPLETE_ATTRIBUTE)?,
        AttributeValue::I32(attributes.incomplete as i32),
    );
    if let Some(tiles) = attributes.finished_tiles {
        let tiles = i32::try_from(tiles).unwrap_or(i32::MAX);
        other.insert(
            exr_text(path, "attribute name", FINISHED_TILES_ATTRIBUTE)?,
            AttributeValue::I32(tiles),
        );
    }
    layer_attributes.world_to_camera = attributes.world_to_camera.as_ref().map(flat_matrix);
    layer_attributes.world_to_normalized_device = attributes.world_to_ndc.as_ref().map(flat_matrix);
    let other = &mut layer_attributes.other;
    for (name, value) in &attributes.strings {
        // A NUL would end the name early in the header and corrupt the file.
        if name.is_empty()
            || name.contains('\0')
            || name == INCOMPLETE_ATTRIBUTE
            || name == FINISHED_TILES_ATTRIBUTE
            || name == WORLD_TO_CAMERA_ATTRIBUTE
            || name == WORLD_TO_NDC_ATTRIBUTE
        {
            return Err(OutputError::invalid(
                path,
                format!("attribute name {name:?} is reserved, empty or contains NUL"),
            ));
        }
        other.insert(
            exr_text(path, "attribute name", name)?,
            AttributeValue::Text(exr_text(path, "attribute value", value)?),
        );
    }

    if let Some(window) = &attributes.window {
        window
            .check_fits(film.width(), film.height())
            .map_err(|problem| OutputError::invalid(path, problem))?;
    }
    let layer = exr::prelude::Layer::new(
        (film.width() as usize, film.height() as usize),
        layer_attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut layer = layer;
    if let Some(window) = &attributes.window {
        layer.attributes.layer_position = exr::math::Vec2(window.x0 as i32, window.y0 as i32);
    }
    let mut image = Image::from_layer(layer);
    if let Some(window) = &attributes.window {
        image.attributes.display_window = exr::meta::attribute::IntegerBounds::new(
            (0, 0),
            (window.full_width as usize, window.full_height as usize),
        );
    }
    set.stage(path, |writer| {
        image
            .write()
            .to_buffered(&mut *writer)
            .map_err(|source| OutputError::Exr {
                path: path.to_path_buf(),
                action: "encoding",
                source,
            })?;
        // The encoder keeps attributes in a hash map, whose order changes from run to run:
        // put them in a fixed order, in place (the header keeps its length, so the offsets
        // that follow it stay valid).
        std::io::Write::flush(writer).map_err(|e| OutputError::io(path, "write", e))?;
        super::exr_header_order::sort_header_attributes_in_file(writer.get_mut())
            .map_err(|problem| OutputError::invalid(path, problem))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::channels::Layer;
    use exr::prelude::ReadChannels;
    use exr::prelude::ReadLayers;

    fn filled_film() -> Film {
        let layers = Layer::ALL;
        let mut film = Film::new(7, 5, &layers);
        for (ci, name) in film.channel_names().iter().enumerate() {
            let plane = film.channel_mut(name).unwrap();
            for (i, v) in plane.iter_mut().enumerate() {
                // Values that f16 could not hold exactly, negative, huge and tiny ones.
                *v = (i as f32 + 0.1) * (ci as f32 + 1.0) * if i % 3 == 0 { -1.0 } else { 1.0 };
            }
        }
        film.channel_mut("Z").unwrap()[0] = f32::INFINITY;
        film.channel_mut("lod").unwrap()[1] = 1.0e-30;
        film.channel_mut("footprint").unwrap()[2] = 3.0e38;
        film
    }

    #[test]
    fn exr_reads_back_with_exact_names_values_and_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("render.exr");
        let film = filled_film();
        let mut attributes = ExrAttributes {
            software: Some("conetrace test".into()),
            incomplete: true,
            finished_tiles: Some(12),
            ..Default::default()
        };
        attributes
            .strings
            .insert("conetrace.scene".into(), "cornell.toml".into());
        write_exr(&film, &path, &attributes).unwrap();

        // Read with the exr crate directly, independent of `read_exr`.
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(&path)
            .unwrap();
        let layer = &image.layer_data;
        assert_eq!(layer.size.0, 7);
        assert_eq!(layer.size.1, 5);
        let mut expected: Vec<String> = film.channel_names();
        expected.sort();
        let names: Vec<String> = layer
            .channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        assert_eq!(names, expected);
        for channel in &layer.channel_data.list {
            let FlatSamples::F32(values) = &channel.sample_data else {
                panic!("channel {} not stored as f32", channel.name);
            };
            let original = film.channel(&channel.name.to_string()).unwrap();
            assert_eq!(values.len(), original.len());
            for (a, b) in values.iter().zip(original) {
                assert_eq!(a.to_bits(), b.to_bits(), "channel {}", channel.name);
            }
        }
        let attrs = &layer.attributes;
        assert_eq!(
            attrs.software_name.as_ref().unwrap().to_string(),
            "conetrace test"
        );
        let get = |name: &str| attrs.other.get(&Text::new_or_panic(name)).cloned();
        assert_eq!(get(INCOMPLETE_ATTRIBUTE), Some(AttributeValue::I32(1)));
        assert_eq!(get(FINISHED_TILES_ATTRIBUTE), Some(AttributeValue::I32(12)));
        assert_eq!(
            get("conetrace.scene"),
            Some(AttributeValue::Text(Text::new_or_panic("cornell.toml")))
        );
    }

    #[test]
    fn failed_exr_write_keeps_the_previous_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("render.exr");
        write_exr(&filled_film(), &path, &ExrAttributes::default()).unwrap();
        let before = std::fs::read(&path).unwrap();
        // A non-Latin-1 attribute fails before anything is written ...
        let mut bad = ExrAttributes::default();
        bad.strings
            .insert("conetrace.note".into(), "\u{1F600}".into());
        let err = write_exr(&filled_film(), &path, &bad).unwrap_err();
        assert!(err.to_string().contains("render.exr"), "{err}");
        // ... the encoder itself refuses an over-long name midway through writing ...
        let mut bad = ExrAttributes::default();
        bad.strings.insert("x".repeat(300), "v".into());
        let err = write_exr(&filled_film(), &path, &bad).unwrap_err();
        assert!(matches!(err, OutputError::Exr { .. }), "{err}");
        // ... a standard attribute name cannot be overridden, a NUL cannot be smuggled in ...
        for name in ["software", "channels", "a\0b", INCOMPLETE_ATTRIBUTE] {
            let mut bad = ExrAttributes::default();
            bad.strings.insert(name.into(), "v".into());
            assert!(write_exr(&filled_film(), &path, &bad).is_err(), "{name:?}");
        }
        // ... and an empty film is refused.
        assert!(write_exr(
            &Film::new(0, 0, &[Layer::Color]),
            &path,
            &ExrAttributes::default()
        )
        .is_err());
        assert_eq!(std::fs::read(&path).unwrap(), before);
        let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(leftovers, 1);
    }
}
