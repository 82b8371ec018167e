//! The `conetrace` command line: subcommands, exit statuses and one-line errors.
//!
//! Exit statuses: 0 success, 1 internal failure (a bug: please report), 2 bad input (a file
//! or an option; the message names it), 3 interrupted (the finished part was saved).

pub mod accuracy;
pub mod bench_effects;
pub mod bench_render;
pub mod bench_scale_out;
pub mod bench_scene;
pub mod bench_textures;
pub mod bench_tiles;
pub mod maketx;
pub mod merge;
pub mod outputs;
pub mod patch_mode;
pub mod progress;
pub mod progressive;
pub mod render_cmd;
pub mod resume;
pub mod sample_texture;
pub mod summary;

use clap::{Parser, Subcommand};

/// Success.
pub const EXIT_OK: i32 = 0;
/// An internal failure that is not the input's fault.
pub const EXIT_INTERNAL: i32 = 1;
/// Bad input: a scene, mesh, texture or option the program cannot use.
pub const EXIT_BAD_INPUT: i32 = 2;
/// The render was interrupted (Ctrl-C, SIGTERM, cancellation); the finished part was saved.
pub const EXIT_INTERRUPTED: i32 = 3;

/// When the program started (the first call; `main` makes it first thing), the origin of
/// `phases.first_ray` in `--stats`.
pub fn program_start() -> std::time::Instant {
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    *START.get_or_init(std::time::Instant::now)
}

/// Seconds from [`program_start`] to `at` (the first traced ray), 0 when nothing was traced.
pub fn seconds_since_start(at: Option<std::time::Instant>) -> f64 {
    at.map_or(0.0, |t| t.duration_since(program_start()).as_secs_f64())
}

/// A failed command: what to print (one line) and the exit status.
#[derive(Debug)]
pub struct CommandError {
    pub message: String,
    pub status: i32,
}

impl CommandError {
    pub fn bad_input(message: impl Into<String>) -> CommandError {
        CommandError {
            message: message.into(),
            status: EXIT_BAD_INPUT,
        }
    }
    pub fn internal(message: impl Into<String>) -> CommandError {
        CommandError {
            message: message.into(),
            status: EXIT_INTERNAL,
        }
    }
}

#[derive(Parser, Debug)]
#[command(
    name = "conetrace",
    version,
    about = "CPU ray tracer on Embree packets; texture lookups filtered by ray cones and ray differentials"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene (TOML, OBJ, glTF); with no scene, the built-in default scene into out/.
    Render(Box<render_cmd::RenderArgs>),
    /// Filter a texture at the (s, t, derivatives) queries of a CSV file; print r,g,b,a rows.
    SampleTexture(sample_texture::SampleTextureArgs),
    /// Benchmarks: raw packet traversal vs full shading, texture filtering vs OpenImageIO.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Error against a supersampled ground truth and time of every footprint strategy and
    /// filter; writes CSV, markdown, an error-vs-time plot and crops (default out/accuracy).
    Accuracy(accuracy::AccuracyArgs),
    /// Merge the parts of a split render (--region, --samples, --part) into the image a
    /// single render gives, bit for bit.
    Merge(merge::MergeArgs),
    /// Convert an untiled image (PNG, JPEG, scanline EXR or TIFF) into a tiled, mip-mapped
    /// TIFF (.tx) that renders read tile by tile under the texture cache's cap.
    Maketx(maketx::MaketxArgs),
}

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Camera rays through Embree with no shading, then the same rays fully shaded.
    Render(bench_render::BenchRenderArgs),
    /// Lookups per second per filter, ours and OpenImageIO's, on the same queries.
    Textures(bench_textures::BenchTexturesArgs),
    /// Specialised path vs general path (--all-effects), and each unneeded effect's cost.
    Effects(bench_effects::BenchEffectsArgs),
    /// Predicted wall time of a render split over 1 to 1,000 Slurm tasks, from per-tile
    /// costs measured here (docs/scale-out.md).
    ScaleOut(bench_scale_out::BenchScaleOutArgs),
    /// Texture tiles (64x64) each level-of-detail strategy touches on one scene, at every
    /// bounce of the integrator (path by default), and the render time of each.
    Tiles(bench_tiles::BenchTilesArgs),
}

/// A render that failed: a ray traversal failure is internal (exit status 1), memory and
/// unreadable texture tiles are bad input (2); never an image of misses or black texels.
pub fn render_failed(error: crate::render::RenderError) -> CommandError {
    match error {
        // Not the program's fault: the input asks for more than the machine has.
        crate::render::RenderError::OutOfMemory { .. } => {
            CommandError::bad_input(error.to_string())
        }
        // A damaged texture file is bad input.
        crate::render::RenderError::TextureTile { .. } => {
            CommandError::bad_input(error.to_string())
        }
        crate::render::RenderError::Traversal { .. } => CommandError::internal(error.to_string()),
    }
}

