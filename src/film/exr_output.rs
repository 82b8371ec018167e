//! Writing a film as a single-part OpenEXR file with every channel as 32-bit float.
//!
//! Channel names are the conventional ones of [`super::Layer`] (OpenEXR stores them sorted
//! alphabetically; readers find them by name). Scanlines are ZIP-compressed (lossless).
//! Besides the standard `software` attribute, the header carries `conetrace.incomplete`
//! (int, 1 while the render is unfinished) and `conetrace.finished_tiles` (int) so that
//! `--resume` can tell a partial image from a finished one, plus any free-form text
//! attributes. The file is written atomically (see [`super::atomic_file`]).

use std::collections::BTreeMap;
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, LayerAttributes, Text,
    WritableImage,
};

use super::atomic_file::write_atomically;
use super::error::OutputError;
use super::film::Film;

/// Header attribute name of the "render is incomplete" flag (int 0 or 1).
pub const INCOMPLETE_ATTRIBUTE: &str = "conetrace.incomplete";
/// Header attribute name of the number of finished tiles (int).
pub const FINISHED_TILES_ATTRIBUTE: &str = "conetrace.finished_tiles";

/// Metadata stored in (and read back from) an EXR header.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
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
}

fn exr_text(path: &Path, what: &str, text: &str) -> Result<Text, OutputError> {
    Text::new_or_none(text)
        .ok_or_else(|| OutputError::invalid(path, format!("{what} {text:?} is not Latin-1 text")))
}

/// Writes every channel of `film` as `f32` to `path` (atomically; the parent directory is
/// created if missing) with the header `attributes`.
pub fn write_exr(film: &Film, path: &Path, attributes: &ExrAttributes) -> Result<(), OutputError> {
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
    for (name, value) in &attributes.strings {
        // A NUL would end the name early in the header and corrupt the file.
        if name.is_empty()
            || name.contains('\0')
            || name == INCOMPLETE_ATTRIBUTE
            || name == FINISHED_TILES_ATTRIBUTE
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

    let layer = exr::prelude::Layer::new(
        (film.width() as usize, film.height() as usize),
        layer_attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let image = Image::from_layer(layer);
    write_atomically(path, |writer| {
        image
            .write()
            .to_buffered(writer)
            .map_err(|source| OutputError::Exr {
                path: path.to_path_buf(),
                action: "encoding",
                source,
            })
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
