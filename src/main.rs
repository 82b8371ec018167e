//! The `conetrace` binary: the command line (`src/cli`), a client of the `conetrace` library.
//!
//! The command line lives here rather than in the library so that `libconetrace.so`/`.a`,
//! which C programs link, carry none of its dependencies (clap, indicatif, ctrlc, plotters
//! and nv-flip's C++ code).

#![deny(unsafe_code)]

mod cli;

// The library's modules at the root of the binary: `crate::render` in `src/cli` is
// `conetrace::render`.
use conetrace::{embree, film, footprint, integrator, render, scene, shading, texture};

use clap::Parser;

fn main() {
    cli::program_start();
    let cli = match cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => std::process::exit(cli::command_line_error(error)),
    };
    // A panic is a bug: report it as an internal error instead of unwinding into the shell.
    let status = match std::panic::catch_unwind(move || cli::run(cli)) {
        Ok(status) => status,
        Err(_) => cli::EXIT_INTERNAL,
    };
    std::process::exit(status);
}
