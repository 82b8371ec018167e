//! `conetrace bench tiles`: the 64x64 texture tiles each level-of-detail strategy touches
//! on one scene, and the render time each takes, as a markdown table
//! (docs/path-tracing.md, "Texture tiles per LOD strategy").
//!
//! Seed 000's figures 4-7 count the tiles a demand-loaded texture cache would have to load;
//! here the count covers every lookup of every bounce of the chosen integrator (the path
//! tracer by default, so rough bounces widen the cones and later lookups read coarse
//! levels). For every strategy x filter row, one untimed pass counts the distinct tiles (all
//! levels, and level 0 alone), the tile touches (each lookup's distinct tiles, summed) and
//! the lookups; then `--runs` rounds render every row once more without counting, in turn,
//! so drift in the shared machine's load falls on all rows alike, and the median render time
//! is reported. Rows differ only in the footprint strategy and the filter: the same seed,
//! samples and integrator.
//!
//! Real loads: the scene's texture files are first made into 64x64-tiled, mip-mapped `.tx`
//! files as `conetrace maketx` writes them (in a temporary directory), and every row runs on them. The counting
//! pass and the timed rounds read them decoded whole; one more render per row opens them
//! tile by tile through a fresh texture cache of `--cache` bytes, and reports the tiles it
//! read from disk, the bytes read, the cache's peak resident bytes and its render time (cold
//! cache: the reads included). Cached and resident lookups are bit-identical, so every pass
//! makes the same lookups, and under a cap that evicts nothing the tiles loaded are the
//! distinct tiles counted plus the one tile of each texture's 1x1 level read on opening
//! when the render did not touch it ([`expected_loads`]).

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;

use crate::cli::render_cmd::{self, RenderArgs};
use crate::cli::CommandError;
use crate::footprint::LodStrategy;
use crate::integrator::selection::{self, IntegratorChoice};
use crate::render::{self, RenderControl, RenderOptions, RenderResult};
use crate::scene::{SceneDescription, TextureSource};
use crate::texture::{
    write_tx, ColorSpace, FilterMode, Texture, TileCache, TxCompression, TxOptions,
};

/// Arguments of `bench tiles`.
#[derive(Args, Debug)]
pub struct BenchTilesArgs {
    /// The scene.
    #[arg(default_value = "assets/scenes/path_textured.toml")]
    pub scene: PathBuf,
    /// Integrator (whitted, path, vct or auto).
    #[arg(long, default_value = "path", value_parser = ["whitted", "path", "vct", "auto"])]
    pub integrator: String,
    /// Image width (default: the scene's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene's).
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (default: the scene's).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Timed rounds (every row rendered once per round); the median is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also write the table to this file.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Cap of the texture cache of the real-load renders (a fresh cache per row).
    #[arg(long, value_name = "SIZE", default_value = "256M",
          value_parser = crate::render::memory::parse_memory_size)]
    pub cache: u64,
}

/// The strategy x filter rows, in table order: `mip0` first, the baseline the others save
/// against; then the distance metric, the single cone, the two-cone envelope with an
/// isotropic (trilinear) and an anisotropic filter, and ray differentials with both.
pub fn tile_rows() -> Vec<(LodStrategy, FilterMode)> {
    use FilterMode::{Aniso, Bilinear, Trilinear};
    use LodStrategy::{Cone, Cone1, Differential, Distance, Mip0};
    vec![
        (Mip0, Bilinear),
        (Distance, Trilinear),
        (Cone1, Trilinear),
        (Cone, Trilinear),
        (Cone, Aniso),
        (Differential, Trilinear),
        (Differential, Aniso),
    ]
}

/// What one row measured.
#[derive(Clone, Debug)]
pub struct TileRow {
    pub lod: LodStrategy,
    pub filter: FilterMode,
    /// Distinct tiles over all textures and levels in the counting pass.
    pub unique_tiles: u64,
    /// Distinct level-0 (finest) tiles.
    pub unique_level0_tiles: u64,
    /// Each lookup's distinct tiles, summed over lookups.
    pub touches: u64,
    pub lookups: u64,
    /// Median render time of the timed rounds (tracing and shading only), seconds.
    pub seconds: f64,
    /// Tiles loaded on demand expected from the counts (see [`expected_loads`]).
    pub expected_loads: u64,
    /// What the render with the textures demand-loaded read.
    pub real: RealLoads,
}

