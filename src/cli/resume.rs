//! What a partial render records so that `--resume` continues exactly the render it started.
//!
//! A partial render's EXR header carries its *signature*: one plain text attribute per item
//! that changes pixels, each a value a person can read or a SHA-256 digest.
//!
//! - `conetrace.option.<name>`: every pixel-changing option in a canonical spelling (the
//!   command-line names of enumerations, decimal numbers), e.g. `conetrace.option.spp = 16`.
//! - `conetrace.input.<part>`: digests of what the scene holds: its camera, lights,
//!   materials, geometry (every mesh and sphere, with the OBJ/glTF data they came from),
//!   environment and settings, and each texture's file bytes with its sampling settings.
//!   Paths never enter a digest, so the same scene named by a relative or an absolute path
//!   is the same scene.
//! - `conetrace.input.scene_file`: the digest of the scene file's own bytes.
//! - `conetrace.version`: the renderer's version (pixels may differ between versions).
//!
//! `--resume` compares the stored signature with the current one and names the first item
//! that differs, options first, the raw scene file last (a change there that touches none of
//! the other items is, e.g., a comment).
//!
//! The finished tiles are listed in `conetrace.tiles_done` ([`encode_tiles`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::cli::CommandError;
use crate::film;
use crate::film::partial::{format_sample_range, ImageWindow, SAMPLES_ATTRIBUTE};
use crate::film::PixelRect;
use crate::render::part::RenderPart;
use crate::render::RenderOptions;
use crate::scene::SceneDescription;

/// Header attribute listing the finished work tiles (see [`encode_tiles`]).
pub const TILES_DONE_ATTRIBUTE: &str = "conetrace.tiles_done";
/// Header attribute of a partial render: the absolute path of the statistics it wrote beside
/// it (`<stats>.partial.json`), so that the render that completes it removes that file even
/// when `--stats` is not given again.
pub const PARTIAL_STATS_ATTRIBUTE: &str = "conetrace.partial_stats";
/// Prefix of the option items of a signature.
const OPTION_PREFIX: &str = "conetrace.option.";
/// Prefix of the input digests of a signature.
const INPUT_PREFIX: &str = "conetrace.input.";
/// The renderer version item.
const VERSION_ATTRIBUTE: &str = "conetrace.version";

/// True for the header attributes that make up a render's signature (see the module doc):
/// `conetrace merge` requires them equal in every part.
pub fn is_signature_attribute(name: &str) -> bool {
    name.starts_with(OPTION_PREFIX) || name.starts_with(INPUT_PREFIX) || name == VERSION_ATTRIBUTE
}

/// Finished tiles as hexadecimal digits, four tiles per digit (tile `4k + b` is bit `b` of
/// digit `k`), so a 4K image's 32,400 tiles take 8,100 characters.
pub fn encode_tiles(finished: &[bool]) -> String {
    finished
        .chunks(4)
        .map(|bits| {
            let value = bits
                .iter()
                .enumerate()
                .fold(0u32, |acc, (b, &done)| acc | ((done as u32) << b));
            char::from_digit(value, 16).unwrap_or('0')
        })
        .collect()
}

/// The inverse of [`encode_tiles`] for `count` tiles; `None` when the text does not fit.
pub fn decode_tiles(text: &str, count: usize) -> Option<Vec<bool>> {
    if text.len() != count.div_ceil(4) {
        return None;
    }
    let mut finished = Vec::with_capacity(count);
    for c in text.chars() {
        let value = c.to_digit(16)?;
        for b in 0..4 {
            if finished.len() < count {
                finished.push(value & (1 << b) != 0);
            } else if value & (1 << b) != 0 {
                return None;
            }
        }
    }
    Some(finished)
}

/// Everything that changes a render's pixels, item by item (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderSignature {
    /// Attribute name to value, in the order items are compared.
    items: Vec<(String, String)>,
}

/// Incremental SHA-256 over the raw bytes of scene data.
struct ContentDigest(Sha256);

