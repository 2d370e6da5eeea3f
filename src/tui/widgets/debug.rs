//! The debug pane: the selected pixel's ray tree, coloured by line kind,
//! with a cursor line for folding, scrolled to keep the cursor visible.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use crate::inspect::LineKind;
use crate::tui::app::App;

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

pub fn draw(f: &mut Frame, area: Rect, app: &mut App) {
    app.debug_area = area;
    let lines = app.debug_lines();
    let title = match app.selected {
        Some(s) => format!(
            " Ray tree: pixel ({}, {}) sample {} · line {}/{} ",
            s.x,
            s.y,
            s.sample,
            (app.debug_cursor + 1).min(lines.len()),
            lines.len()
        ),
        None => " Ray tree ".into(),
    };
    let block = Block::new()
        .borders(Borders::TOP)
        .title(title)
        .title_style(Style::new().add_modifier(Modifier::BOLD));
    let inner = block.inner(area);
    f.render_widget(block, area);
    let height = inner.height.max(1) as usize;
    app.debug_height = height;
    if lines.is_empty() {
        f.render_widget(
            Paragraph::new("select a pixel (v, then hjkl or arrows; or click it) to see its rays")
                .style(Style::new().fg(Color::DarkGray)),
            inner,
        );
        return;
    }
    app.debug_cursor = app.debug_cursor.min(lines.len() - 1);
    if app.debug_cursor < app.debug_top {
        app.debug_top = app.debug_cursor;
    } else if app.debug_cursor >= app.debug_top + height {
        app.debug_top = app.debug_cursor + 1 - height;
    }
    let text: Vec<Line> = lines
        .iter()
        .enumerate()
        .skip(app.debug_top)
        .take(height)
        .map(|(i, l)| {
            let mut s = style(l.kind);
            if i == app.debug_cursor {
                s = s.add_modifier(Modifier::REVERSED);
            }
            Line::styled(format!("{}{}", "  ".repeat(l.depth), l.text), s)
        })
        .collect();
    f.render_widget(Paragraph::new(text), inner);
}