/// What one render with the textures read tile by tile through a fresh cache did.
#[derive(Clone, Debug, Default)]
pub struct RealLoads {
    /// Tiles read from disk (the 1x1 level's tile read on opening included).
    pub tiles_loaded: u64,
    /// Tiles evicted to stay under the cap.
    pub tiles_evicted: u64,
    /// Bytes of those tiles in the files (compressed).
    pub bytes_read: u64,
    /// Most texel bytes resident in the cache at once.
    pub peak_resident_bytes: u64,
    /// Render time (tracing and shading, the reads included), seconds.
    pub seconds: f64,
}

fn render_args(args: &BenchTilesArgs) -> Result<RenderArgs, CommandError> {
    let mut argv: Vec<OsString> = vec!["conetrace".into(), "--quiet".into(), "--no-png".into()];
    argv.extend(["--integrator".into(), args.integrator.clone().into()]);
    if let Some(width) = args.width {
        argv.extend(["--width".into(), width.to_string().into()]);
    }
    if let Some(height) = args.height {
        argv.extend(["--height".into(), height.to_string().into()]);
    }
    if let Some(spp) = args.spp {
        argv.extend(["--spp".into(), spp.to_string().into()]);
    }
    argv.extend(["--".into(), args.scene.as_os_str().to_owned()]);
    RenderArgs::from_argv(argv).map_err(|e| CommandError::bad_input(format!("bench tiles: {e}")))
}

fn render_once(
    context: &render::RenderContext,
    choice: IntegratorChoice,
) -> Result<RenderResult, CommandError> {
    selection::render(context, choice, &RenderControl::default()).map_err(|e| match e {
        selection::SelectedRenderError::Render(e) => crate::cli::render_failed(e),
        selection::SelectedRenderError::Build(e) => CommandError::bad_input(e.to_string()),
    })
}

/// The scene's textures made into 64x64-tiled, mip-mapped `.tx` files in `dir` by
/// [`crate::texture::write_tx`] (as `conetrace maketx` makes them, every level built as a
/// render builds it): the scene with its texture files replaced by them. Embedded textures
/// stay as they are (decoded whole).
pub fn with_tx_textures(
    scene: &SceneDescription,
    dir: &Path,
) -> Result<SceneDescription, CommandError> {
    let mut converted = scene.clone();
    for (index, texture) in converted.textures.iter_mut().enumerate() {
        let TextureSource::File(path) = &texture.source else {
            continue;
        };
        let bad = |message: String| CommandError::bad_input(message);
        let whole =
            Texture::from_file_whole(path, texture.color_space).map_err(|e| bad(e.to_string()))?;
        let tx = dir.join(format!("{index}.tx"));
        let options = TxOptions {
            compression: TxCompression::Deflate,
            color_space: whole.color_space().unwrap_or(ColorSpace::Linear),
            software: format!("conetrace bench tiles {}", path.display()),
        };
        let file = std::fs::File::create(&tx)
            .map_err(|e| bad(format!("{}: cannot create: {e}", tx.display())))?;
        let mut writer = std::io::BufWriter::new(file);
        write_tx(whole.pyramid(), &mut writer, &options)
            .and_then(|()| std::io::Write::flush(&mut writer).map_err(|e| e.to_string()))
            .map_err(|e| bad(format!("{}: {e}", tx.display())))?;
        texture.source = TextureSource::File(tx);
    }
    Ok(converted)
}

/// The textures of `scene` decoded whole (`.tx` files too).
fn resident_textures(scene: &SceneDescription) -> Result<Vec<Arc<Texture>>, CommandError> {
    scene
        .textures
        .iter()
        .map(|desc| {
            let texture = match &desc.source {
                TextureSource::File(path) => Texture::from_file_whole(path, desc.color_space),
                TextureSource::Encoded { .. } => render::prepared::decode_texture(desc),
            };
            texture
                .map(Arc::new)
                .map_err(|e| CommandError::bad_input(e.to_string()))
        })
        .collect()
}

