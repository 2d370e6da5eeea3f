//! The layer rules of `docs/ARCHITECTURE.md`, checked on the source: a
//! module names only modules at its level or below, and only `cli/` (with
//! `main.rs`) names clap and indicatif, only `tui/` ratatui and crossterm.

use std::path::{Path, PathBuf};

/// Each top-level module and its level: a module may name its own level
/// and those below.
const LEVELS: &[(&str, u8)] = &[
    ("geometry", 0),
    ("memory", 0),
    ("words", 0),
    ("interrupt", 0),
    ("choice", 0),
    ("color", 0),
    ("console", 1),
    ("raster", 1),
    ("scene", 2),
    ("bvh", 3),
    ("render", 4),
    ("inspect", 5),
    ("report", 5),
    ("viz", 6),
    ("tui", 7),
    ("cli", 8),
];

/// The crates only one layer may name.
const CRATES: &[(&str, &[&str])] = &[
    ("clap", &["cli", "main.rs"]),
    ("indicatif", &["cli"]),
    ("ratatui", &["tui"]),
    ("crossterm", &["tui"]),
];

fn level(module: &str) -> Option<u8> {
    // `noteln!`, `outln!` and `out!` are the console's macros.
    let module = match module {
        "noteln" | "outln" | "out" => "console",
        m => m,
    };
    LEVELS.iter().find(|(m, _)| *m == module).map(|&(_, l)| l)
}

fn sources(dir: &Path, found: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, found);
        } else if p.extension().is_some_and(|x| x == "rs") {
            found.push(p);
        }
    }
}

/// The code of a line: comments (and so doc links) left out.
fn code(line: &str) -> &str {
    let t = line.trim_start();
    if t.starts_with("//") {
        return "";
    }
    match line.find("// ") {
        Some(i) if !line[..i].contains('"') => &line[..i],
        _ => line,
    }
}

/// Every `crate::NAME` a line names.
fn named(line: &str) -> impl Iterator<Item = &str> {
    line.match_indices("crate::").filter_map(move |(i, _)| {
        let before = line[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            return None;
        }
        let rest = &line[i + 7..];
        let end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        Some(&rest[..end])
    })
}

fn crate_named(line: &str, krate: &str) -> bool {
    line.match_indices(krate).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + krate.len()..].chars().next();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '"' || c == '`')
            && after == Some(':')
    })
}

#[test]
fn layers_name_only_what_is_below_them() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        if rel == Path::new("layers.rs") {
            continue; // its tests quote what it looks for
        }
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_str()
            .unwrap();
        let module = top.trim_end_matches(".rs");
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in text.lines().enumerate() {
            let line = code(line);
            let at = || format!("src/{}:{}", rel.display(), n + 1);
            if let Some(own) = level(module) {
                for m in named(line) {
                    match level(m) {
                        Some(l) if l > own => {
                            wrong.push(format!("{}: {module} names crate::{m}, above it", at()))
                        }
                        None => wrong.push(format!("{}: crate::{m} has no level here", at())),
                        _ => {}
                    }
                }
            }
            for (krate, homes) in CRATES {
                if crate_named(line, krate) && !homes.contains(&top) {
                    wrong.push(format!("{}: {module} names {krate}", at()));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "layer rules broken (docs/ARCHITECTURE.md):\n{}",
        wrong.join("\n")
    );
}

/// What reads the process's signal flag; only the commands choose to stop
/// on a signal, and hand the rest an `interrupt::Cancel`.
const SIGNAL_READS: &[&str] = &["interrupt::requested", "interrupt::flag", "Cancel::Signal"];

#[test]
fn only_the_commands_read_the_signal_flag() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel.components().next().unwrap().as_os_str();
        if ["cli", "tui", "main.rs", "interrupt.rs", "layers.rs"]
            .map(std::ffi::OsStr::new)
            .contains(&top)
        {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in text.lines().enumerate() {
            if SIGNAL_READS.iter().any(|r| code(line).contains(r)) {
                wrong.push(format!("src/{}:{}", rel.display(), n + 1));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "the signal flag read below the commands (take a Cancel):\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_checks_see_what_they_look_for() {
    assert_eq!(
        named("use crate::cli::say; crate::tui::x()").collect::<Vec<_>>(),
        ["cli", "tui"]
    );
    assert_eq!(named("$crate::console::out(x)").count(), 0);
    assert!(crate_named("use clap::ValueEnum;", "clap"));
    assert!(crate_named("#[derive(clap::ValueEnum)]", "clap"));
    assert!(!crate_named("let clap = 1;", "clap"));
    assert_eq!(code("    // crate::cli"), "");
    assert_eq!(code("x(); // crate::cli"), "x(); ");
}
