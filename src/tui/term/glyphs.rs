//! Which block symbols the terminal shows. Two things can be found out at
//! startup: how far a glyph moves the cursor (print one, then ask for the
//! cursor's position), and which terminal it is (XTVERSION, or what tmux
//! was told by its own terminal). Whether the font has a glyph cannot: a
//! terminal that lacks one draws a box or nothing and still moves the
//! cursor one cell. So `auto` picks sextants or octants only in terminals
//! known to draw them themselves, without a font, and a set asked for by
//! name is kept but said to be at risk where that is not known.

use crate::tui::graphics::symbols::{Symbols, SymbolsArg};

/// Terminals that draw block symbols themselves, whatever the font: the
/// name XTVERSION gives, and the first version that draws quadrants,
/// sextants and octants (`None`: no version does yet).
/// - kitty: sextants since 0.19.0, with fixes in 0.19.3; octants since
///   0.40.0 (its changelog).
/// - WezTerm (`custom_block_glyphs`, on by default): block elements since
///   20210314, sextants since 20210814; octants only in nightly builds.
const KNOWN: &[(&str, [Option<&str>; 3])] = &[
    ("kitty", [Some("0"), Some("0.19.3"), Some("0.40.0")]),
    ("WezTerm", [Some("20210314"), Some("20210814"), None]),
];

/// The densest set that `terminal` (an XTVERSION answer: `kitty(0.40.1)`,
/// `WezTerm 20240203-110809-5046fc22`) draws itself, if it is one known.
fn drawn(terminal: &str) -> Option<Symbols> {
    let (name, version) = split(terminal);
    let (_, since) = KNOWN.iter().find(|(n, _)| n.eq_ignore_ascii_case(name))?;
    let sets = [Symbols::Quad, Symbols::Sextant, Symbols::Octant];
    let best = sets
        .iter()
        .zip(since)
        .rev()
        .find(|(_, v)| v.is_some_and(|v| at_least(version, v)))
        .map(|(s, _)| *s);
    Some(best.unwrap_or(Symbols::Half))
}

/// A name and a version: `name(1.2.3)` or `name 1.2.3`.
fn split(terminal: &str) -> (&str, &str) {
    let t = terminal.trim();
    match t.find(['(', ' ']) {
        Some(i) => (&t[..i], t[i + 1..].trim_end_matches(')').trim()),
        None => (t, ""),
    }
}

/// Whether `version` is `least` or later, compared number by number
/// (`0.40.1` against `0.40.0`; `20240203-110809-5046fc22` against
/// `20210814`); a version without numbers is not.
fn at_least(version: &str, least: &str) -> bool {
    let numbers = |v: &str| -> Vec<u64> {
        v.split(|c: char| !c.is_ascii_digit())
            .take_while(|p| !p.is_empty())
            .filter_map(|p| p.parse().ok())
            .collect()
    };
    let (v, l) = (numbers(version), numbers(least));
    !v.is_empty() && v.iter().take(l.len()).cmp(l.iter()) != std::cmp::Ordering::Less
}

/// The glyph of `set` that the probe printed, and where it goes: one cell.
fn probe(set: Symbols) -> Option<usize> {
    match set {
        Symbols::Sextant => Some(0),
        Symbols::Octant => Some(1),
        Symbols::Half | Symbols::Quad => None,
    }
}