impl ContentDigest {
    fn new() -> Self {
        ContentDigest(Sha256::new())
    }
    fn bytes(&mut self, data: &[u8]) -> &mut Self {
        // Length-prefixed, so consecutive fields cannot run into each other.
        self.0.update((data.len() as u64).to_le_bytes());
        self.0.update(data);
        self
    }
    fn floats(&mut self, values: impl IntoIterator<Item = f32>) -> &mut Self {
        let data: Vec<u8> = values.into_iter().flat_map(f32::to_le_bytes).collect();
        self.bytes(&data)
    }
    /// Small descriptive structs (camera, lights, materials) by their derived text: stable
    /// within one renderer version, which the signature records too.
    fn text(&mut self, value: &impl std::fmt::Debug) -> &mut Self {
        self.bytes(format!("{value:?}").as_bytes())
    }
    fn hex(&self) -> String {
        self.0
            .clone()
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }
}

fn digest_file(path: &Path) -> Result<String, CommandError> {
    let bytes = std::fs::read(path)
        .map_err(|e| CommandError::bad_input(format!("{}: cannot read: {e}", path.display())))?;
    Ok(encoded_texture_digest(&bytes))
}

/// The digest of a texture's encoded bytes (its file, or its embedded data), one of the
/// inputs of [`RenderSignature::new`]. Taken from the bytes the texture is decoded from, so
/// a render reads each texture file once.
pub fn encoded_texture_digest(bytes: &[u8]) -> String {
    ContentDigest::new().bytes(bytes).hex()
}

/// The digest of a demand-loaded texture file, from what identifies it without reading its
/// tiles ([`crate::texture::Texture::file_identity`]: length, modification time and every
/// level's tile offsets and byte counts), so that opening a 1 GB `.tx` reads kilobytes.
/// Tagged apart from [`encoded_texture_digest`]: the two never coincide.
pub fn tiled_texture_digest(identity: &[u64]) -> String {
    let mut digest = ContentDigest::new();
    digest.bytes(b"tiled texture file: length, mtime, tile tables\0");
    for word in identity {
        digest.bytes(&word.to_le_bytes());
    }
    digest.hex()
}

impl RenderSignature {
    /// The signature of rendering `scene` (loaded from `scene_file`, `None` for the built-in
    /// scene) with `options`; `texture_digests` holds [`encoded_texture_digest`] of each of
    /// the scene's textures, in order.
    pub fn new(
        scene: &SceneDescription,
        scene_file: Option<&Path>,
        options: &RenderOptions,
        texture_digests: &[String],
    ) -> Result<RenderSignature, CommandError> {
        let mut items = Vec::new();
        let mut option = |name: &str, value: String| {
            items.push((format!("{OPTION_PREFIX}{name}"), value));
        };
        option("width", options.width.to_string());
        option("height", options.height.to_string());
        option("spp", options.spp.to_string());
        option("seed", options.seed.to_string());
        option("max-depth", options.max_depth.to_string());
        option("min-throughput", options.min_throughput.to_string());
        option("lod", options.lod.name().to_string());
        option("filter", options.filter.filter.to_string());
        option("max-aniso", options.filter.max_aniso.to_string());
        option(
            "fresnel",
            match options.fresnel {
                crate::scene::FresnelMode::Exact => "exact",
                crate::scene::FresnelMode::Schlick => "schlick",
            }
            .to_string(),
        );
        let flag = |on: bool| if on { "on" } else { "off" }.to_string();
        option("aov-surface", flag(options.aovs.surface));
        option("aov-footprint", flag(options.aovs.texture_footprint));
        option("aov-lod", flag(options.aovs.lod));
        option("all-effects", flag(options.all_effects));
        option(
            "clamp",
            options
                .sample_clamp
                .map_or_else(|| "off".to_string(), |value| value.to_string()),
        );

        let mut input = |name: &str, digest: &ContentDigest| {
            items.push((format!("{INPUT_PREFIX}{name}"), digest.hex()));
        };
        input("camera", ContentDigest::new().text(&scene.camera));
        input("lights", ContentDigest::new().text(&scene.lights));
        input("materials", ContentDigest::new().text(&scene.materials));
        input("environment", ContentDigest::new().text(&scene.environment));
        input("settings", ContentDigest::new().text(&scene.settings));
        let mut geometry = ContentDigest::new();
        for mesh in &scene.meshes {
            geometry
                .floats(mesh.positions.iter().flat_map(|p| p.to_array()))
                .floats(mesh.normals.iter().flat_map(|n| n.to_array()))
                .floats(mesh.st.iter().flat_map(|st| st.to_array()))
                .bytes(
                    &mesh
                        .triangles
                        .iter()
                        .flat_map(|t| t.iter().flat_map(|i| i.to_le_bytes()))
                        .collect::<Vec<u8>>(),
                )
                .bytes(&(mesh.material as u64).to_le_bytes());
        }
        geometry.text(&scene.spheres);
        geometry.text(&scene.patches);
        input("geometry", &geometry);
        for (index, (texture, encoded)) in scene.textures.iter().zip(texture_digests).enumerate() {
            let mut digest = ContentDigest::new();
            digest.text(&(texture.color_space, texture.wrap_s, texture.wrap_t));
            digest.bytes(encoded.as_bytes());
            input(&format!("texture.{index}"), &digest);
        }
        let scene_file_digest = match scene_file {
            Some(path) => digest_file(path)?,
            None => "built-in".to_string(),
        };
        items.push((format!("{INPUT_PREFIX}scene_file"), scene_file_digest));
        items.push((
            VERSION_ATTRIBUTE.to_string(),
            env!("CARGO_PKG_VERSION").to_string(),
        ));
        Ok(RenderSignature { items })
    }