/// Tiles a demand-loaded render of `textures` must read, from the distinct tiles it
/// counted per texture and level (`per_texture`, in scene order): every counted tile, plus
/// the tile of the 1x1 level, read on opening, of each demand-loaded texture whose count
/// does not include it.
pub fn expected_loads(textures: &[Arc<Texture>], per_texture: &[(String, Vec<u64>)]) -> u64 {
    textures
        .iter()
        .zip(per_texture)
        .filter(|(texture, _)| texture.is_demand_loaded())
        .map(|(texture, (_, levels))| {
            let counted: u64 = levels.iter().sum();
            let coarsest = texture.level_count() - 1;
            let opened = u64::from(levels.get(coarsest).copied().unwrap_or(0) == 0);
            counted + opened
        })
        .sum()
}

/// One render of `scene` with its textures opened through a fresh cache of `cap` bytes,
/// and what the cache did; also the textures, for [`expected_loads`].
fn real_loads(
    scene: &Arc<SceneDescription>,
    options: RenderOptions,
    choice: IntegratorChoice,
    cap: u64,
) -> Result<(RealLoads, Vec<Arc<Texture>>), CommandError> {
    let cache = Arc::new(TileCache::new(cap));
    let textures = render::prepared::decode_textures_in(scene, &cache)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let context = render::prepare_with_textures(scene.clone(), options, textures.clone())
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let rendered = render_once(&context, choice)?;
    if let Some(failure) = textures.iter().find_map(|t| t.tile_failure()) {
        return Err(CommandError::bad_input(failure.to_string()));
    }
    let stats = textures
        .iter()
        .filter_map(|t| t.cache_stats())
        .fold(crate::texture::TextureCacheStats::default(), |sum, s| {
            sum.plus(&s)
        });
    let loads = RealLoads {
        tiles_loaded: stats.tiles_loaded,
        tiles_evicted: stats.tiles_evicted,
        bytes_read: stats.bytes_read,
        peak_resident_bytes: cache.peak_resident_bytes(),
        seconds: rendered.stats.seconds,
    };
    Ok((loads, textures))
}

/// Counts, loads and times every row of [`tile_rows`] on `scene` (whose textures should be
/// `.tx` files: see [`with_tx_textures`]) rendered with `options` (whose strategy and
/// filter each row replaces) by the integrator `choice`; real loads under a cache of `cap`
/// bytes.
pub fn measure(
    scene: Arc<SceneDescription>,
    options: &RenderOptions,
    choice: IntegratorChoice,
    runs: usize,
    cap: u64,
) -> Result<(Vec<TileRow>, String), CommandError> {
    let textures = resident_textures(&scene)?;
    let mut contexts = Vec::new();
    let mut rows = Vec::new();
    let mut integrator = String::new();
    for (lod, filter) in tile_rows() {
        let mut row_options = options.clone();
        row_options.lod = lod;
        row_options.filter.filter = filter;
        let (real, demand_textures) = real_loads(&scene, row_options.clone(), choice, cap)?;
        row_options.count_texture_tiles = true;
        let mut context =
            render::prepare_with_textures(scene.clone(), row_options, textures.clone())
                .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let counted = render_once(&context, choice)?;
        let usage = counted.stats.texture_tiles.clone().unwrap_or_default();
        integrator = counted.stats.integrator.clone().unwrap_or_default();
        rows.push(TileRow {
            lod,
            filter,
            unique_tiles: usage.total,
            unique_level0_tiles: usage
                .per_texture
                .iter()
                .map(|(_, levels)| levels.first().copied().unwrap_or(0))
                .sum(),
            touches: usage.touches,
            lookups: counted.stats.counters.texture_lookups,
            seconds: f64::NAN,
            expected_loads: expected_loads(&demand_textures, &usage.per_texture),
            real,
        });
        context.options.count_texture_tiles = false;
        contexts.push(context);
    }
    let mut times = vec![Vec::with_capacity(runs); contexts.len()];
    for round in 0..runs {
        for (index, context) in contexts.iter().enumerate() {
            times[index].push(render_once(context, choice)?.stats.seconds);
        }
        eprintln!("bench tiles: timed round {}/{runs} done", round + 1);
    }
    for (row, seconds) in rows.iter_mut().zip(times) {
        row.seconds = super::summary::median(&seconds);
    }
    Ok((rows, integrator))
}

