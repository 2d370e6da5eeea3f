//! The TUI inside tmux, driven as a user would (`send-keys`) and read back
//! from the pane (`capture-pane`): it leaves the pane's title alone, with
//! and without passthrough. Skips, saying so, where tmux is not installed.

use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// How long the TUI may take to start or quit.
const PATIENCE: Duration = Duration::from_secs(30);

/// A tmux server of its own (its own socket, no configuration file), with
/// one detached session running a shell; killed when dropped.
struct Tmux {
    socket: String,
}

impl Tmux {
    /// None (after saying so) where tmux is missing.
    fn start(name: &str, cols: u16, rows: u16) -> Option<Tmux> {
        if Command::new("tmux").arg("-V").output().is_err() {
            eprintln!("skipped: tmux is not installed");
            return None;
        }
        let t = Tmux {
            socket: format!("rayterm-test-{name}-{}", std::process::id()),
        };
        let size = [cols.to_string(), rows.to_string()];
        let out = t.run(&[
            "new-session",
            "-d",
            "-x",
            &size[0],
            "-y",
            &size[1],
            "sh",
        ]);
        assert!(out.status.success(), "tmux: {out:?}");
        Some(t)
    }

    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
            .unwrap()
    }

    fn text(&self, args: &[&str]) -> String {
        String::from_utf8_lossy(&self.run(args).stdout).into_owned()
    }

    fn title(&self) -> String {
        self.text(&["display-message", "-p", "-t", "0", "#{pane_title}"])
    }

    fn screen(&self) -> String {
        self.text(&["capture-pane", "-p", "-t", "0"])
    }

    /// Types `text` and Enter into the shell.
    fn type_line(&self, text: &str) {
        self.run(&["send-keys", "-t", "0", "-l", text]);
        self.run(&["send-keys", "-t", "0", "Enter"]);
    }

    /// Waits until the pane shows `needle`.
    fn wait_for(&self, needle: &str) {
        let end = Instant::now() + PATIENCE;
        while !self.screen().contains(needle) {
            assert!(
                Instant::now() < end,
                "no {needle:?} on screen:\n{}",
                self.screen()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        self.run(&["kill-server"]);
    }
}

/// Runs the TUI in the pane until it has drawn, and quits it with `q`
/// (the shell's echo of the line, quoted, does not say it ended).
fn run_and_quit(t: &Tmux, args: &str) {
    t.type_line(&format!(
        "{} tui {args}; echo rayterm-\"ended\"",
        env!("CARGO_BIN_EXE_rayterm")
    ));
    t.wait_for("Render");
    t.run(&["send-keys", "-t", "0", "q"]);
    t.wait_for("rayterm-ended");
}

#[test]
fn the_pane_title_stays_as_it_was() {
    let Some(t) = Tmux::start("title", 120, 36) else {
        return;
    };
    let before = t.title();
    // Without passthrough the graphics queries stay out of tmux; with it
    // they go through, wrapped, to the (here absent) outer terminal.
    for passthrough in ["off", "on"] {
        t.run(&["set-option", "-g", "allow-passthrough", passthrough]);
        run_and_quit(&t, "cornell");
        assert_eq!(t.title(), before, "allow-passthrough {passthrough}");
    }
}