    /// The signature as EXR header attributes.
    pub fn attributes(&self) -> impl Iterator<Item = (&str, &str)> {
        self.items.iter().map(|(k, v)| (k.as_str(), v.as_str()))
    }

    /// Compares with a stored signature: `None` when they agree, else a description of the
    /// first item that differs (for a message such as "--resume: <it>").
    pub fn difference(
        &self,
        stored: &BTreeMap<String, String>,
        scene: &SceneDescription,
    ) -> Option<String> {
        for (name, now) in &self.items {
            let Some(before) = stored.get(name) else {
                return Some(format!("the partial render has no {name} attribute"));
            };
            if before == now {
                continue;
            }
            return Some(if let Some(option) = name.strip_prefix(OPTION_PREFIX) {
                format!("option --{option} changed (partial render: {before}, now: {now})")
            } else if let Some(part) = name.strip_prefix("conetrace.input.texture.") {
                let label = part
                    .parse::<usize>()
                    .ok()
                    .and_then(|i| scene.textures.get(i))
                    .map(|t| t.source.label())
                    .unwrap_or_else(|| part.to_string());
                format!("texture {label} changed since the partial render")
            } else if name == "conetrace.input.scene_file" {
                "the scene file changed since the partial render".to_string()
            } else if let Some(part) = name.strip_prefix(INPUT_PREFIX) {
                format!("the scene's {part} changed since the partial render")
            } else {
                format!("{name} changed (partial render: {before}, now: {now})")
            });
        }
        // A scene with fewer textures than before.
        let texture_count = self
            .items
            .iter()
            .filter(|(k, _)| k.starts_with("conetrace.input.texture."))
            .count();
        let stored_textures = stored
            .keys()
            .filter(|k| k.starts_with("conetrace.input.texture."))
            .count();
        (texture_count != stored_textures).then(|| {
            format!(
                "the scene's textures changed since the partial render ({stored_textures} then, \
                 {texture_count} now)"
            )
        })
    }
}

/// The earlier, partial render `--resume` continues.
pub struct ResumeState {
    /// The earlier run's film, of the part's region.
    pub film: film::Film,
    /// Per work tile: finished by the earlier run.
    pub finished: Vec<bool>,
    /// The statistics file the earlier run wrote beside its partial EXR, when it still holds
    /// an incomplete render's statistics.
    pub partial_stats: Option<PathBuf>,
}

/// The partial statistics file named by a partial EXR's header, if that file is one: a JSON
/// object whose `complete` is false. A header is data anyone can edit, and the file it names
/// is going to be removed.
fn recorded_partial_stats(attributes: &film::ExrAttributes) -> Option<PathBuf> {
    let path = PathBuf::from(attributes.strings.get(PARTIAL_STATS_ATTRIBUTE)?);
    let text = std::fs::read_to_string(&path).ok()?;
    let stats: serde_json::Value = serde_json::from_str(&text).ok()?;
    (stats.get("complete") == Some(&serde_json::Value::Bool(false))).then_some(path)
}

