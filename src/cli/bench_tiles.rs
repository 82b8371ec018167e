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

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;

use crate::cli::render_cmd::{self, RenderArgs};
use crate::cli::CommandError;
use crate::footprint::LodStrategy;
use crate::integrator::selection::{self, IntegratorChoice};
use crate::render::{self, RenderControl, RenderOptions, RenderResult};
use crate::texture::FilterMode;

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
}

/// The strategy x filter rows, in table order: `mip0` first, the baseline the others save
/// against; then the single cone, the two-cone envelope with an isotropic (trilinear) and
/// an anisotropic filter, and ray differentials with both.
pub fn tile_rows() -> Vec<(LodStrategy, FilterMode)> {
    use FilterMode::{Aniso, Bilinear, Trilinear};
    use LodStrategy::{Cone, Cone1, Differential, Mip0};
    vec![
        (Mip0, Bilinear),
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

/// Counts and times every row of [`tile_rows`] on `scene` rendered with `options` (whose
/// strategy and filter each row replaces) by the integrator `choice`.
pub fn measure(
    scene: Arc<crate::scene::SceneDescription>,
    options: &RenderOptions,
    choice: IntegratorChoice,
    runs: usize,
) -> Result<(Vec<TileRow>, String), CommandError> {
    let textures = render::prepared::decode_textures(&scene)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let mut contexts = Vec::new();
    let mut rows = Vec::new();
    let mut integrator = String::new();
    for (lod, filter) in tile_rows() {
        let mut row_options = options.clone();
        row_options.lod = lod;
        row_options.filter.filter = filter;
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
        "| strategy | filter | unique tiles | unique level-0 tiles | tile touches | lookups | touches per lookup | render time (s) | vs mip0 |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let baseline = rows.first().map_or(f64::NAN, |r| r.seconds);
    for row in rows {
        let _ = writeln!(
            text,
            "| {} | {} | {} | {} | {} | {} | {:.2} | {:.3} | {:+.1}% |",
            row.lod,
            row.filter,
            row.unique_tiles,
            row.unique_level0_tiles,
            row.touches,
            row.lookups,
            row.touches as f64 / row.lookups.max(1) as f64,
            row.seconds,
            100.0 * (row.seconds / baseline - 1.0),
        );
    }
    text
}

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
    pool.install(|| {
        let (rows, integrator) = measure(Arc::new(scene), &options, choice, args.runs)?;
        let command = std::iter::once("conetrace".to_string())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" ");
        let mut text = format!(
            "`{command}`: {} at {width}x{height}, {spp} spp, integrator {integrator}, {} threads, \
             median of {} timed rounds\n\n",
            args.scene.display(),
            rayon::current_num_threads(),
            args.runs,
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
