//! The status line, the key-hint bar, popups and the too-small message.

use ratatui::layout::{Alignment, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Wrap};
use ratatui::Frame;

use crate::tui::app::App;
use crate::tui::keys;
use crate::tui::layout::MIN_SIZE;
use crate::tui::popup::Popup;

pub fn status(f: &mut Frame, area: Rect, app: &App) {
    let text = match app.jobs.export_progress() {
        Some(p) => format!("{p} · {}", app.status),
        None => app.status.clone(),
    };
    f.render_widget(
        Paragraph::new(text).style(Style::new().bg(Color::DarkGray).fg(Color::White)),
        area,
    );
}

pub fn hints(f: &mut Frame, area: Rect, app: &App) {
    let key = Style::new().fg(Color::Black).bg(Color::Gray);
    let spans: Vec<Span> = keys::hints(app.mode())
        .into_iter()
        .flat_map(|(k, h)| [Span::styled(k, key), Span::raw(format!(" {h} "))])
        .collect();
    f.render_widget(Paragraph::new(Line::from(spans)), area);
}

pub fn popup(f: &mut Frame, r: Rect, p: &Popup) {
    let text: Vec<Line> = p
        .lines
        .iter()
        .skip(p.scroll)
        .map(|l| Line::from(l.as_str()))
        .collect();
    f.render_widget(Clear, r);
    f.render_widget(
        Paragraph::new(text).block(
            Block::bordered()
                .title(format!(" {} ", p.title))
                .title_style(Style::new().add_modifier(Modifier::BOLD)),
        ),
        r,
    );
}

pub fn too_small(f: &mut Frame, area: Rect) {
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
