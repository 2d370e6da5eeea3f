//! The documents' commands, run as written from a fresh directory holding
//! only the repository's `data/` and `tests/` (the files the commands
//! name): every `rayterm` line of the ```` ```sh ```` blocks of the README,
//! then of each page of `docs/`, in the order of [`COMMANDS`] (the TUI
//! ones in a pseudo-terminal, quit with `q`), since later ones read what
//! earlier ones wrote; and every `$ rayterm` example whose output a
//! document shows, compared line by line with only its times and rates
//! masked. The list below is checked against the documents, so a command
//! added to one must be added here, with how to run it. Blocks marked
//! ```` ```shell ```` or ```` ```bash ```` are shown, not run here: they
//! need what the repository does not hold (a cluster, another program), or
//! another test runs them (`tests/suite/split.rs`, the `bash` blocks of
//! docs/split-renders.md). BENCHMARKS.md and docs/notes/ record
//! measurements whose commands mostly need `../shared`; their links are
//! checked, their commands are not run.
//!
//! Also: every relative link in the documents leads to a file that exists,
//! and to a heading of it where it names one.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;

/// How a documented command is checked.
#[derive(Clone, Copy, Debug, PartialEq)]
enum How {
    /// Runs to the end and succeeds.
    Run,
    /// The TUI: draws a frame showing the text, quits on `q` with status 0.
    Tui(&'static str),
    /// Long by design (benchmark tables): still running without an error
    /// after a few seconds, then stopped.
    Starts,
    /// A cargo command: CI runs those.
    Cargo,
}

use How::*;

/// Every document, in the order its commands run, with the commands of its
/// ```` ```sh ```` blocks. Producers come before consumers: the turntable's
/// frames before `animate`, `ref.exr` and `view.exr` before the commands
/// that read them. Pages without commands are listed too, so that a
/// command added to any page is found.
const COMMANDS: &[(&str, &[(&str, How)])] = &[
    (
        "README.md",
        &[
            ("cargo run --release", Cargo),
            ("cargo test --release", Cargo),
            ("cargo install --path .", Cargo),
            ("rayterm mirrors", Tui("(estimated)")),
            ("rayterm scenes", Run),
            ("rayterm render cornell -o cornell.png", Run),
            (
                "rayterm render data/mirrors.toml -o mirrors.png --size 640x360 --no shadows",
                Run,
            ),
            (
                "rayterm render cornell-area -o film.exr --size 256x256",
                Run,
            ),
            (
                "rayterm render tests/files/gltfpack/sphere.glb --env 0.4,0.6,1.0 --size 640x360 --spp 64 -o sphere.png",
                Run,
            ),
            (
                "rayterm render teapot --turntable 24 --size 320x240 --spp 8 -o spin.gif",
                Run,
            ),
            ("rayterm inspect cornell --pixel 400,300", Run),
        ],
    ),
    ("docs/tui.md", &[]),
    (
        "docs/cli.md",
        &[
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
            ("rayterm bench", Starts),
            ("rayterm bench rays teapot:64 --threads 1", Run),
            ("rayterm bench scaling", Starts),
            ("rayterm bench tui teapot:64", Run),
            ("cargo bench", Cargo),
        ],
    ),
    ("docs/scene-format.md", &[]),
    ("docs/formats.md", &[]),
    (
        "docs/shading.md",
        &[
            (
                "rayterm render env --env 0.4,0.6,1.0 --size 640x360 -o blue-sky.png",
                Run,
            ),
            (
                "rayterm render env --env 0.5 --env-strength 2 --size 640x360 -o grey-sky.png",
                Run,
            ),
        ],
    ),
    (
        "docs/debug-views.md",
        &[
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
        ],
    ),
    (
        "docs/inspector.md",
        &[
            ("rayterm inspect cornell --pixel 400,300", Run),
            ("rayterm inspect cornell --pixel 400,300 --json", Run),
            ("rayterm inspect cornell-area --pixel 150,600 --expand", Run),
            ("rayterm inspect mirrors --worst variance", Run),
        ],
    ),
    ("docs/inspect-json.md", &[]),
    (
        "docs/converge.md",
        &[
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
        ],
    ),
    ("docs/adaptive.md", &[]),
    ("docs/split-renders.md", &[]),
    ("docs/stability.md", &[]),
    ("docs/pbr-check.md", &[]),
    ("docs/ARCHITECTURE.md", &[]),
];

/// The documents whose links are checked: [`COMMANDS`]' and these.
const LINKED: &[&str] = &[
    "BENCHMARKS.md",
    "CONTRIBUTING.md",
    "data/README.md",
    "tests/files/README.md",
    "docs/notes/benchmark-history.md",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(doc: &str) -> String {
    std::fs::read_to_string(root().join(doc)).unwrap_or_else(|e| panic!("{doc}: {e}"))
}

/// The lines of a document's ```` ```sh ```` blocks, comments and blanks
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

/// A directory like a fresh clone's working directory: `data/` and
/// `tests/`, nothing else.
fn workdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rayterm-readme-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for folder in ["data", "tests"] {
        std::os::unix::fs::symlink(root().join(folder), d.join(folder)).unwrap();
    }
    d
}

fn args(cmd: &str) -> Vec<&str> {
    assert!(
        !cmd.contains(['"', '\'', '|', '>', '<', '$']),
        "{cmd}: plain words only"
    );
    cmd.split_whitespace().skip(1).collect()
}

/// Every command the documents show, checked as a whole list, document by
/// document; and every page of `docs/` is in the list.
#[test]
fn the_documented_commands_are_the_checked_list() {
    for (doc, commands) in COMMANDS {
        let listed: Vec<&str> = commands.iter().map(|c| c.0).collect();
        assert_eq!(
            sh_commands(&read(doc)),
            listed,
            "{doc}'s commands changed: update COMMANDS in tests/readme.rs"
        );
    }
    let pages: HashSet<String> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    let listed: HashSet<String> = COMMANDS
        .iter()
        .map(|c| c.0.to_string())
        .filter(|d| d.starts_with("docs/"))
        .collect();
    assert_eq!(
        pages, listed,
        "add the new page to COMMANDS in tests/readme.rs"
    );
    assert!(COMMANDS
        .iter()
        .any(|(doc, _)| !examples(&read(doc)).is_empty()));
}

/// Runs every command in order, as the documents list them.
#[test]
fn every_documented_command_runs_as_written() {
    let dir = workdir("run");
    let bin = env!("CARGO_BIN_EXE_rayterm");
    for &(cmd, how) in COMMANDS.iter().flat_map(|c| c.1.iter()) {
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
                    // The documented reference is three times the view: exact.
                    assert!(!text.contains("resampled"), "{cmd}: resampled");
                }
            }
        }
        eprintln!("{:6.1} s  {cmd}", started.elapsed().as_secs_f64());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Units of the figures that change from run to run, and what each reads
