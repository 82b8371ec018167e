//! The options of the benchmarks that render one scene as `conetrace render` would
//! (`bench render`, `bench scale-out`): the scene, the image and how it is shaded. Options
//! about output files, interruption, progress or splitting the render have no meaning for a
//! benchmark, which writes no image, so these commands do not take them (and `--help` does
//! not list them).

use std::path::PathBuf;

use clap::Args;

use crate::cli::render_cmd::{self, AovName, PatchMode, RenderArgs};
use crate::cli::CommandError;
use crate::footprint::LodStrategy;
use crate::texture::FilterMode;

/// The scene and image options a benchmark shares with `conetrace render`.
#[derive(Args, Debug, Clone)]
pub struct BenchSceneArgs {
    /// Scene file (.toml, .obj, .gltf, .glb). Without it, the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Image width in pixels, 1 to 65536 [default: the scene's width, else 640].
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(render_cmd::MAX_IMAGE_SIDE)))]
    pub width: Option<u32>,
    /// Image height in pixels, 1 to 65536 [default: the scene's height, else 360].
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(render_cmd::MAX_IMAGE_SIDE)))]
    pub height: Option<u32>,
    /// Samples per pixel (Owen-scrambled Sobol; 1 = pixel centre) [default: the scene's,
    /// else 1].
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Seed of the sample positions, 0 to 4294967295 [default: the scene's, else 0].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Maximum number of reflection/refraction bounces, 0 or more [default: the scene's,
    /// else 8].
    #[arg(long, allow_negative_numbers = true)]
    pub max_depth: Option<u32>,
    /// Footprint strategy that drives texture level of detail.
    #[arg(long, default_value = "cone", value_parser = render_cmd::lod_parser())]
    pub lod: LodStrategy,
    /// Texture filter.
    #[arg(long, default_value = "aniso", value_parser = render_cmd::filter_parser())]
    pub filter: FilterMode,
    /// Maximum anisotropy of the aniso and ewa filters (a number >= 1).
    #[arg(long, default_value_t = 16.0, allow_negative_numbers = true)]
    pub max_aniso: f32,
    /// Extra layers rendered (Z, N, albedo and uv are computed unless `--aov none`).
    #[arg(long, value_enum)]
    pub aov: Vec<AovName>,
    /// Fresnel equations at dielectric boundaries (default: the scene's, else exact).
    #[arg(long, value_parser = ["exact", "schlick"])]
    pub fresnel: Option<String>,
    /// Force every effect on (the general path), for comparisons.
    #[arg(long)]
    pub all_effects: bool,
    /// How curved patches are traced: `exact` (the polynomial surface itself, through an
    /// Embree user geometry) or `tessellate` (triangles within --tessellation-error of it).
    #[arg(long, value_enum, default_value = "exact")]
    pub patch_mode: PatchMode,
    /// With --patch-mode tessellate: the largest distance, in world units, between a patch
    /// and its triangles.
    #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true)]
    pub tessellation_error: f32,
}

impl BenchSceneArgs {
    /// The `conetrace render` options these stand for (every other option at its default),
    /// with `threads` worker threads.
    pub fn render_args(&self, threads: Option<usize>) -> Result<RenderArgs, CommandError> {
        let mut args = RenderArgs::from_argv(vec!["conetrace".into()])
            .map_err(|e| CommandError::internal(format!("render's default options: {e}")))?;
        args.scene = self.scene.clone();
        args.width = self.width;
        args.height = self.height;
        args.spp = self.spp;
        args.seed = self.seed;
        args.max_depth = self.max_depth;
        args.threads = threads;
        args.lod = self.lod;
        args.filter = self.filter;
        args.max_aniso = self.max_aniso;
        args.aov = self.aov.clone();
        args.fresnel = self.fresnel.clone();
        args.all_effects = self.all_effects;
        args.patch_mode = self.patch_mode;
        args.tessellation_error = self.tessellation_error;
        Ok(args)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser, Debug)]
    struct Parsed {
        #[command(flatten)]
        scene: BenchSceneArgs,
    }

    fn parse(argv: &[&str]) -> BenchSceneArgs {
        let argv = std::iter::once("bench").chain(argv.iter().copied());
        Parsed::try_parse_from(argv).expect("parses").scene
    }

    #[test]
    fn defaults_are_those_of_render() {
        let bench = parse(&[]).render_args(None).expect("render arguments");
        let render = RenderArgs::from_argv(vec!["conetrace".into()]).expect("defaults");
        assert_eq!(format!("{bench:?}"), format!("{render:?}"));
    }

    #[test]
    fn every_option_reaches_the_render_options() {
        let argv = [
            "scene.toml",
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "4",
            "--seed",
            "7",
            "--max-depth",
            "3",
            "--lod",
            "differential",
            "--filter",
            "ewa",
            "--max-aniso",
            "4",
            "--aov",
            "lod",
            "--fresnel",
            "schlick",
            "--all-effects",
            "--patch-mode",
            "tessellate",
            "--tessellation-error",
            "0.01",
        ];
        let from_bench = parse(&argv).render_args(Some(3)).expect("render arguments");
        let mut render_argv: Vec<std::ffi::OsString> = vec!["conetrace".into()];
        render_argv.extend(argv.iter().map(|a| a.into()));
        render_argv.extend(["--threads".into(), "3".into()]);
        let from_render = RenderArgs::from_argv(render_argv).expect("render parses");
        assert_eq!(format!("{from_bench:?}"), format!("{from_render:?}"));
    }
}
