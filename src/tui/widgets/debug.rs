//! The debug pane: the selected pixel's ray tree, coloured by line kind,
//! with a cursor line for folding, long lines wrapped, scrolled to keep the
//! cursor visible.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use super::fit;
use crate::inspect::LineKind;
use crate::tui::app::App;
use crate::tui::inspector::wrap;

fn style(k: LineKind) -> Style {
    match k {
        LineKind::Header => Style::new().add_modifier(Modifier::BOLD),
        LineKind::Ray => Style::new().fg(Color::Cyan).add_modifier(Modifier::BOLD),
        LineKind::Detail => Style::new().fg(Color::Gray),
        LineKind::Light => Style::new().fg(Color::Yellow),
        LineKind::Occluded => Style::new().fg(Color::Red),
        LineKind::Visible => Style::new().fg(Color::Green),
        LineKind::Fold => Style::new().fg(Color::Magenta),
        LineKind::Result => Style::new().fg(Color::White).add_modifier(Modifier::BOLD),
    }
}

pub(crate) fn draw(f: &mut Frame, area: Rect, app: &App) {
    let ins = &app.inspector;
    let lines = ins.lines();
    let title = match ins.selected {
        Some(s) => format!(
            " Ray tree: pixel ({}, {}) sample {} · line {}/{} ",
            s.x,
            s.y,
            s.sample,
            (ins.cursor + 1).min(lines.len()),
            lines.len()
        ),
        None => " Ray tree ".into(),
    };
    let block = Block::new()
        .borders(Borders::TOP)
        .title(title.clone())
        .title_style(Style::new().add_modifier(Modifier::BOLD));
    fit::check("ray tree title", &Line::raw(&title), area.width);
    let inner = block.inner(area);
    f.render_widget(block, area);
    if lines.is_empty() {
        f.render_widget(
            Paragraph::new("select a pixel (v, then hjkl or arrows; or click it) to see its rays")
                .style(Style::new().fg(Color::DarkGray))
                .wrap(ratatui::widgets::Wrap { trim: true }),
            inner,
        );
        return;
    }
    let text: Vec<Line> = lines
        .iter()
        .enumerate()
        .skip(ins.top)
        .flat_map(|(i, l)| {
            let mut s = style(l.kind);
            if i == ins.cursor {
                s = s.add_modifier(Modifier::REVERSED);
            }
            wrap(l, inner.width as usize)
                .into_iter()
                .map(move |row| Line::styled(row, s))
        })
        .take(inner.height as usize)
        .collect();
    fit::check_all("ray tree", &text, inner);
    f.render_widget(Paragraph::new(text), inner);
}
