//! Command line: argument parsing and dispatch.

mod args;
mod bench;
mod choices;
mod converge;
mod debug;
mod inputs;
mod inspect;
mod merge;
mod progress;
mod render;
mod scenes;
mod stability;
mod turntable;

use std::process::ExitCode;

use clap::Parser;

use anyhow::Result;

pub(crate) use args::{Cli, Command, SceneOpts};

use crate::render::{SceneRequest, Session};
use crate::scene::Scene;

/// `rayterm SCENE [OPTIONS]` (anything but a command, help or version
/// first) means `rayterm tui SCENE [OPTIONS]`.
fn with_default_command(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    use clap::CommandFactory;
    let Some(first) = args.get(1) else {
        return args;
    };
    // An argument that is not UTF-8 names no command: a scene, for the TUI.
    let first = first.to_str().unwrap_or_default();
    let cli = Cli::command();
    let named = cli
        .get_subcommands()
        .any(|c| c.get_name() == first || c.get_all_aliases().any(|a| a == first));
    let own = ["-h", "--help", "-V", "--version", "help"].contains(&first);
    if !named && !own {
        args.insert(1, "tui".into());
    }
    args
}

pub fn main() -> ExitCode {
    crate::interrupt::default_sigpipe();
    let cli = match Cli::try_parse_from(with_default_command(std::env::args_os().collect())) {
        Ok(cli) => cli,
        // Help, the version, or a usage error: printed by clap, whose own
        // exit would pass over a stream that cannot be written.
        Err(e) => {
            return match e.print() {
                Ok(()) => ExitCode::from(e.exit_code() as u8),
                Err(io) => {
                    crate::noteln!("rayterm: cannot write to standard output: {io}");
                    ExitCode::FAILURE
                }
            };
        }
    };
    if let Some(n) = cli.threads() {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            crate::noteln!("rayterm: cannot set up {n} threads: {e}");
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
        Command::Merge(a) => merge::run(a),
        Command::Animate(a) => turntable::animate(a),
        Command::Inputs(a) => inputs::run(a),
        Command::Scenes => scenes::run(),
        Command::Inspect(a) => inspect::run(a),
        Command::Converge(a) => converge::run(a),
        Command::Tui(a) => crate::tui::run(
            &a.scene.request(),
            a.color,
            a.symbols,
            a.graphics,
            a.reference.as_deref(),
        ),
        Command::Stability(a) => stability::run(a),
        Command::Bench(a) => bench::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            say("rayterm", &format!("{e:#}"));
            ExitCode::FAILURE
        }
    }
}

/// Opens the scene the options name, with its load warnings on stderr.
fn open_scene(opts: &SceneOpts) -> Result<Session> {
    open_request(&opts.request())
}

/// Opens the scene `req` names, with its load warnings on stderr.
fn open_request(req: &SceneRequest) -> Result<Session> {
    let (session, warnings) = Session::open(req)?;
    for w in &warnings {
        say("warning", w);
    }
    Ok(session)
}

/// Loads a scene for its geometry alone (no BVH, no plan), with its load
/// warnings on stderr.
fn load_scene(spec: &str) -> Result<Scene> {
    let mut scene = crate::scene::load::open(spec, &Default::default())?.scene;
    for w in std::mem::take(&mut scene.warnings) {
        say("warning", &w);
    }
    Ok(scene)
}

pub(crate) use crate::console::say;

/// The reader of our output went away (`rayterm inspect ... | head`): not a failure.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(args: &[&str]) -> Vec<String> {
        with_default_command(args.iter().map(Into::into).collect())
            .into_iter()
            .map(|a| a.into_string().unwrap())
            .collect()
    }

    #[test]
    fn a_scene_first_opens_the_tui() {
        assert_eq!(
            parsed(&["rayterm", "cornell"]),
            ["rayterm", "tui", "cornell"]
        );
        assert_eq!(
            parsed(&["rayterm", "--color", "256"]),
            ["rayterm", "tui", "--color", "256"]
        );
        for kept in [
            &["rayterm"][..],
            &["rayterm", "render", "cornell", "-o", "x.png"],
            &["rayterm", "--help"],
            &["rayterm", "help"],
            &["rayterm", "scenes"],
        ] {
            assert_eq!(parsed(kept), kept);
        }
        let cli = Cli::try_parse_from(parsed(&["rayterm", "m.obj", "--size", "64x48"])).unwrap();
        assert!(matches!(cli.command, Some(Command::Tui(_))));
    }
}
