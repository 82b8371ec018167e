//! Counters of the work a render did, merged from every worker, printed and written as JSON.
//!
//! Each worker fills its own [`WorkCounters`] over all the tiles it renders; the workers'
//! counters are summed once at the end of the render (no shared total, no lock), so
//! counting costs nothing on the hot path beyond an integer increment.

use serde::Serialize;

/// Kinds of rays the renderer traces, counted separately (seed 001's ray tree).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    Camera,
    Shadow,
    Reflection,
    Refraction,
}

/// Work done by one worker (or, after merging, by the whole render).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct WorkCounters {
    pub camera_rays: u64,
    pub shadow_rays: u64,
    pub reflection_rays: u64,
    pub refraction_rays: u64,
    /// Footprint transfers, reflections and refractions (ray cones or differentials).
    pub footprint_updates: u64,
    /// Filtered texture lookups (surface, environment and alpha textures).
    pub texture_lookups: u64,
    /// Alpha-cutout filter callbacks run by Embree.
    pub filter_callbacks: u64,
    /// Absorption (Beer's law) evaluations.
    pub absorption_evaluations: u64,
    /// Shadow-ray segments traced as closest-hit queries to walk through transmissive
    /// occluders (with opaque occluders only, shadow rays are any-hit occlusion queries).
    pub shadow_walk_queries: u64,
    /// Level-0 voxels the voxel cone tracer's voxelisation filled (zero unless `vct`).
    pub vct_voxels_built: u64,
    /// Cones traced through the voxels by the `vct` integrator.
    pub vct_cones_traced: u64,
    /// Lookups of those cones in the voxel pyramid.
    pub vct_cone_steps: u64,
    /// Path tracing: paths started (one per camera ray), bounces (rays a hit scattered),
    /// paths ended by Russian roulette, and samples dropped because their radiance was not
    /// finite (NaN or infinity never reach the film).
    pub paths: u64,
    pub path_bounces: u64,
    pub roulette_terminations: u64,
    pub nonfinite_samples: u64,
    /// Segments (camera, secondary, shadow, escaping) whose fog was evaluated.
    pub fog_segments: u64,
    /// Fog volumes those segments crossed (the closed-form depth ran for each).
    pub fog_volume_crossings: u64,
    /// Density samples taken by ray-marched fog (`fog_march_steps`; 0 for the closed form).
    pub fog_density_samples: u64,
    /// Path tracing: collisions sampled inside fog (medium vertices).
    pub fog_scatter_events: u64,
    /// Hits reconstructed and textured in structure-of-arrays lanes (`integrator::lanes`),
    /// not each by the scalar path (Whitted and the path tracer).
    pub lane_hits: u64,
    /// Rays that left the scene whose environment the lanes looked up together
    /// (`integrator::lanes::misses`), not each by the scalar path.
    pub lane_misses: u64,
}

impl WorkCounters {
    pub fn count_rays(&mut self, kind: RayKind, n: u64) {
        match kind {
            RayKind::Camera => self.camera_rays += n,
            RayKind::Shadow => self.shadow_rays += n,
            RayKind::Reflection => self.reflection_rays += n,
            RayKind::Refraction => self.refraction_rays += n,
        }
    }

    pub fn total_rays(&self) -> u64 {
        self.camera_rays + self.shadow_rays + self.reflection_rays + self.refraction_rays
    }

