//! The README's commands, run as written from a fresh directory holding
//! only the repository's `data/`: every `rayterm` line of its `sh` blocks
//! (the TUI ones in a pseudo-terminal, quit with `q`), in order, since later
//! ones read what earlier ones wrote; and every `$ rayterm` example whose
//! output the README shows, compared line by line with its numbers masked.
//! The list below is checked against the README, so a command added there
//! must be added here, with how to run it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;

/// How a README command is checked.
#[derive(Clone, Copy, Debug, PartialEq)]
enum How {
    /// Runs to the end and succeeds.
    Run,
    /// The TUI: draws a frame with an estimated error (or, given the text,
    /// that text), quits on `q` with status 0.
    Tui(&'static str),
    /// Long by design (benchmark tables): still running without an error
    /// after a few seconds, then stopped.
    Starts,
    /// A cargo command: CI runs those.
    Cargo,
}

use How::*;

const COMMANDS: &[(&str, How)] = &[
    ("cargo run --release", Cargo),
    ("cargo test --release", Cargo),
    ("cargo build --release", Cargo),
    ("rayterm scenes", Run),
    ("rayterm render cornell -o cornell.png", Run),
    (
        "rayterm render teapot:64 -o t.png --size 1920x1080 --spp 4",
        Run,
    ),
    (
        "rayterm render data/mirrors.toml -o out.png --no shadows --no reflections",
        Run,
    ),
    (
        "rayterm render data/meshes/cornell.obj -o box.png --builder median --threads 1",
        Run,
    ),
    (
        "rayterm render cornell-area -o film.exr --size 256x256",
        Run,
    ),
    (
        "rayterm render teapot --turntable 24 --size 320x240 --spp 8 -o spin.gif",
        Run,
    ),
    (
        "rayterm render teapot --frame 1/3 --size 240x180 --spp 4 -o f1.png",
        Run,
    ),
    (
        "rayterm render teapot --frame 2/3 --size 240x180 --spp 4 -o f2.png",
        Run,
    ),
    (
        "rayterm render teapot --frame 3/3 --size 240x180 --spp 4 -o f3.png",
        Run,
    ),
    (
        "rayterm animate f1.png f2.png f3.png --fps 6 -o spin3.apng",
        Run,
    ),
    (
        "rayterm render env --env 0.4,0.6,1.0 --size 640x360 -o blue-sky.png",
        Run,
    ),
    (
        "rayterm render env --env 0.5 --env-strength 2 --size 640x360 -o grey-sky.png",
        Run,
    ),
    (
        "rayterm render teapot --debug bvh-level:4 -o level4.png",
        Run,
    ),
    (
        "rayterm render cornell --debug bvh-leaves -o leaves.png",
        Run,
    ),
    ("rayterm render teapot:32 --debug bvh-heat -o heat.png", Run),
    (
        "rayterm render teapot:32 --debug bvh-heat:tests -o tests.png",
        Run,
    ),
    (
        "rayterm render cornell --debug ray:400,500:traversal -o traversal.png",
        Run,
    ),
    (
        "rayterm render cornell --debug ray:400,500:traversal:1 -o shadow.png",
        Run,
    ),
    (
        "rayterm render mirrors --size 640x480 --debug ray:320,330:normals -o normals.png",
        Run,
    ),
    (
        "rayterm render cube-textured --size 480x360 --debug ray:240,150:texture -o texel.png",
        Run,
    ),
    (
        "rayterm render env --size 640x360 --debug ray:330,190:environment -o env.png",
        Run,
    ),
    (
        "rayterm render cornell-area --size 400x400 --spp 16 --debug samples:200,330 -o samples.png",
        Run,
    ),
    ("rayterm render cornell --debug bloom -o bloom.png", Run),
    ("rayterm inspect cornell --pixel 400,300", Run),
    ("rayterm inspect cornell --pixel 400,300 --json", Run),
    ("rayterm inspect cornell-area --pixel 150,600 --expand", Run),
    ("rayterm inspect mirrors --worst variance", Run),
    (
        "rayterm converge cornell-area --plot err.png --csv err.csv",
        Run,
    ),
    (
        "rayterm converge mirrors --spp 1,2,4,8,16,32 --seeds 5",
        Run,
    ),
    (
        "rayterm render cornell-area --spp 1024 --size 64x64 -o ref.exr",
        Run,
    ),
    (
        "rayterm converge cornell-area --times 0.05,0.1,0.2 --reference ref.exr",
        Run,
    ),
    ("rayterm tui cornell-area", Tui("114x64")),
    (
        "rayterm render cornell-area --spp 256 --size 342x192 -o view.exr",
        Run,
    ),
    (
        "rayterm tui cornell-area --reference view.exr",
        Tui("(true)"),
    ),
    ("rayterm bench", Starts),
    ("rayterm bench rays teapot:64 --threads 1", Run),
    ("rayterm bench scaling", Starts),
    ("rayterm bench tui teapot:64", Run),
    ("cargo bench", Cargo),
];

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap()
}

/// The lines of the README's ```` ```sh ```` blocks, comments and blanks
/// left out.
fn sh_commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with("```") {
            inside = !inside && line.trim() == "```sh";
            continue;
        }
        if inside {
            let cmd = line.split(" #").next().unwrap().trim();
            if !cmd.is_empty() {
                out.push(cmd.to_string());
            }
        }
    }
    out
}