/// The header value recording `partial_stats` (see [`PARTIAL_STATS_ATTRIBUTE`]): absolute,
/// so a resume from another working directory finds it.
pub fn partial_stats_record(partial_stats: &Path) -> String {
    std::path::absolute(partial_stats)
        .unwrap_or_else(|_| partial_stats.to_path_buf())
        .display()
        .to_string()
}

/// The earlier, partial render `--resume` continues: its film (of `part`'s region) and
/// finished tiles (`part`'s), after checking that it was made with the same `signature` and
/// the same region and sample range.
pub fn read_resume_state(
    partial_path: &Path,
    signature: &RenderSignature,
    scene: &SceneDescription,
    options: &RenderOptions,
    part: &RenderPart,
) -> Result<ResumeState, CommandError> {
    let label = partial_path.display();
    if !partial_path.exists() {
        return Err(CommandError::bad_input(format!(
            "{label}: --resume: no partial render to continue (an interrupted render writes it)"
        )));
    }
    let (earlier, attributes) = film::read_exr(partial_path)
        .map_err(|e| CommandError::bad_input(format!("--resume: {e}")))?;
    if !attributes.strings.contains_key(VERSION_ATTRIBUTE) {
        return Err(CommandError::bad_input(format!(
            "{label}: --resume: not a partial conetrace render (no {VERSION_ATTRIBUTE} attribute)"
        )));
    }
    if let Some(what) = signature.difference(&attributes.strings, scene) {
        return Err(CommandError::bad_input(format!(
            "{label}: --resume: {what}"
        )));
    }
    check_same_part(&earlier, &attributes, options, part)
        .map_err(|what| CommandError::bad_input(format!("{label}: --resume: {what}")))?;
    let expected = part.film_layers(options);
    if let Some(missing) = expected.iter().find(|layer| !earlier.has(**layer)) {
        return Err(CommandError::bad_input(format!(
            "{label}: --resume: the partial image lacks the {missing:?} channels"
        )));
    }
    let finished = attributes
        .strings
        .get(TILES_DONE_ATTRIBUTE)
        .and_then(|text| decode_tiles(text, part.tiles(options.width, options.height).len()))
        .ok_or_else(|| {
            CommandError::bad_input(format!(
                "{label}: --resume: missing or malformed {TILES_DONE_ATTRIBUTE} attribute"
            ))
        })?;
    Ok(ResumeState {
        film: earlier,
        finished,
        partial_stats: recorded_partial_stats(&attributes),
    })
}