    pub fn add(&mut self, other: &WorkCounters) {
        self.camera_rays += other.camera_rays;
        self.shadow_rays += other.shadow_rays;
        self.reflection_rays += other.reflection_rays;
        self.refraction_rays += other.refraction_rays;
        self.footprint_updates += other.footprint_updates;
        self.texture_lookups += other.texture_lookups;
        self.filter_callbacks += other.filter_callbacks;
        self.absorption_evaluations += other.absorption_evaluations;
        self.shadow_walk_queries += other.shadow_walk_queries;
        self.vct_voxels_built += other.vct_voxels_built;
        self.vct_cones_traced += other.vct_cones_traced;
        self.vct_cone_steps += other.vct_cone_steps;
        self.paths += other.paths;
        self.path_bounces += other.path_bounces;
        self.roulette_terminations += other.roulette_terminations;
        self.nonfinite_samples += other.nonfinite_samples;
        self.fog_segments += other.fog_segments;
        self.fog_volume_crossings += other.fog_volume_crossings;
        self.fog_density_samples += other.fog_density_samples;
        self.fog_scatter_events += other.fog_scatter_events;
        self.lane_hits += other.lane_hits;
        self.lane_misses += other.lane_misses;
    }
}

/// Texture tiles (64x64 texels) touched per texture and mip level over a whole render:
/// the metric of seed 000's figures 4-7.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TextureTileUsage {
    pub total: u64,
    /// Tile touches: for every lookup, the distinct tiles it read, summed over lookups (the
    /// tile requests a demand-loaded texture cache would serve).
    pub touches: u64,
    /// One entry per texture, in scene order: `(name, tiles per mip level)`.
    pub per_texture: Vec<(String, Vec<u64>)>,
}

/// Everything `--stats` writes and the summary line prints.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub threads: usize,
    pub lod: String,
    pub filter: String,
    pub seconds: f64,
    pub counters: WorkCounters,
    pub mrays_per_second: f64,
    /// Decoded texture memory (all mip levels), bytes.
    pub texture_memory_bytes: u64,
    pub texture_tiles: Option<TextureTileUsage>,
    /// Effects the scene needs, each with the reason.
    pub effects: Vec<EffectReason>,
    pub notes: Vec<String>,
    pub complete: bool,
    /// Wall time of each phase of a command-line render (`None` where the caller did not
    /// time them, e.g. the C API).
    pub phases: Option<PhaseSeconds>,
    /// Decoded memory of each texture (all mip levels), in scene order.
    pub texture_memory: Vec<TextureMemory>,
    /// The voxel cone tracer's voxelisation: resolution, time and memory (`vct` only).
    pub vct: Option<crate::vct::VctBuildStats>,
    /// The integrator that rendered and why it was chosen (e.g. "path: emissive geometry
    /// (12 triangles)"); `None` when the caller rendered with an integrator directly.
    pub integrator: Option<String>,
    /// The vector instructions the lane loops ran with ([`crate::simd::Level::name`]).
    pub simd: String,
    /// The texture cache over the demand-loaded (`.tx`) textures, all of them together
    /// (`None` when no texture is demand-loaded).
    pub texture_cache: Option<TextureCacheTotals>,
}

/// The texture cache's counters for one demand-loaded texture, or summed over all of them
/// (`crate::texture::TextureCacheStats`, with its rates).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TextureCacheReport {
    /// Tiles read from the file, a tile read again after its eviction counted again.
    pub tiles_loaded: u64,
    /// Tiles evicted to stay under the cap.
    pub tiles_evicted: u64,
    /// Bytes of those tiles in the file (as stored, compressed).
    pub bytes_read: u64,
    /// Most texel bytes resident at once (of the total: the cache's own peak).
    pub peak_resident_bytes: u64,
    /// Tile fetches served by the fetching thread's micro-cache.
    pub micro_cache_hits: u64,
    /// Tile fetches past the micro-cache, to the shared cache.
    pub micro_cache_misses: u64,
    /// Of those, the fetches that found the tile resident.
    pub cache_hits: u64,
    /// micro_cache_hits / (micro_cache_hits + micro_cache_misses).
    pub micro_cache_hit_rate: f64,
    /// cache_hits / micro_cache_misses.
    pub cache_hit_rate: f64,
}