/// The worker threads of a command: `threads` of them (all cores when `None`), each with
/// denormals flushed as Embree expects. `Some(0)` is bad input.
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, CommandError> {
    let mut pool =
        rayon::ThreadPoolBuilder::new().start_handler(|_| crate::embree::enable_flush_denormals());
    if let Some(threads) = threads {
        if threads == 0 {
            return Err(CommandError::bad_input("--threads must be at least 1"));
        }
        if threads > crate::render::MAX_WORKER_THREADS {
            return Err(CommandError::bad_input(format!(
                "--threads {threads}: at most {} worker threads",
                crate::render::MAX_WORKER_THREADS
            )));
        }
        pool = pool.num_threads(threads);
    }
    pool.build()
        .map_err(|e| CommandError::internal(format!("cannot start worker threads: {e}")))
}

/// Reports a command line clap could not parse; returns the exit status. Help and version
/// requests print as clap prints them. An error is one line, like every other error, with
/// clap's tip (a similarly spelled option or command) kept on it and its usage block left
/// out: status 2 ([`EXIT_BAD_INPUT`]).
pub fn command_line_error(error: clap::Error) -> i32 {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = error.print();
        return error.exit_code();
    }
    let text = error.render().to_string();
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("cannot parse the command line");
    let message = first.strip_prefix("error: ").unwrap_or(first);
    match lines.find(|l| l.starts_with("tip:")) {
        Some(tip) => print_error(&format!("{message} ({tip})")),
        None => print_error(message),
    }
    EXIT_BAD_INPUT
}

/// Prints an error as every command does: one line on stderr, `conetrace: error: ...`
/// (a decoder's message can end in blank lines or span several).
pub(crate) fn print_error(message: &str) {
    eprintln!(
        "conetrace: error: {}",
        crate::scene::load::one_line(message)
    );
}

/// Run the parsed command line; returns the exit status.
pub fn run(cli: Cli) -> i32 {
    // Checked before any work, so that a level the processor lacks is refused, not ignored.
    if let Err(message) = conetrace::simd::level_from_environment() {
        print_error(&message);
        return EXIT_BAD_INPUT;
    }
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(&args),
        Command::SampleTexture(args) => sample_texture::run(&args).map_err(CommandError::bad_input),
        Command::Bench(BenchCommand::Render(args)) => bench_render::run(&args),
        Command::Accuracy(args) => accuracy::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Maketx(args) => maketx::run(&args),
        Command::Bench(BenchCommand::Effects(args)) => bench_effects::run(&args),
        Command::Bench(BenchCommand::ScaleOut(args)) => bench_scale_out::run(&args),
        Command::Bench(BenchCommand::Tiles(args)) => bench_tiles::run(&args),
        Command::Bench(BenchCommand::Textures(args)) => {
            bench_textures::run(&args).map_err(CommandError::bad_input)
        }
    };
    match result {
        Ok(()) => EXIT_OK,
        Err(error) => {
            print_error(&error.message);
            error.status
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::load::one_line;

    #[test]
    fn error_messages_print_on_one_line() {
        assert_eq!(
            one_line("a.jpg: cannot decode image: found 0\n\n"),
            "a.jpg: cannot decode image: found 0"
        );
        assert_eq!(one_line("first\r\n  second\n"), "first; second");
        assert_eq!(one_line("plain"), "plain");
    }

    use super::*;

    /// Every command's `--help`, long form, and its name.
    fn all_help_texts(command: &mut clap::Command, path: String, out: &mut Vec<(String, String)>) {
        out.push((path.clone(), command.render_long_help().to_string()));
        for sub in command.get_subcommands_mut() {
            let name = format!("{path} {}", sub.get_name());
            all_help_texts(sub, name, out);
        }
    }

    #[test]
    fn help_texts_carry_no_rustdoc_link_syntax() {
        use clap::CommandFactory;
        let mut texts = Vec::new();
        all_help_texts(&mut Cli::command(), "conetrace".to_string(), &mut texts);
        assert!(texts.len() > 8, "{} commands", texts.len());
        for (command, help) in &texts {
            let link = help.lines().find(|line| line.contains("[`"));
            assert!(link.is_none(), "{command} --help: {link:?}");
        }
    }

    #[test]
    fn a_failed_traversal_is_an_internal_error_with_its_message() {
        let error = render_failed(crate::render::RenderError::Traversal {
            scene: "quad.toml".to_string(),
            source: crate::embree::EmbreeError::FilterPanicked {
                geom_id: 0,
                count: 3,
                message: "alpha texture lookup failed".to_string(),
            },
        });
        assert_eq!(error.status, EXIT_INTERNAL);
        assert!(
            error
                .message
                .starts_with("quad.toml: ray traversal failed: ")
                && error.message.contains("alpha texture lookup failed"),
            "{}",
            error.message
        );
    }
}
