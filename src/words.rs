//! Numbers in words as the UI and the reports print them, and text from
//! files and the command line made safe to print.

use std::path::Path;

/// `s` with control characters (tab and newline too) replaced by U+FFFD:
/// names and values read from files, and paths given on the command line,
/// go through this before a message holds them (an escape sequence in one
/// would reach the terminal).
pub(crate) fn printable(s: &str) -> String {
    printable_but(s, "")
}

/// `s` with control characters other than those in `kept` replaced by
/// U+FFFD.
pub(crate) fn printable_but(s: &str, kept: &str) -> String {
    s.chars()
        .map(|c| match c.is_control() && !kept.contains(c) {
            true => '\u{fffd}',
            false => c,
        })
        .collect()
}

/// The most characters of one name, value or path a message quotes.
pub(crate) const QUOTED: usize = 256;

/// A name, value or path from a file or the command line as a message
/// quotes it: [`printable`], and cut to [`QUOTED`] characters (`…` marking
/// the cut), so a ten-megabyte key is not echoed whole.
pub(crate) fn quoted(s: &str) -> String {
    match s.char_indices().nth(QUOTED) {
        Some((cut, _)) => printable(&s[..cut]) + "…",
        None => printable(s),
    }
}

/// A message of another crate's (a parser's) with what it quotes, between
/// backticks, single or double quotes, cut as [`quoted`] cuts it.
pub(crate) fn clip_quotes(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(4096));
    let mut rest = msg;
    while let Some(open) = rest.find(['`', '\'', '"']) {
        let q = rest[open..].chars().next().unwrap_or('"');
        out.push_str(&rest[..=open]);
        let inner = &rest[open + 1..];
        let (span, tail) = match inner.find(q) {
            Some(close) => (&inner[..close], &inner[close..]),
            None => (inner, ""),
        };
        out.push_str(&quoted(span));
        // The closing quote, if any, and what follows it.
        let (close, after) = tail.split_at(tail.len().min(1));
        out.push_str(close);
        rest = after;
    }
    out.push_str(rest);
    out
}

/// A path as messages and summaries print it: [`Path::display`] prints
/// control characters as they are; `a/../b` and `./` are written out (on
/// the path's own words, as `data/textures/x.png` for a texture a scene
/// in `data/scenes` reaches as `../textures/x.png`).
pub(crate) fn path(p: &Path) -> String {
    quoted(&tidy(p).display().to_string())
}

/// `p` without `.` and with each `..` taking back the name before it,
/// where there is one.
pub(crate) fn tidy(p: &Path) -> std::path::PathBuf {
    use std::path::Component;
    let mut out = std::path::PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.components().next_back() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                // Above the root is the root.
                Some(Component::RootDir) => {}
                _ => out.push(".."),
            },
            c => out.push(c),
        }
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    out
}

/// `1 light`, `3 lights`; `plural` is the word for any count but one.
pub(crate) fn count(n: impl Into<u64>, one: &str, plural: &str) -> String {
    let n = n.into();
    format!("{n} {}", if n == 1 { one } else { plural })
}

/// `n` with an SI prefix and three significant digits: `950`, `1.23k`,
/// `45.6M`.
pub(crate) fn si(x: f64) -> String {
    let (v, unit) = match x.abs() {
        a if a >= 1e9 => (x / 1e9, "G"),
        a if a >= 1e6 => (x / 1e6, "M"),
        a if a >= 1e3 => (x / 1e3, "k"),
        _ => (x, ""),
    };
    match v.abs() {
        _ if unit.is_empty() => format!("{v:.0}"),
        a if a >= 100.0 => format!("{v:.0}{unit}"),
        a if a >= 10.0 => format!("{v:.1}{unit}"),
        _ => format!("{v:.2}{unit}"),
    }
}

/// A rate of rays: `12.3 Mrays/s`, `456 krays/s`, `87 rays/s`.
pub(crate) fn rays_per_s(rays_per_s: f64) -> String {
    format!("{}rays/s", spaced(si(rays_per_s)))
}

/// A time in milliseconds as people read it, three significant digits:
/// `0.05 ms`, `812 ms`, `3.73 s`, then whole seconds: `2 min 05 s`.
pub(crate) fn ms(ms: f64) -> String {
    match ms {
        m if m >= 60e3 => {
            let s = (m / 1e3).round() as u64;
            format!("{} min {:02} s", s / 60, s % 60)
        }
        m if m >= 1e3 => format!("{} s", significant(m / 1e3)),
        m => format!("{} ms", significant(m)),
    }
}

