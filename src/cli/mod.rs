//! Command line: argument parsing and dispatch.

mod args;
mod inspect;
mod render;
mod scenes;

use std::process::ExitCode;

use clap::Parser;

pub use args::{parse_size, Cli, Command};
pub(crate) use args::{SceneOpts, Worst};
pub(crate) use inspect::find_worst;
pub(crate) use render::{prepare, Prepared};

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
    // No command opens the TUI exactly as `rayterm tui` does.
    let command = cli.command.unwrap_or_else(|| {
        Cli::parse_from(["rayterm", "tui"])
            .command
            .expect("`rayterm tui` parses")
    });
    let result = match command {
        Command::Render(a) => render::run(a),
        Command::Scenes => scenes::run(),
        Command::Inspect(a) => inspect::run(a),
        Command::Tui(a) => crate::tui::run(&a.scene_opts(), a.color),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("rayterm: {e:#}");
            ExitCode::FAILURE
        }
    }
}
