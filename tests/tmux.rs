//! The TUI inside tmux, driven as a user would (`send-keys`) and read back
//! from the pane (`capture-pane`): it leaves the pane's title alone, with
//! and without passthrough; the hint on its colours is whole in a narrow
//! terminal; defaults come from the environment and the config file, and a
//! bad file is named with its line. Skips, saying so, where tmux is not
//! installed.

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
        let out = t.run(&["new-session", "-d", "-x", &size[0], "-y", &size[1], "sh"]);
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

    /// Clears the screen, and waits until it is.
    fn clear(&self) {
        self.type_line("clear");
        let end = Instant::now() + PATIENCE;
        while self.screen().contains(ENDED) {
            assert!(Instant::now() < end, "no clear:\n{}", self.screen());
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Types a command line that ends by saying so, on a clear screen, and
    /// waits for that.
    fn run_to_end(&self, line: &str) {
        self.clear();
        self.type_line(&format!("{line}; echo rayterm-\"ended\""));
        self.wait_for(ENDED);
    }
}

/// What the shell prints after a command (its echo of the line, quoted,
/// does not say it).
const ENDED: &str = "rayterm-ended";

impl Drop for Tmux {
    fn drop(&mut self) {
        self.run(&["kill-server"]);
    }
}

/// Runs the TUI in the pane until it has drawn, and quits it with `q`;
/// returns the screen it drew. `env` goes before the command.
fn run_and_quit(t: &Tmux, env: &str, args: &str) -> String {
    t.clear();
    t.type_line(&format!(
        "{env} {} tui {args}; echo rayterm-\"ended\"",
        env!("CARGO_BIN_EXE_rayterm")
    ));
    t.wait_for("Render");
    let screen = t.screen();
    t.run(&["send-keys", "-t", "0", "q"]);
    t.wait_for(ENDED);
    screen
}

/// No truecolor from the environment: tmux's own terminfo entry has none.
const NO_TRUECOLOR: &str = "env -u COLORTERM TERM=screen-256color";

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
        run_and_quit(&t, "", "cornell");
        assert_eq!(t.title(), before, "allow-passthrough {passthrough}");
    }
}

#[test]
fn the_colour_hint_is_whole_at_80_columns() {
    let Some(t) = Tmux::start("hint", 80, 24) else {
        return;
    };
    // Over ssh, in a terminal (tmux, without a client) that says nothing
    // of 24-bit colour.
    let screen = run_and_quit(&t, &format!("SSH_TTY=/dev/pts/9 {NO_TRUECOLOR}"), "cornell");
    let lines: Vec<&str> = screen.lines().collect();
    let bottom = lines[lines.len().saturating_sub(3)..].join(" ");
    let bottom = bottom.split_whitespace().collect::<Vec<_>>().join(" ");
    let hint = "256 colours: no answer on 24-bit colour, and ssh does not pass COLORTERM on; \
                for 24-bit: --color truecolor or RAYTERM_COLOR=truecolor";
    assert!(bottom.contains(hint), "{screen}");
}