/// Checks that a partial render's film and header hold `part`: the same region of an image
/// of the render's size (the header may agree while the pixels do not, in an edited or
/// foreign file, and the finished tiles are copied from this film) and the same samples.
fn check_same_part(
    earlier: &film::Film,
    attributes: &film::ExrAttributes,
    options: &RenderOptions,
    part: &RenderPart,
) -> Result<(), String> {
    let (width, height) = (earlier.width(), earlier.height());
    let window = attributes.window.unwrap_or(ImageWindow {
        x0: 0,
        y0: 0,
        full_width: width,
        full_height: height,
    });
    let full = (window.full_width, window.full_height);
    if full != (options.width, options.height) {
        return Err(format!(
            "the partial image is {}x{}, the render {}x{}",
            full.0, full.1, options.width, options.height
        ));
    }
    let region = window.rect(width, height);
    if region != part.region {
        let corners =
            |r: PixelRect| format!("{},{},{},{}", r.x0, r.y0, r.x0 + r.width, r.y0 + r.height);
        return Err(format!(
            "the partial render holds the region {}, this render {}",
            corners(region),
            corners(part.region)
        ));
    }
    let samples = attributes.strings.get(SAMPLES_ATTRIBUTE);
    let wanted = format_sample_range(&part.samples);
    if samples != Some(&wanted) {
        return Err(format!(
            "the partial render holds the samples {}, this render {wanted}",
            samples.map_or("(none recorded)", String::as_str)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::TextureSource;

    #[test]
    fn only_an_incomplete_render_s_statistics_are_taken_for_partial_ones() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let header = |path: &Path| {
            let mut attributes = film::ExrAttributes::default();
            attributes.strings.insert(
                PARTIAL_STATS_ATTRIBUTE.to_string(),
                partial_stats_record(path),
            );
            attributes
        };
        let partial = dir.path().join("s.partial.json");
        std::fs::write(&partial, r#"{"scene": "a.toml", "complete": false}"#).unwrap();
        assert_eq!(recorded_partial_stats(&header(&partial)), Some(partial));
        for (name, text) in [
            ("complete.json", r#"{"complete": true}"#),
            ("other.json", r#"{"scene": "a.toml"}"#),
            ("notes.txt", "complete: false"),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            assert_eq!(recorded_partial_stats(&header(&path)), None, "{name}");
        }
        let missing = dir.path().join("gone.partial.json");
        assert_eq!(recorded_partial_stats(&header(&missing)), None);
        assert_eq!(
            recorded_partial_stats(&film::ExrAttributes::default()),
            None
        );
    }

    #[test]
    fn tile_lists_round_trip_through_their_text() {
        for count in [1usize, 3, 4, 5, 17, 64] {
            let finished: Vec<bool> = (0..count).map(|i| (i * 7) % 3 == 0).collect();
            let text = encode_tiles(&finished);
            assert_eq!(text.len(), count.div_ceil(4));
            assert_eq!(decode_tiles(&text, count), Some(finished));
        }
        assert_eq!(encode_tiles(&[true, false, false, true, true]), "91");
        // Wrong length, non-hex digits and bits past the end are refused.
        assert_eq!(decode_tiles("9", 5), None);
        assert_eq!(decode_tiles("9g", 5), None);
        assert_eq!(decode_tiles("93", 5), None);
    }

    fn stored(signature: &RenderSignature) -> BTreeMap<String, String> {
        signature
            .attributes()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn each_change_is_named() {
        use clap::Parser;
        let scene = crate::scene::load::default_scene();
        let cli =
            crate::cli::Cli::try_parse_from(["conetrace", "render", "--width", "64"]).unwrap();
        let crate::cli::Command::Render(args) = cli.command else {
            unreachable!("parsed a render command")
        };
        let options = crate::cli::render_cmd::options(&args, &scene).unwrap();
        let digests: Vec<String> = scene
            .textures
            .iter()
            .map(|t| match &t.source {
                TextureSource::File(path) => encoded_texture_digest(&std::fs::read(path).unwrap()),
                TextureSource::Encoded { bytes, .. } => encoded_texture_digest(bytes),
            })
            .collect();
        let base = RenderSignature::new(&scene, None, &options, &digests).unwrap();
        assert_eq!(base.difference(&stored(&base), &scene), None);

        let more_samples = crate::render::RenderOptions {
            spp: 16,
            ..options.clone()
        };
        let now = RenderSignature::new(&scene, None, &more_samples, &digests).unwrap();
        let what = now.difference(&stored(&base), &scene).unwrap();
        assert!(what.contains("--spp") && what.contains("16"), "{what}");

        let other_seed = crate::render::RenderOptions {
            seed: 5,
            ..options.clone()
        };
        let now = RenderSignature::new(&scene, None, &other_seed, &digests).unwrap();
        let what = now.difference(&stored(&base), &scene).unwrap();
        assert!(what.contains("--seed") && what.contains('5'), "{what}");

        let mut brighter = scene.clone();
        match brighter
            .lights
            .first_mut()
            .expect("the default scene has a light")
        {
            crate::scene::Light::Point { intensity, .. }
            | crate::scene::Light::Directional { intensity, .. }
            | crate::scene::Light::Spot { intensity, .. } => *intensity *= 2.0,
        }
        let now = RenderSignature::new(&brighter, None, &options, &digests).unwrap();
        let what = now.difference(&stored(&base), &scene).unwrap();
        assert!(what.contains("lights"), "{what}");

        let mut moved = scene.clone();
        moved.meshes[0].positions[0].x += 1e-3;
        let now = RenderSignature::new(&moved, None, &options, &digests).unwrap();
        let what = now.difference(&stored(&base), &scene).unwrap();
        assert!(what.contains("geometry"), "{what}");
    }
}
