//! The memory a render will need, estimated before anything large is allocated.
//!
//! An image or a texture set that cannot fit is refused up front with the estimate, instead
//! of the process aborting halfway when an allocation fails. The estimate counts what the
//! render holds at its peak:
//!
//! - the film: one f32 plane per channel of the layers the options ask for;
//! - the work tiles in flight: per worker thread, one tile's pixels and the slices of the
//!   film band it writes into (finished tiles go straight into the film, so this is small);
//! - the outputs: the EXR encoder's copy of every plane and the PNG's 8-bit pixels;
//! - every texture with its mip levels, in the precision it is stored in (4 bytes a texel
//!   for 8-bit sources, 8 for half, 16 otherwise), from the file headers, nothing decoded.
//!
//! The limit is `--max-memory` when given, else the memory the system reports available
//! (`MemAvailable` in `/proc/meminfo`); where neither is known, nothing is refused.

use std::fmt;

use crate::render::context::RenderOptions;
use crate::scene::{SceneDescription, TextureSource};
use crate::texture::{encoded_texture_header, file_texture_header};

/// What a render is estimated to need, in bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub film: u64,
    pub tiles: u64,
    pub outputs: u64,
    /// Per texture: its label and decoded size.
    pub textures: Vec<(String, u64)>,
    /// The voxel pyramid of the voxel cone tracer (0 for the other integrators); the caller
    /// that knows the integrator sets it.
    pub voxels: u64,
}

impl MemoryEstimate {
    /// Adds `channels` f32 channels over `pixels` to the film and, as the EXR encoder copies
    /// every plane, to the outputs: e.g. the exact sample sums of a render of a sample range
    /// ([`crate::film::Layer::SampleSum`], 18 channels).
    pub fn add_film_channels(&mut self, pixels: u64, channels: u64) {
        let bytes = pixels * channels * 4;
        self.film += bytes;
        self.outputs += bytes;
    }

    /// The sum of every part.
    pub fn total(&self) -> u64 {
        self.film
            + self.tiles
            + self.outputs
            + self.voxels
            + self.textures.iter().map(|t| t.1).sum::<u64>()
    }
}

/// Bytes as a person reads them (GiB, MiB, KiB, bytes).
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0 as f64;
        const KIB: f64 = 1024.0;
        if b >= KIB * KIB * KIB {
            write!(f, "{:.1} GiB", b / (KIB * KIB * KIB))
        } else if b >= KIB * KIB {
            write!(f, "{:.1} MiB", b / (KIB * KIB))
        } else if b >= KIB {
            write!(f, "{:.1} KiB", b / KIB)
        } else {
            write!(f, "{} bytes", self.0)
        }
    }
}

/// Estimates the memory of rendering `scene` with `options`. A texture whose header cannot
/// be read is an error naming it (the render would fail on it anyway).
pub fn estimate(
    scene: &SceneDescription,
    options: &RenderOptions,
) -> Result<MemoryEstimate, crate::texture::TextureError> {
    estimate_decoding(scene, options, |_| true)
}

