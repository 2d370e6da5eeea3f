//! Command line: argument parsing and dispatch.

mod args;
mod bench;
mod inspect;
mod render;
mod scenes;

use std::process::ExitCode;

use clap::Parser;

pub use args::{parse_size, Cli, Command};

pub fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(n) = cli.threads() {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("rayterm: cannot set up {n} threads: {e}");
            return ExitCode::FAILURE;
        }
    }
    let result = match cli.command {
        Command::Render(a) => render::run(a),
        Command::Scenes => scenes::run(),
        Command::Inspect(a) => inspect::run(a),
        Command::Bench(a) => bench::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("rayterm: {e:#}");
            ExitCode::FAILURE
        }
    }
}