/// The examples shown with their output: (command, expected lines).
fn examples(text: &str) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    let mut current: Option<(String, Vec<String>)> = None;
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with("```") {
            if inside {
                out.extend(current.take());
            }
            inside = !inside;
            continue;
        }
        if !inside {
            continue;
        }
        match (line.strip_prefix("$ "), &mut current) {
            (Some(cmd), _) => {
                out.extend(current.take());
                current = Some((cmd.to_string(), Vec::new()));
            }
            (None, Some((_, lines))) => lines.push(line.to_string()),
            (None, None) => {}
        }
    }
    out
}

/// A directory like a fresh clone's working directory: `data/` and nothing
/// else.
fn workdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rayterm-readme-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::os::unix::fs::symlink(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data"),
        d.join("data"),
    )
    .unwrap();
    d
}

fn args(cmd: &str) -> Vec<&str> {
    assert!(
        !cmd.contains(['"', '\'', '|', '>', '<', '$']),
        "{cmd}: plain words only"
    );
    cmd.split_whitespace().skip(1).collect()
}

/// Every `rayterm` argument the README shows, checked as a whole list.
#[test]
fn the_readme_commands_are_the_checked_list() {
    let text = readme();
    let listed: Vec<&str> = COMMANDS.iter().map(|c| c.0).collect();
    assert_eq!(
        sh_commands(&text),
        listed,
        "the README's commands changed: update COMMANDS in tests/readme.rs"
    );
    assert!(!examples(&text).is_empty());
}

/// Runs every command in order, as the README lists them.
#[test]
fn every_readme_command_runs_as_written() {
    let dir = workdir("run");
    let bin = env!("CARGO_BIN_EXE_rayterm");
    for &(cmd, how) in COMMANDS {
        let started = Instant::now();
        match how {
            Cargo => continue,
            Run => {
                let out = Command::new(bin)
                    .args(args(cmd))
                    .current_dir(&dir)
                    .stdin(Stdio::null())
                    .output()
                    .unwrap();
                assert!(
                    out.status.success(),
                    "{cmd}: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
            Starts => {
                let mut child = Command::new(bin)
                    .args(args(cmd))
                    .current_dir(&dir)
                    .stdin(Stdio::null())
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap();
                std::thread::sleep(Duration::from_secs(3));
                if let Some(status) = child.try_wait().unwrap() {
                    assert!(status.success(), "{cmd}: {status:?}");
                } else {
                    child.kill().unwrap();
                    child.wait().unwrap();
                }
            }
            Tui(shows) => {
                let (status, out) = pty::run_tui(
                    &dir,
                    &args(cmd),
                    (160, 48),
                    shows.as_bytes(),
                    b"q",
                    Duration::from_secs(60),
                );
                let text = String::from_utf8_lossy(&out);
                assert!(text.contains(shows), "{cmd}: never showed {shows}");
                assert!(
                    status.is_some_and(|s| s.success()),
                    "{cmd}: did not quit on q: {status:?}"
                );
                if shows == "(true)" {
                    // The README's reference is three times the view: exact.
                    assert!(!text.contains("resampled"), "{cmd}: resampled");
                }
            }
        }
        eprintln!("{:6.1} s  {cmd}", started.elapsed().as_secs_f64());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Numbers (and the words that carry units with them) masked, so that an
/// example's shape is compared, not its timings.
fn masked(line: &str) -> String {
    let mut out = String::new();
    let mut number = false;
    for c in line.chars() {
        let digit = c.is_ascii_digit() || (number && c == '.');
        if digit {
            if !number {
                out.push('#');
            }
        } else {
            out.push(c);
        }
        number = digit;
    }
    // A duration reads in the unit that fits it: `812.3 ms`, `24.9 s`; a
    // rate too (`980.2 krays/s` on a loaded machine).
    out.replace("# ms", "# s").replace("# krays/s", "# Mrays/s")
}

/// The examples with output print lines of the same shape: each README
/// line, numbers masked, equals the program's, and `  ...` stands for any
/// run of lines.
#[test]
fn readme_examples_print_what_the_readme_shows() {
    let dir = workdir("examples");
    for (cmd, expected) in examples(&readme()) {
        let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(args(&cmd))
            .current_dir(&dir)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(out.status.success(), "{cmd}");
        // A render's progress lines stand for the bar a terminal shows and
        // clears, which the examples leave out.
        let err = String::from_utf8_lossy(&out.stderr);
        let err: String = err
            .lines()
            .filter(|l| {
                !["render: ", "progress: ", "checkpoint: "]
                    .iter()
                    .any(|p| l.starts_with(p))
            })
            .map(|l| format!("{l}\n"))
            .collect();
        let printed = format!("{err}{}", String::from_utf8_lossy(&out.stdout));
        let got: Vec<String> = printed
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(masked)
            .collect();
        let want: Vec<String> = expected
            .iter()
            .filter(|l| !l.trim().is_empty())
            .map(|l| masked(l))
            .collect();
        let mut g = 0;
        let mut skipping = false;
        for w in &want {
            if w.trim() == "..." {
                skipping = true;
                continue;
            }
            while skipping && g < got.len() && &got[g] != w {
                g += 1;
            }
            assert!(
                g < got.len() && &got[g] == w,
                "{cmd}: expected\n  {w}\nat line {g} of\n{}",
                got.join("\n")
            );
            g += 1;
            skipping = false;
        }
        assert!(
            skipping || g == got.len(),
            "{cmd}: more output than the README shows:\n{}",
            got[g..].join("\n")
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
