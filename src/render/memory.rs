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
//! - every texture decoded whole with its mip levels, in the precision it is stored in (4
//!   bytes a texel for 8-bit sources, 8 for half, 16 otherwise), from the file headers,
//!   nothing decoded;
//! - the texture cache of the demand-loaded textures (tiled, mip-mapped `.tx` files read
//!   tile by tile): their texel bytes, but at most the cache's cap, plus what comes on top
//!   of the cap (see `texture::tile_cache`): the tiles each worker's micro-cache may keep
//!   alive after their eviction, and one slot per tile of every level.
//!
//! The limit is `--max-memory` when given, else the memory the system reports available
//! (`MemAvailable` in `/proc/meminfo`); where neither is known, nothing is refused.

use std::fmt;

use crate::render::context::RenderOptions;
use crate::scene::{SceneDescription, TextureSource};
use crate::texture::{demand_level_sizes, encoded_texture_header, file_texture_header};

/// What a render is estimated to need, in bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub film: u64,
    pub tiles: u64,
    pub outputs: u64,
    /// Per texture decoded whole: its label and decoded size.
    pub textures: Vec<(String, u64)>,
    /// The demand-loaded textures' cache: their texel bytes up to the cap, plus the
    /// micro-caches' tiles and the tile slots.
    pub texture_cache: u64,
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
            + self.texture_cache
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

/// Estimates the memory of rendering `scene` with `options`, demand-loaded textures in a
/// cache capped at `texture_cache` bytes. A texture whose header cannot be read is an
/// error naming it (the render would fail on it anyway).
pub fn estimate(
    scene: &SceneDescription,
    options: &RenderOptions,
    texture_cache: u64,
) -> Result<MemoryEstimate, crate::texture::TextureError> {
    estimate_decoding(scene, options, texture_cache, |_| true)
}

/// [`estimate`] counting only the textures `decoded(index)` says the render decodes (with a
/// texture callback, the ones it serves are never decoded and their files need not exist).
pub fn estimate_decoding(
    scene: &SceneDescription,
    options: &RenderOptions,
    texture_cache: u64,
    decoded: impl Fn(usize) -> bool,
) -> Result<MemoryEstimate, crate::texture::TextureError> {
    let pixels = u64::from(options.width) * u64::from(options.height);
    let channels: u64 = crate::render::film_layers(options.aovs)
        .iter()
        .map(|layer| layer.channel_count() as u64)
        .sum();
    let film = pixels * channels * 4;
    let workers = rayon::current_num_threads() as u64;
    let mut textures = Vec::new();
    let mut cache = DemandTextures::default();
    for (_, texture) in scene
        .textures
        .iter()
        .enumerate()
        .filter(|(i, _)| decoded(*i))
    {
        let header = match &texture.source {
            TextureSource::File(path) => {
                let header = file_texture_header(path)?;
                if let Some(levels) = demand_level_sizes(path)? {
                    cache.add(&header, &levels);
                    continue;
                }
                header
            }
            TextureSource::Encoded { label, bytes } => encoded_texture_header(bytes, label)?,
        };
        textures.push((texture.source.label(), header.decoded_bytes()));
    }
    // Per worker: a tile's pixels (at most every channel of every pixel, plus a flag) and
    // the film band it writes into cut into per-tile row slices (one slice per channel, row
    // and tile column; see `film::regions`).
    let tile = crate::render::WORK_TILE_SIZE as u64;
    let tile_pixels = tile * tile * (channels * 4 + 1);
    let band_slices = channels
        * tile
        * u64::from(options.width.div_ceil(crate::render::WORK_TILE_SIZE))
        * std::mem::size_of::<&mut [f32]>() as u64;
    Ok(MemoryEstimate {
        film,
        tiles: workers * (tile_pixels + band_slices),
        outputs: film + pixels * 4,
        textures,
        texture_cache: cache.bytes(texture_cache, workers),
        voxels: 0,
    })
}

/// The demand-loaded textures of a scene, as the texture cache holds them.
#[derive(Default)]
struct DemandTextures {
    /// Texel bytes of every level of every one of them.
    texels: u64,
    /// Tiles over every level of every one of them (each has a slot).
    tiles: u64,
    /// Bytes of the largest full tile among them.
    largest_tile: u64,
}

impl DemandTextures {
    /// Adds a texture whose header is `header` and whose stored levels are `levels`.
    fn add(&mut self, header: &crate::texture::TextureHeader, levels: &[(u32, u32)]) {
        let tile = u64::from(crate::texture::TEXTURE_TILE_SIZE);
        for &(w, h) in levels {
            let (w, h) = (u64::from(w), u64::from(h));
            self.texels += w * h * header.bytes_per_texel;
            self.tiles += w.div_ceil(tile) * h.div_ceil(tile);
        }
        self.largest_tile = self.largest_tile.max(tile * tile * header.bytes_per_texel);
    }