#[test]
fn defaults_come_from_the_environment_and_the_config_file() {
    let Some(t) = Tmux::start("config", 120, 36) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("rayterm-tmux-config-{}", std::process::id()));
    let file = dir.join("rayterm").join("config.toml");
    std::fs::create_dir_all(file.parent().unwrap()).unwrap();
    std::fs::write(&file, "symbols = \"quad\"\ncolor = \"256\"\n").unwrap();
    let xdg = format!("XDG_CONFIG_HOME={}", dir.display());
    let title = |screen: &str| screen.lines().next().unwrap_or("").to_string();
    // The file's choices, the variable over the file, the option over both.
    let screen = run_and_quit(&t, &format!("{xdg} {NO_TRUECOLOR}"), "cornell");
    assert!(
        title(&screen).contains("quadrants · 256 colours"),
        "{screen}"
    );
    let screen = run_and_quit(&t, &format!("{xdg} RAYTERM_COLOR=16"), "cornell");
    assert!(
        title(&screen).contains("quadrants · 16 colours"),
        "{screen}"
    );
    let screen = run_and_quit(
        &t,
        &format!("{xdg} RAYTERM_COLOR=16"),
        "cornell --symbols sextant --color truecolor",
    );
    assert!(title(&screen).contains("sextants · truecolor"), "{screen}");
    // A bad value: the file and the line, before the screen changes.
    std::fs::write(&file, "color = \"256\"\nsymbols = \"braille\"\n").unwrap();
    t.run_to_end(&format!(
        "{xdg} {} tui cornell",
        env!("CARGO_BIN_EXE_rayterm")
    ));
    let said = format!("{}:2: \"braille\" is not one of", file.display());
    let screen = t.screen().split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(screen.contains(&said), "{screen}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Through passthrough, each image band moves the cursor of the terminal
/// tmux runs in itself, to its place in this pane (the pane's corner plus
/// the viewport's cell), and puts it back: tmux moves that cursor only when
/// it next draws, so a bare cursor move before the image went nowhere
/// near it. Here that terminal is a second tmux's pane, whose input
/// `pipe-pane` records.
#[test]
fn images_through_passthrough_land_in_the_pane() {
    let Some(inner) = Tmux::start("inner", 120, 40) else {
        return;
    };
    // Wide enough for two panes the TUI fits in: tmux sizes the inner
    // window to its client's terminal.
    let outer = Tmux::start("outer", 200, 50).unwrap();
    inner.run(&["set-option", "-g", "allow-passthrough", "on"]);
    let dir = std::env::temp_dir().join(format!("rayterm-tmux-place-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("outer.log");
    let pipe = format!("cat > '{}'", log.display());
    outer.run(&["pipe-pane", "-o", "-t", "0", &pipe]);
    outer.type_line(&format!(
        "env -u TMUX tmux -L {} -f /dev/null attach",
        inner.socket
    ));
    let end = Instant::now() + PATIENCE;
    while inner.text(&["list-clients"]).trim().is_empty() {
        assert!(Instant::now() < end, "the client did not attach");
        std::thread::sleep(Duration::from_millis(50));
    }
    // The pane on the right: its corner is not the terminal's.
    let pane = inner.text(&["split-window", "-h", "-P", "-F", "#{pane_id}", "sh"]);
    let pane = pane.trim();
    let place = inner.text(&[
        "display-message",
        "-p",
        "-t",
        pane,
        "#{pane_left} #{pane_width}",
    ]);
    let (left, width): (u16, u16) = {
        let mut v = place.split_whitespace().map(|n| n.parse().unwrap());
        (v.next().unwrap(), v.next().unwrap())
    };
    assert!(left > 10, "{place}");
    let line = format!(
        "{} tui cornell --graphics sixel; echo rayterm-\"ended\"",
        env!("CARGO_BIN_EXE_rayterm")
    );
    inner.run(&["send-keys", "-t", pane, "-l", &line]);
    inner.run(&["send-keys", "-t", pane, "Enter"]);
    // Bands: ESC 7, a cursor move, then a sixel image.
    let bands = || -> Vec<(u16, u16)> {
        let bytes = std::fs::read(&log).unwrap_or_default();
        let text = String::from_utf8_lossy(&bytes);
        text.split("\x1b7\x1b[")
            .skip(1)
            .filter_map(|s| {
                let (at, rest) = s.split_once('H')?;
                rest.starts_with("\x1bP").then_some(())?;
                let (r, c) = at.split_once(';')?;
                Some((r.parse().ok()?, c.parse().ok()?))
            })
            .collect()
    };
    let end = Instant::now() + PATIENCE;
    while bands().len() < 2 {
        assert!(Instant::now() < end, "no image bands reached the terminal");
        std::thread::sleep(Duration::from_millis(100));
    }
    inner.run(&["send-keys", "-t", pane, "q"]);
    let bands = bands();
    // Every band starts in the pane's columns (cursor moves count from 1),
    // and the bands go down the viewport.
    for &(row, col) in &bands {
        assert!(col > left && col <= left + width, "{bands:?} left {left}");
        assert!((1..=50).contains(&row), "{bands:?}");
    }
    assert!(bands.iter().any(|b| b.0 != bands[0].0), "{bands:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