/// The symbols to draw with: what `arg` asks, given the terminal's name
/// (`terminal`, if it said) and how many cells the probe's sextant and
/// octant moved the cursor (`advances`, where it answered); and what to
/// tell the user when the picture may be wrong.
pub(crate) fn choose(
    arg: SymbolsArg,
    terminal: Option<&str>,
    advances: &[u16],
) -> (Symbols, Option<String>) {
    // A glyph that moves the cursor by other than one cell would shift
    // every cell after it: such a set is never used.
    let fits = |set: Symbols| {
        probe(set)
            .and_then(|i| advances.get(i))
            .is_none_or(|&a| a == 1)
    };
    let densest_fitting = |most: Symbols| {
        [
            Symbols::Octant,
            Symbols::Sextant,
            Symbols::Quad,
            Symbols::Half,
        ]
        .into_iter()
        .find(|&s| s.grid().1 <= most.grid().1 && s.grid().0 <= most.grid().0 && fits(s))
        .unwrap_or(Symbols::Half)
    };
    let drawn = terminal.and_then(drawn);
    let asked = match arg {
        SymbolsArg::Auto => return (densest_fitting(drawn.unwrap_or(Symbols::Half)), None),
        SymbolsArg::Set(set) => set,
    };
    if !fits(asked) {
        let used = densest_fitting(asked);
        let cells = probe(asked)
            .and_then(|i| advances.get(i))
            .copied()
            .unwrap_or(0);
        let hint = format!(
            "{} move the cursor {cells} cells here, not 1: {} instead",
            asked.name(),
            used.name()
        );
        return (used, Some(hint));
    }
    // Half blocks and quadrants are in nearly every font.
    if probe(asked).is_none() || drawn.is_some_and(|d| d.grid().1 >= asked.grid().1) {
        return (asked, None);
    }
    let who = match (terminal, drawn) {
        (Some(t), Some(_)) => format!("{} does not draw them itself", t.trim()),
        _ => "the terminal is not one known to draw them itself".to_string(),
    };
    let hint = format!(
        "{} show as boxes or blanks unless the font has them ({who}); \
         --symbols auto picks what it draws",
        asked.name()
    );
    (asked, Some(hint))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::term::detect::tests::answers;

    fn pick(arg: SymbolsArg, bytes: &[u8]) -> (Symbols, Option<String>) {
        let a = answers(bytes);
        choose(arg, a.version.as_deref(), &a.advances)
    }

    const AUTO: SymbolsArg = SymbolsArg::Auto;
    const OCTANT: SymbolsArg = SymbolsArg::Set(Symbols::Octant);
    const SEXTANT: SymbolsArg = SymbolsArg::Set(Symbols::Sextant);

    #[test]
    fn auto_picks_only_what_the_terminal_is_known_to_draw() {
        // kitty 0.40 draws octants; 0.26 sextants; 0.19.0 had them wrong.
        let kitty = |v: &str| format!("\x1bP>|kitty({v})\x1b\\\x1b[1;2R\x1b[1;2R\x1b[?62;22c");
        assert_eq!(
            pick(AUTO, kitty("0.40.1").as_bytes()),
            (Symbols::Octant, None)
        );
        assert_eq!(pick(AUTO, kitty("0.26.5").as_bytes()).0, Symbols::Sextant);
        assert_eq!(pick(AUTO, kitty("0.19.0").as_bytes()).0, Symbols::Quad);
        // WezTerm's releases: sextants; one from before them: quadrants.
        let wez = b"\x1bP>|WezTerm 20240203-110809-5046fc22\x1b\\\x1b[1;2R\x1b[1;2R\x1b[?65;4c";
        assert_eq!(pick(AUTO, wez).0, Symbols::Sextant);
        let old = b"\x1bP>|WezTerm 20210502-154244-3f7122cb\x1b\\\x1b[?65c";
        assert_eq!(pick(AUTO, old).0, Symbols::Quad);
        // xterm, a terminal that names itself oddly, one that says nothing,
        // and no answer at all: half blocks, without a word.
        for bytes in [
            &b"\x1bP>|XTerm(379)\x1b\\\x1b[1;2R\x1b[1;2R\x1b[?63;4c"[..],
            b"\x1bP>|(\x1b\\\x1bP>|kitty\x1b\\\x1b[?62c",
            b"\x1b[1;2R\x1b[1;2R\x1b[?62c",
            b"",
        ] {
            assert_eq!(pick(AUTO, bytes), (Symbols::Half, None));
        }
    }

    #[test]
    fn a_glyph_that_moves_the_cursor_wrongly_is_never_used() {
        // A kitty whose octant took two cells (a width table of its own),
        // and one whose sextant took none: the densest that fits.
        let b = b"\x1bP>|kitty(0.41.0)\x1b\\\x1b[1;2R\x1b[1;3R\x1b[?62c";
        assert_eq!(pick(AUTO, b), (Symbols::Sextant, None));
        let b = b"\x1bP>|kitty(0.41.0)\x1b\\\x1b[1;1R\x1b[1;3R\x1b[?62c";
        assert_eq!(pick(AUTO, b), (Symbols::Quad, None));
        // Asked for by name: the fallback is said, with the cells.
        let (set, hint) = pick(OCTANT, b"\x1b[1;2R\x1b[1;3R\x1b[?62c");
        assert_eq!(set, Symbols::Sextant);
        let hint = hint.unwrap();
        assert!(hint.contains("octants move the cursor 2 cells"), "{hint}");
        assert!(hint.contains("sextants instead"), "{hint}");
        // tmux without a width for it: the cursor stays.
        let (set, hint) = pick(SEXTANT, b"\x1b[5;1R\x1b[5;1R\x1b[?62c");
        assert_eq!(set, Symbols::Quad);
        assert!(hint.unwrap().contains("0 cells"));
    }

    #[test]
    fn sets_asked_by_name_are_kept_and_the_risk_is_said() {
        // Where nothing is known: kept, with how to switch.
        let (set, hint) = pick(
            OCTANT,
            b"\x1bP>|XTerm(379)\x1b\\\x1b[1;2R\x1b[1;2R\x1b[?63c",
        );
        assert_eq!(set, Symbols::Octant);
        let hint = hint.unwrap();
        assert!(hint.contains("octants show as boxes"), "{hint}");
        assert!(hint.contains("not one known"), "{hint}");
        assert!(hint.contains("--symbols auto"), "{hint}");
        // A kitty too old for octants is named.
        let (_, hint) = pick(OCTANT, b"\x1bP>|kitty(0.26.5)\x1b\\\x1b[?62c");
        assert!(hint.unwrap().contains("kitty(0.26.5) does not draw them"));
        // What the terminal draws, and half blocks and quadrants anywhere:
        // nothing to say.
        assert_eq!(
            pick(SEXTANT, b"\x1bP>|kitty(0.26.5)\x1b\\\x1b[?62c"),
            (Symbols::Sextant, None)
        );
        for set in [Symbols::Half, Symbols::Quad] {
            assert_eq!(pick(SymbolsArg::Set(set), b""), (set, None));
        }
    }

    #[test]
    fn versions_compare_number_by_number() {
        assert!(at_least("0.40.0", "0.40.0") && at_least("0.41", "0.40.0"));
        assert!(!at_least("0.39.9", "0.40.0") && !at_least("0.4.0", "0.40.0"));
        assert!(at_least("20240203-110809-5046fc22", "20210814"));
        assert!(!at_least("", "0") && !at_least("nightly", "0"));
        assert_eq!(split(" kitty(0.40.1) "), ("kitty", "0.40.1"));
        assert_eq!(split("WezTerm 2024"), ("WezTerm", "2024"));
    }
}