    /// Bytes under a cache capped at `cap` rendered by `workers` threads: the texels up to
    /// the cap, each worker's micro-cache full of the largest tiles, and the slots.
    fn bytes(&self, cap: u64, workers: u64) -> u64 {
        if self.tiles == 0 {
            return 0;
        }
        self.texels.min(cap)
            + workers * crate::texture::MICRO_TILES as u64 * self.largest_tile
            + self.tiles * crate::texture::SLOT_BYTES
    }
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
    let cache = if estimate.texture_cache > 0 {
        format!(", texture cache {}", Bytes(estimate.texture_cache))
    } else {
        String::new()
    };
    Err(format!(
        "{label}: the render needs about {} (film {}, tiles {}, outputs {}, textures {}{}{cache}{}), \
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
            .install(|| estimate(&SceneDescription::default(), &options, 256 << 20))
            .unwrap();
        assert!(
            estimate.tiles * 10 < estimate.film,
            "tiles {} vs film {} bytes",
            estimate.tiles,
            estimate.film
        );
        assert!(estimate.tiles > 0);
    }

    /// A noise PNG of `size`x`size` made into a 64x64-tiled `.tx` (8-bit) in `dir`.
    fn noise_tx(dir: &std::path::Path, name: &str, size: u32) -> std::path::PathBuf {
        let mut state = 0x2545_f491_4f6c_dd1du64 ^ u64::from(size);
        let image = image::RgbImage::from_fn(size, size, |_, _| {
            image::Rgb(std::array::from_fn(|_| {
                (crate::test_rng::xorshift64_star(&mut state) >> 56) as u8
            }))
        });
        let png = dir.join(format!("{name}.png"));
        image.save(&png).unwrap();
        let tx = dir.join(format!("{name}.tx"));
        let status = std::process::Command::new("maketx")
            .arg(&png)
            .arg("-o")
            .arg(&tx)
            .status()
            .expect("maketx must be installed (scripts/setup.sh)");
        assert!(status.success(), "maketx failed");
        tx
    }

    fn texture(name: &str, path: &std::path::Path) -> crate::scene::TextureDesc {
        crate::scene::TextureDesc {
            name: name.into(),
            source: TextureSource::File(path.to_path_buf()),
            color_space: Some(crate::texture::ColorSpace::Srgb),
            wrap_s: crate::texture::WrapMode::Periodic,
            wrap_t: crate::texture::WrapMode::Periodic,
        }
    }

    /// Demand-loaded textures larger than the cache's cap are estimated at the cap plus
    /// the micro-caches and slots, not at their decoded size; textures decoded whole still
    /// count whole.
    #[test]
    fn demand_loaded_textures_count_at_most_the_cap_plus_the_overhead() {
        let dir = tempfile::tempdir().unwrap();
        let mut scene = SceneDescription {
            textures: vec![
                texture("a", &noise_tx(dir.path(), "a", 512)),
                texture("b", &noise_tx(dir.path(), "b", 300)),
            ],
            ..SceneDescription::default()
        };
        let options = RenderOptions::from_settings(&crate::scene::RenderSettings::default());
        let workers = 3u64;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(workers as usize)
            .build()
            .unwrap();
        let decoded: u64 = scene
            .textures
            .iter()
            .map(|t| match &t.source {
                TextureSource::File(path) => file_texture_header(path).unwrap().decoded_bytes(),
                TextureSource::Encoded { .. } => unreachable!(),
            })
            .sum();
        let cap = 64 << 10;
        assert!(decoded > 10 * cap, "{decoded}");
        let capped = pool.install(|| estimate(&scene, &options, cap)).unwrap();
        assert!(capped.textures.is_empty(), "{:?}", capped.textures);
        // Per worker, 8 tiles of 16 KiB (8-bit RGBA); a slot per tile: 91 + 44 over the
        // levels of the two textures.
        let micro = workers * crate::texture::MICRO_TILES as u64 * 64 * 64 * 4;
        let slots = 135 * crate::texture::SLOT_BYTES;
        assert_eq!(capped.texture_cache, cap + micro + slots);
        // Under a cap larger than both, their texels count once, as decoded.
        let roomy = pool
            .install(|| estimate(&scene, &options, 1 << 30))
            .unwrap();
        assert_eq!(roomy.texture_cache, decoded + micro + slots);
        assert_eq!(
            capped.total() - capped.texture_cache,
            roomy.total() - roomy.texture_cache
        );
        // A texture decoded whole (a PNG) counts whole, beside the cache.
        scene.textures.push(texture("c", &dir.path().join("a.png")));
        let mixed = pool.install(|| estimate(&scene, &options, cap)).unwrap();
        assert_eq!(mixed.textures.len(), 1);
        assert_eq!(mixed.texture_cache, capped.texture_cache);
    }

    #[test]
    fn a_large_image_is_refused_with_its_estimate() {
        let estimate = MemoryEstimate {
            film: 200 << 30,
            tiles: 200 << 30,
            outputs: 216 << 30,
            textures: vec![("sky.png".into(), 1 << 20)],
            texture_cache: 0,
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
