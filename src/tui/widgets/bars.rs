//! The status line, the key-hint bar, popups and the too-small message.

use ratatui::layout::{Alignment, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Wrap};
use ratatui::Frame;

use crate::tui::app::App;
use crate::tui::keys;
use crate::tui::layout::{MIN_SIZE, POPUP_HINT};
use crate::tui::popup::{wrap, Popup};

use super::fit;

/// How a message too long for two rows ends.
const MORE: &str = " … (W shows it whole)";

/// The status line; a message longer than the line wraps onto the hint
/// bar's row below while it lasts (true then).
pub(crate) fn status(f: &mut Frame, area: Rect, hints: Rect, app: &App) -> bool {
    let text = match app.jobs.export_progress() {
        Some(p) => format!("{p} · {}", app.status_line()),
        None => app.status_line(),
    };
    let width = area.width as usize;
    let mut rows = wrap(&text, width, 0);
    // Two rows at most: the rest is in the popup `W` opens.
    if rows.len() > 2 {
        rows.truncate(2);
        let mut last: Vec<&str> = rows[1].split(' ').collect();
        while !last.is_empty() && fit::width(&last.join(" ")) + fit::width(MORE) > width {
            last.pop();
        }
        rows[1] = last.join(" ") + MORE;
    }
    let rows: Vec<Line> = rows.into_iter().map(Line::raw).collect();
    let wraps = rows.len() > 1;
    let area = if wraps { area.union(hints) } else { area };
    fit::check_all("status line", &rows, area);
    f.render_widget(
        Paragraph::new(rows).style(Style::new().bg(Color::DarkGray).fg(Color::White)),
        area,
    );
    wraps
}

/// As many whole hints as fit, in the key table's order (help and quit
/// first); `?` lists the rest.
pub(crate) fn hints(f: &mut Frame, area: Rect, app: &App) {
    let key = Style::new().fg(Color::Black).bg(Color::Gray);
    let mut left = area.width as usize;
    let mut spans = Vec::new();
    for (k, h) in keys::hints(app.mode()) {
        let text = format!(" {h} ");
        let need = k.chars().count() + text.chars().count();
        if need > left {
            break;
        }
        left -= need;
        spans.push(Span::styled(k, key));
        spans.push(Span::raw(text));
    }
    f.render_widget(Paragraph::new(Line::from(spans)), area);
}

pub(crate) fn popup(f: &mut Frame, r: Rect, p: &Popup) {
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let text: Vec<Line> = p
        .header
        .iter()
        .map(|l| Line::styled(l.as_str(), bold))
        .chain(
            p.lines
                .iter()
                .skip(p.scroll)
                .map(|l| Line::from(l.as_str())),
        )
        .collect();
    let shown = if p.lines.len() > p.visible {
        format!(
            " lines {}-{} of {} ",
            p.scroll + 1,
            (p.scroll + p.visible).min(p.lines.len()),
            p.lines.len()
        )
    } else {
        String::new()
    };
    let inner = Block::bordered().inner(r);
    fit::check(
        "popup title",
        &Line::raw(format!(" {} ", p.title)),
        inner.width,
    );
    fit::check(
        "popup foot",
        &Line::raw(format!("{shown}{POPUP_HINT}")),
        inner.width,
    );
    fit::check_all(
        "popup",
        &text[..text.len().min(inner.height as usize)],
        inner,
    );
    f.render_widget(Clear, r);
    f.render_widget(
        Paragraph::new(text).block(
            Block::bordered()
                .title(format!(" {} ", p.title))
                .title_style(bold)
                .title_bottom(Line::from(POPUP_HINT).right_aligned())
                .title_bottom(Line::from(shown).left_aligned()),
        ),
        r,
    );
}

pub(crate) fn too_small(f: &mut Frame, area: Rect) {
    let msg = format!(
        "terminal too small (need {}x{}, have {}x{})",
        MIN_SIZE.0, MIN_SIZE.1, area.width, area.height
    );
    let y = area.height / 2;
    f.render_widget(
        Paragraph::new(msg)
            .alignment(Alignment::Center)
            .wrap(Wrap { trim: true }),
        Rect::new(area.x, area.y + y, area.width, area.height - y),
    );
}
