//! The `conetrace` binary: parses the command line and maps failures to exit statuses.

#![deny(unsafe_code)]

use clap::Parser;

fn main() {
    let cli = conetrace::cli::Cli::parse();
    // A panic is a bug: report it as an internal error instead of unwinding into the shell.
    let status = match std::panic::catch_unwind(move || conetrace::cli::run(cli)) {
        Ok(status) => status,
        Err(_) => conetrace::cli::EXIT_INTERNAL,
    };
    std::process::exit(status);
}