/// as once masked: a duration reads in the unit that fits it (`812.3 ms`,
/// `24.9 s`), a rate too (`980.2 krays/s` on a loaded machine).
const UNITS: &[(&str, &str)] = &[
    (" ms", " s"),
    (" s", " s"),
    (" µs", " s"),
    (" Mrays/s", " Mrays/s"),
    (" krays/s", " Mrays/s"),
];

/// Times and rates masked (`#` and the unit), so that an example's
/// timings are not compared; every other number (counts, samples, errors,
/// coordinates: the same on every run and machine) stays as it is.
fn masked(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let len = rest[start..]
            .find(|c: char| !c.is_ascii_digit() && c != '.')
            .unwrap_or(rest.len() - start);
        let (number, after) = (&rest[start..start + len], &rest[start + len..]);
        // A number inside a word (`x1`, `0x1f`) is part of the word.
        let in_word = rest[..start]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric());
        let unit = UNITS.iter().find(|(u, _)| {
            after.starts_with(u)
                && !after[u.len()..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_alphanumeric())
        });
        out.push_str(&rest[..start]);
        match unit {
            Some((u, reads)) if !in_word => {
                out.push('#');
                out.push_str(reads);
                rest = &after[u.len()..];
            }
            _ => {
                out.push_str(number);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

#[test]
fn masking_leaves_all_but_times_and_rates() {
    assert_eq!(
        masked("build 0.0 ms (sah), render 2.5 s, 12 / 32.0 / 384 spp, 9.07 Mrays/s, error 0.955%"),
        "build # s (sah), render # s, 12 / 32.0 / 384 spp, # Mrays/s, error 0.955%"
    );
    assert_eq!(masked("980.2 krays/s at 64x64"), "# Mrays/s at 64x64");
    assert_eq!(masked("levels 0 to 13"), "levels 0 to 13");
    assert_eq!(masked("(97.6 ms) -> heat.png"), "(# s) -> heat.png");
    assert_eq!(masked("4 spp"), "4 spp");
}

/// The examples with output print what the documents show: each line
/// equals the program's with times and rates masked, and `  ...` stands
/// for any run of lines. An example whose output is an error
/// (`rayterm: ...`) must fail with it.
#[test]
fn documented_examples_print_what_the_documents_show() {
    let dir = workdir("examples");
    let mut count = 0;
    for (doc, _) in COMMANDS {
        for (cmd, expected) in examples(&read(doc)) {
            count += 1;
            let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
                .args(args(&cmd))
                .current_dir(&dir)
                .stdin(Stdio::null())
                .output()
                .unwrap();
            let fails = expected.first().is_some_and(|l| l.starts_with("rayterm: "));
            assert_eq!(
                out.status.success(),
                !fails,
                "{doc}: {cmd}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            // A render's progress lines stand for the bar a terminal shows
            // and clears, which the examples leave out.
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
                    "{doc}: {cmd}: expected\n  {w}\nat line {g} of\n{}",
                    got.join("\n")
                );
                g += 1;
                skipping = false;
            }
            assert!(
                skipping || g == got.len(),
                "{doc}: {cmd}: more output than the document shows:\n{}",
                got[g..].join("\n")
            );
        }
    }
    assert!(count > 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A heading's anchor as GitHub makes it: lower case, punctuation but `-`
/// and `_` dropped, spaces made `-`.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings (fenced blocks left out),
/// repeated ones numbered as GitHub numbers them.
fn anchors(text: &str) -> HashSet<String> {
    let mut out = HashSet::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with("```") {
            inside = !inside;
            continue;
        }
        let hashes = line.len() - line.trim_start_matches('#').len();
        if inside || !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let a = anchor(&line[hashes..]);
        let mut name = a.clone();
        let mut n = 0;
        while out.contains(&name) {
            n += 1;
            name = format!("{a}-{n}");
        }
        out.insert(name);
    }
    out
}

/// The targets of a Markdown file's links (`[text](target)`, images too),
/// outside fenced blocks and inline code.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with("```") {
            inside = !inside;
            continue;
        }
        if inside {
            continue;
        }
        // Inline code dropped: every other backtick-delimited span.
        let plain: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let mut rest = plain.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            out.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    out
}

/// Every relative link of the documents leads to a file or folder of the
/// repository, and to a heading of it where it names one.
#[test]
fn every_link_between_the_documents_resolves() {
    let mut broken = Vec::new();
    let docs = COMMANDS.iter().map(|c| c.0).chain(LINKED.iter().copied());
    for doc in docs {
        let text = read(doc);
        let base = root().join(doc).parent().unwrap().to_path_buf();
        for target in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, fragment) = match target.split_once('#') {
                Some((p, f)) => (p, Some(f)),
                None => (target.as_str(), None),
            };
            let file = if path.is_empty() {
                root().join(doc)
            } else {
                base.join(path)
            };
            if !file.exists() {
                broken.push(format!("{doc}: {target}: no such file"));
                continue;
            }
            if let Some(fragment) = fragment {
                let known = file.extension().is_some_and(|e| e == "md")
                    && anchors(&std::fs::read_to_string(&file).unwrap()).contains(fragment);
                if !known {
                    broken.push(format!("{doc}: {target}: no such heading"));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}