impl From<crate::texture::TextureCacheStats> for TextureCacheReport {
    fn from(s: crate::texture::TextureCacheStats) -> TextureCacheReport {
        TextureCacheReport {
            tiles_loaded: s.tiles_loaded,
            tiles_evicted: s.tiles_evicted,
            bytes_read: s.bytes_read,
            peak_resident_bytes: s.peak_resident_bytes,
            micro_cache_hits: s.micro_cache_hits,
            micro_cache_misses: s.micro_cache_misses,
            cache_hits: s.cache_hits,
            micro_cache_hit_rate: s.micro_cache_hit_rate(),
            cache_hit_rate: s.cache_hit_rate(),
        }
    }
}

/// The cache counters summed over the demand-loaded textures among `textures`, the peak
/// and the cap being those of the caches they live in (each counted once); `None` when
/// none is demand-loaded.
pub fn texture_cache_totals(
    textures: &[std::sync::Arc<crate::texture::Texture>],
) -> Option<TextureCacheTotals> {
    let mut sum: Option<crate::texture::TextureCacheStats> = None;
    let mut caches: Vec<&std::sync::Arc<crate::texture::TileCache>> = Vec::new();
    for texture in textures {
        let (Some(stats), Some(cache)) = (texture.cache_stats(), texture.tile_cache()) else {
            continue;
        };
        sum = Some(sum.unwrap_or_default().plus(&stats));
        if !caches.iter().any(|c| std::sync::Arc::ptr_eq(c, cache)) {
            caches.push(cache);
        }
    }
    let mut totals = TextureCacheReport::from(sum?);
    totals.peak_resident_bytes = caches.iter().map(|c| c.peak_resident_bytes()).sum();
    Some(TextureCacheTotals {
        capacity_bytes: caches.iter().map(|c| c.capacity()).sum(),
        totals,
    })
}

/// The texture cache over all demand-loaded textures of a render.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TextureCacheTotals {
    /// The cap (`--texture-cache`), in bytes.
    pub capacity_bytes: u64,
    #[serde(flatten)]
    pub totals: TextureCacheReport,
}

impl TextureCacheTotals {
    /// The summary line's part: loads, evictions, bytes read, peak against the cap, rates.
    fn summary(&self) -> String {
        let t = &self.totals;
        let mib = |bytes: u64| bytes as f64 / (1024.0 * 1024.0);
        format!(
            "texture cache: {} tiles loaded, {} evicted, {:.1} MiB read, peak {:.1} of {:.1} MiB, \
             micro-cache hits {:.1} %, cache hits {:.1} %",
            t.tiles_loaded,
            t.tiles_evicted,
            mib(t.bytes_read),
            mib(t.peak_resident_bytes),
            mib(self.capacity_bytes),
            100.0 * t.micro_cache_hit_rate,
            100.0 * t.cache_hit_rate
        )
    }
}

/// Seconds spent in each phase of a render, and in all of them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PhaseSeconds {
    /// Reading and validating the scene and its meshes.
    pub load: f64,
    /// Decoding textures and building their mip pyramids.
    pub textures: f64,
    /// Building Embree's BVH and the render's tables.
    pub prepare: f64,
    /// Tracing and shading.
    pub render: f64,
    /// Encoding the EXR and PNG (the statistics file cannot time its own writing).
    pub write: f64,
    /// From the start of the program to the first traced ray (the first work tile's start):
    /// how long a user waits before anything is traced.
    pub first_ray: f64,
    /// From the start of loading to the end of writing the images.
    pub total: f64,
}

/// One texture's decoded size (of a demand-loaded `.tx`: of the tiles resident at the end).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureMemory {
    pub texture: String,
    pub bytes: u64,
    /// True when the texture's tiles are read from its file on demand (a tiled `.tx`),
    /// false when it was decoded whole in memory, every level built before the first ray
    /// (`conetrace maketx` turns such a file into a `.tx`).
    pub demand_loaded: bool,
    /// Of a demand-loaded `.tx`: tiles read from the file, and tiles it holds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tiles_read: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tiles_in_file: Option<u64>,
    /// Of a demand-loaded `.tx`: its texture-cache counters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cache: Option<TextureCacheReport>,
}

