//! Text where it must fit. Every title and line the widgets draw is
//! measured here against its room, so that a test can draw every panel
//! and popup at every size and fail on a cut word ([`take_cut`]).

use ratatui::layout::Rect;
use ratatui::text::Line;

#[cfg(test)]
thread_local! {
    static CUT: std::cell::RefCell<Vec<String>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The display width of `s` in terminal columns.
pub(crate) fn width(s: &str) -> usize {
    Line::raw(s).width()
}

/// `parts` joined by `sep`, leaving out those of the highest rank (then
/// the next) until the line fits `room`; rank 0 is always kept.
pub(crate) fn joined(parts: &[(String, u8)], sep: &str, room: usize) -> String {
    let join = |most: u8| {
        parts
            .iter()
            .filter(|(_, r)| *r <= most)
            .map(|(p, _)| p.as_str())
            .collect::<Vec<_>>()
            .join(sep)
    };
    let top = parts.iter().map(|(_, r)| *r).max().unwrap_or(0);
    (0..=top)
        .rev()
        .map(join)
        .find(|l| width(l) <= room)
        .unwrap_or_else(|| join(0))
}

/// Notes (in tests) `line` drawn `room` columns wide, at `place`.
pub(crate) fn check(place: &str, line: &Line, room: u16) {
    if line.width() > room as usize {
        cut(format!("{place} ({room} wide): {line}"));
    }
}

/// Notes (in tests) `lines` drawn in `area`, at `place`: each must fit its
/// width, and all of them its height.
pub(crate) fn check_all(place: &str, lines: &[Line], area: Rect) {
    for l in lines {
        check(place, l, area.width);
    }
    if lines.len() > area.height as usize {
        let last = &lines[area.height as usize..];
        cut(format!(
            "{place} ({} rows): {} more line(s), from {:?}",
            area.height,
            last.len(),
            last[0].to_string()
        ));
    }
}

#[cfg(test)]
fn cut(what: String) {
    CUT.with(|c| c.borrow_mut().push(what));
}

#[cfg(not(test))]
fn cut(_: String) {}

/// What was cut since the last call (tests only).
#[cfg(test)]
pub(crate) fn take_cut() -> Vec<String> {
    CUT.with(|c| std::mem::take(&mut *c.borrow_mut()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_of_the_highest_rank_go_first() {
        let parts = [
            ("scene".to_string(), 0),
            ("47x30 px".to_string(), 1),
            ("half blocks".to_string(), 2),
            ("SELECT".to_string(), 0),
        ];
        assert_eq!(
            joined(&parts, " · ", 80),
            "scene · 47x30 px · half blocks · SELECT"
        );
        assert_eq!(joined(&parts, " · ", 30), "scene · 47x30 px · SELECT");
        assert_eq!(joined(&parts, " · ", 20), "scene · SELECT");
        assert_eq!(joined(&parts, " · ", 5), "scene · SELECT");
    }
}