/// The markdown table of `rows`: counts, and time with the saving against the first row
/// (`mip0`).
pub fn table(rows: &[TileRow]) -> String {
    let mut text = String::from(
        "| strategy | filter | unique tiles | unique level-0 tiles | tile touches | lookups | touches per lookup | render time (s) | vs mip0 \
         | tiles loaded | expected | evicted | MiB read | peak MiB | cold render (s) |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let baseline = rows.first().map_or(f64::NAN, |r| r.seconds);
    for row in rows {
        let _ = writeln!(
            text,
            "| {} | {} | {} | {} | {} | {} | {:.2} | {:.3} | {:+.1}% | {} | {} | {} | {:.2} | {:.2} | {:.3} |",
            row.lod,
            row.filter,
            row.unique_tiles,
            row.unique_level0_tiles,
            row.touches,
            row.lookups,
            row.touches as f64 / row.lookups.max(1) as f64,
            row.seconds,
            100.0 * (row.seconds / baseline - 1.0),
            row.real.tiles_loaded,
            row.expected_loads,
            row.real.tiles_evicted,
            row.real.bytes_read as f64 / MIB,
            row.real.peak_resident_bytes as f64 / MIB,
            row.real.seconds,
        );
    }
    text
}

const MIB: f64 = 1024.0 * 1024.0;

pub fn run(args: &BenchTilesArgs) -> Result<(), CommandError> {
    if args.runs == 0 {
        return Err(CommandError::bad_input("--runs must be at least 1"));
    }
    let render_args = render_args(args)?;
    let pool = crate::cli::worker_pool(args.threads)?;
    let mut scene = render_cmd::load(&render_args)?;
    render_cmd::apply_integrator_options(&render_args, &mut scene)?;
    let options = render_cmd::options(&render_args, &scene)?;
    let choice = scene.settings.integrator;
    let (width, height, spp) = (options.width, options.height, options.spp);
    let tx_dir = std::env::temp_dir().join(format!("conetrace-bench-tiles-{}", std::process::id()));
    std::fs::create_dir_all(&tx_dir)
        .map_err(|e| CommandError::bad_input(format!("{}: {e}", tx_dir.display())))?;
    let result = with_tx_textures(&scene, &tx_dir).and_then(|scene| {
        measure_and_print(args, scene, &options, choice, &pool, (width, height, spp))
    });
    let _ = std::fs::remove_dir_all(&tx_dir);
    result
}

/// Runs [`measure`] on `scene` in `pool` and prints (and writes) the table.
fn measure_and_print(
    args: &BenchTilesArgs,
    scene: SceneDescription,
    options: &RenderOptions,
    choice: IntegratorChoice,
    pool: &rayon::ThreadPool,
    (width, height, spp): (u32, u32, u32),
) -> Result<(), CommandError> {
    pool.install(|| {
        let (rows, integrator) = measure(Arc::new(scene), options, choice, args.runs, args.cache)?;
        let command = std::iter::once("conetrace".to_string())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" ");
        let mut text = format!(
            "`{command}`: {} at {width}x{height}, {spp} spp, integrator {integrator}, {} threads, \
             median of {} timed rounds; textures made into 64x64-tiled .tx files as conetrace maketx makes them; real \
             loads through a fresh {} cache per row\n\n",
            args.scene.display(),
            rayon::current_num_threads(),
            args.runs,
            crate::render::memory::Bytes(args.cache),
        );
        text.push_str(&table(&rows));
        print!("{text}");
        if let Some(file) = &args.markdown {
            // Written whole or not at all (a temporary file renamed into place).
            crate::cli::accuracy::files::write_text(file, &text)?;
        }
        Ok(())
    })
}