/// Three significant digits, without an exponent for ordinary values.
pub(crate) fn significant(x: f64) -> String {
    match x.abs() {
        a if a >= 100.0 || a == 0.0 => format!("{x:.0}"),
        a if a >= 10.0 => format!("{x:.1}"),
        a if a >= 1.0 => format!("{x:.2}"),
        a if a >= 0.001 => format!("{x:.*}", (2 - a.log10().floor() as i32) as usize),
        _ => format!("{x:.2e}"),
    }
}

/// `1.23k` as `1.23 k`, `950` as `950 `: a unit can follow directly.
fn spaced(s: String) -> String {
    match s.chars().last() {
        Some(c) if c.is_ascii_alphabetic() => {
            let (num, unit) = s.split_at(s.len() - 1);
            format!("{num} {unit}")
        }
        _ => s + " ",
    }
}

/// Why a film's error is not known yet, after `spp` samples in its
/// sparest pixel: too few samples, or a pixel kept fewer than two finite
/// ones (the others NaN or infinite, dropped).
pub(crate) fn error_unknown(spp: u32) -> &'static str {
    if spp < 2 {
        "error unknown until 2 spp"
    } else {
        "error unknown: a pixel kept fewer than 2 finite samples"
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn paths_are_printed_tidy() {
        let p = |s: &str| path(Path::new(s));
        assert_eq!(
            p("data/scenes/../meshes/../textures/checker.png"),
            "data/textures/checker.png"
        );
        assert_eq!(p("./a/./b"), "a/b");
        assert_eq!(p("../x/../y"), "../y");
        assert_eq!(p("/a/../../b"), "/b");
        assert_eq!(p("a/.."), ".");
    }

    use super::*;

    #[test]
    fn counts_agree_with_their_nouns() {
        assert_eq!(count(1u32, "light", "lights"), "1 light");
        assert_eq!(count(0u32, "light", "lights"), "0 lights");
        assert_eq!(count(12u64, "box", "boxes"), "12 boxes");
    }

    #[test]
    fn rates_and_times_keep_three_digits() {
        assert_eq!(si(950.0), "950");
        assert_eq!(si(1_234_567.0), "1.23M");
        assert_eq!(rays_per_s(45_600.0), "45.6 krays/s");
        assert_eq!(rays_per_s(12_345_678.0), "12.3 Mrays/s");
        assert_eq!(rays_per_s(87.0), "87 rays/s");
        assert_eq!(ms(0.0512), "0.0512 ms");
        assert_eq!(ms(12.34), "12.3 ms");
        assert_eq!(ms(1234.0), "1.23 s");
        assert_eq!(significant(0.0), "0");
        assert_eq!(significant(3.0e-6), "3.00e-6");
    }

    #[test]
    fn control_characters_never_reach_the_terminal() {
        assert_eq!(
            printable("a\u{1b}]0;x\u{7}\nb\u{9b}"),
            "a\u{fffd}]0;x\u{fffd}\u{fffd}b\u{fffd}"
        );
        assert_eq!(printable_but("a\tb\nc\u{1b}", "\n\t"), "a\tb\nc\u{fffd}");
        assert_eq!(path(Path::new("e\u{1b}[2J.png")), "e\u{fffd}[2J.png");
    }

    #[test]
    fn quotes_are_cut_to_a_few_hundred_characters() {
        let key = "k".repeat(10_000_000);
        let q = quoted(&key);
        assert_eq!(q.chars().count(), QUOTED + 1);
        assert!(q.ends_with("k…"));
        assert_eq!(quoted("é\u{1b}"), "é\u{fffd}");
        let msg = format!("unknown field `{key}`, expected one of `name`, 'a', \"{key}");
        let cut = clip_quotes(&msg);
        assert!(cut.len() < 2 * QUOTED + 100, "{}", cut.len());
        assert!(cut.starts_with("unknown field `kkk"), "{cut}");
        assert!(
            cut.contains("k…`, expected one of `name`, 'a', \"kkk"),
            "{cut}"
        );
        assert_eq!(clip_quotes("it's fine"), "it's fine");
    }
}