/// [`estimate`] counting only the textures `decoded(index)` says the render decodes (with a
/// texture callback, the ones it serves are never decoded and their files need not exist).
pub fn estimate_decoding(
    scene: &SceneDescription,
    options: &RenderOptions,
    decoded: impl Fn(usize) -> bool,
) -> Result<MemoryEstimate, crate::texture::TextureError> {
    let pixels = u64::from(options.width) * u64::from(options.height);
    let channels: u64 = crate::render::film_layers(options.aovs)
        .iter()
        .map(|layer| layer.channel_count() as u64)
        .sum();
    let film = pixels * channels * 4;
    let textures = scene
        .textures
        .iter()
        .enumerate()
        .filter(|(index, _)| decoded(*index))
        .map(|(_, texture)| {
            let header = match &texture.source {
                TextureSource::File(path) => file_texture_header(path)?,
                TextureSource::Encoded { label, bytes } => encoded_texture_header(bytes, label)?,
            };
            Ok((texture.source.label(), header.decoded_bytes()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // Per worker: a tile's pixels (at most every channel of every pixel, plus a flag) and
    // the film band it writes into cut into per-tile row slices (one slice per channel, row
    // and tile column; see `film::regions`).
    let tile = crate::render::WORK_TILE_SIZE as u64;
    let tile_pixels = tile * tile * (channels * 4 + 1);
    let band_slices = channels
        * tile
        * u64::from(options.width.div_ceil(crate::render::WORK_TILE_SIZE))
        * std::mem::size_of::<&mut [f32]>() as u64;
    let workers = rayon::current_num_threads() as u64;
    Ok(MemoryEstimate {
        film,
        tiles: workers * (tile_pixels + band_slices),
        outputs: film + pixels * 4,
        textures,
        voxels: 0,
    })
}

/// `MemAvailable` from `/proc/meminfo`, in bytes, where the system reports it.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_mem_available(&text)
}

fn parse_mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Parses a memory size such as `512M`, `8G`, `1.5GiB` or `1000000` (bytes).
pub fn parse_memory_size(text: &str) -> Result<u64, String> {
    let trimmed = text.trim();
    let split = trimmed
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(trimmed.len());
    let (number, unit) = trimmed.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{text}' is not a memory size (e.g. 512M, 8G)"))?;
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        other => return Err(format!("'{text}': unknown unit '{other}' (K, M, G or T)")),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0) {
        return Err(format!("'{text}' is not a positive memory size"));
    }
    Ok(bytes as u64)
}

/// Refuses a render whose estimate exceeds `limit` (or the available memory when `None`),
/// with a one-line message giving the estimate and its largest parts.
pub fn check(estimate: &MemoryEstimate, limit: Option<u64>, label: &str) -> Result<(), String> {
    check_against(estimate, limit, "--max-memory", label)
}

/// [`check`] naming the limit `limit_name` in the message (an option or a field).
pub fn check_against(
    estimate: &MemoryEstimate,
    limit: Option<u64>,
    limit_name: &str,
    label: &str,
) -> Result<(), String> {
    let (limit, source) = match limit {
        Some(limit) => (limit, limit_name),
        None => match available_memory() {
            Some(available) => (available, "available memory"),
            None => return Ok(()),
        },
    };
    let total = estimate.total();
    if total <= limit {
        return Ok(());
    }
    let largest_texture = estimate
        .textures
        .iter()
        .max_by_key(|t| t.1)
        .map(|(name, bytes)| format!(", largest texture {name} {}", Bytes(*bytes)))
        .unwrap_or_default();
    let voxels = if estimate.voxels > 0 {
        format!(", voxel pyramid {}", Bytes(estimate.voxels))
    } else {
        String::new()
    };
    Err(format!(
        "{label}: the render needs about {} (film {}, tiles {}, outputs {}, textures {}{}{}), \
         more than the {} of {source}",
        Bytes(total),
        Bytes(estimate.film),
        Bytes(estimate.tiles),
        Bytes(estimate.outputs),
        Bytes(estimate.textures.iter().map(|t| t.1).sum()),
        largest_texture,
        voxels,
        Bytes(limit),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_memory_size("1000").unwrap(), 1000);
        assert_eq!(parse_memory_size("512M").unwrap(), 512 << 20);
        assert_eq!(parse_memory_size("1.5GiB").unwrap(), 3 << 29);
        assert_eq!(parse_memory_size("8g").unwrap(), 8 << 30);
        for bad in ["", "-1G", "12Q", "G", "0"] {
            assert!(parse_memory_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn mem_available_is_read_from_meminfo_text() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(parse_mem_available(text), Some(20_000_000 * 1024));
        assert_eq!(parse_mem_available("MemTotal: 1 kB\n"), None);
    }

    /// Finished tiles go straight into the film: the tiles in flight cost a sliver of the
    /// film, not a second film.
    #[test]
    fn tiles_in_flight_are_small_beside_the_film() {
        let options = RenderOptions {
            width: 7680,
            height: 4320,
            max_depth: 1,
            min_throughput: 0.0,
            aovs: crate::film::AovSelection::ALL,
            ..RenderOptions::from_settings(&crate::scene::RenderSettings::default())
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(64)
            .build()
            .unwrap();
        let estimate = pool
            .install(|| estimate(&SceneDescription::default(), &options))
            .unwrap();
        assert!(
            estimate.tiles * 10 < estimate.film,
            "tiles {} vs film {} bytes",
            estimate.tiles,
            estimate.film
        );
        assert!(estimate.tiles > 0);
    }

    #[test]
    fn a_large_image_is_refused_with_its_estimate() {
        let estimate = MemoryEstimate {
            film: 200 << 30,
            tiles: 200 << 30,
            outputs: 216 << 30,
            textures: vec![("sky.png".into(), 1 << 20)],
            voxels: 0,
        };
        let message = check(&estimate, Some(8 << 30), "scene.toml").unwrap_err();
        assert!(
            message.contains("616.0 GiB") && message.contains("8.0 GiB"),
            "{message}"
        );
        assert!(
            message.contains("--max-memory") && message.contains("sky.png"),
            "{message}"
        );
        assert!(check(&estimate, Some(1 << 40), "scene.toml").is_ok());
        assert!(!message.contains("voxel"), "{message}");
        // A voxel pyramid counts towards the total and is named.
        let with_voxels = MemoryEstimate {
            voxels: 1 << 40,
            ..estimate
        };
        let message = check(&with_voxels, Some(1 << 40), "scene.toml").unwrap_err();
        assert!(message.contains("voxel pyramid 1024.0 GiB"), "{message}");
    }
}