#[derive(Clone, Debug, Serialize, PartialEq, Eq)]
pub struct EffectReason {
    pub effect: String,
    pub because: String,
}

impl RenderStats {
    /// The render's time, with every phase when they were timed.
    fn time_text(&self) -> String {
        match &self.phases {
            Some(p) => format!(
                "{:.3} s (load {:.3} s, textures {:.3} s, BVH and set-up {:.3} s, first ray at \
                 {:.3} s, render {:.3} s, write {:.3} s)",
                p.total, p.load, p.textures, p.prepare, p.first_ray, p.render, p.write
            ),
            None => format!("{:.3} s", self.seconds),
        }
    }

    /// The summary line's part on textures decoded whole in memory (`None` when there are
    /// none): how many, their memory, and the way to read them on demand instead.
    fn decoded_whole_summary(&self) -> Option<String> {
        let whole: Vec<&TextureMemory> = self
            .texture_memory
            .iter()
            .filter(|t| !t.demand_loaded)
            .collect();
        if whole.is_empty() {
            return None;
        }
        let bytes: u64 = whole.iter().map(|t| t.bytes).sum();
        Some(format!(
            "{} of {} textures decoded whole in memory ({:.1} MiB; `conetrace maketx` makes \
             tiled .tx files read on demand)",
            whole.len(),
            self.texture_memory.len(),
            bytes as f64 / (1024.0 * 1024.0)
        ))
    }

    /// The one-line summary printed at the end of a render.
    pub fn summary_line(&self) -> String {
        let c = &self.counters;
        let mut line = format!(
            "rendered {} ({}x{}, {} spp, lod {}, filter {}) in {}: {} camera, {} shadow, {} reflection, {} refraction rays, {:.2} Mrays/s",
            self.scene,
            self.width,
            self.height,
            self.spp,
            self.lod,
            self.filter,
            self.time_text(),
            c.camera_rays,
            c.shadow_rays,
            c.reflection_rays,
            c.refraction_rays,
            self.mrays_per_second
        );
        if c.paths > 0 {
            line.push_str(&format!(
                "; {} paths, {} bounces, {} ended by roulette",
                c.paths, c.path_bounces, c.roulette_terminations
            ));
            if c.nonfinite_samples > 0 {
                line.push_str(&format!(
                    ", {} non-finite samples dropped",
                    c.nonfinite_samples
                ));
            }
        }
        if let Some(integrator) = &self.integrator {
            line.push_str(&format!("; integrator {integrator}"));
        }
        if !self.effects.is_empty() {
            let names: Vec<&str> = self.effects.iter().map(|e| e.effect.as_str()).collect();
            line.push_str(&format!("; effects: {}", names.join(", ")));
        }
        if let Some(tiles) = &self.texture_tiles {
            line.push_str(&format!("; {} texture tiles", tiles.total));
        }
        if let Some(cache) = &self.texture_cache {
            line.push_str("; ");
            line.push_str(&cache.summary());
        }
        if let Some(whole) = self.decoded_whole_summary() {
            line.push_str("; ");
            line.push_str(&whole);
        }
        for note in &self.notes {
            line.push_str("; ");
            line.push_str(note);
        }
        if !self.complete {
            line.push_str("; INCOMPLETE");
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_add_and_total() {
        let mut a = WorkCounters::default();
        a.count_rays(RayKind::Camera, 16);
        a.count_rays(RayKind::Shadow, 4);
        let mut b = WorkCounters::default();
        b.count_rays(RayKind::Refraction, 2);
        b.texture_lookups = 7;
        a.add(&b);
        assert_eq!(a.total_rays(), 22);
        assert_eq!(a.refraction_rays, 2);
        assert_eq!(a.texture_lookups, 7);
    }
}
