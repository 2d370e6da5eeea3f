//! The overlays' legend beneath the view: its items packed into lines
//! (" · " between them), a long item wrapped; when the rows the layout
//! gives are too few, the last says how to see it whole.

use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::Line;
use ratatui::widgets::Paragraph;
use ratatui::Frame;

use super::fit;
use crate::tui::popup::wrap;

/// The last row when the legend does not fit.
const MORE: &str = "… O shows the whole legend";

/// `items` packed into rows of at most `width` columns.
pub(crate) fn rows(items: &[String], width: usize) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for item in items {
        let joined = out
            .last()
            .map(|l| format!("{l} · {item}"))
            .filter(|l| fit::width(l) <= width);
        match joined {
            Some(l) => *out.last_mut().unwrap() = l,
            None => out.extend(wrap(item, width, 2)),
        }
    }
    out
}

pub(crate) fn draw(f: &mut Frame, area: Rect, items: &[String]) {
    if area.height == 0 || items.is_empty() {
        return;
    }
    let mut rows = rows(items, area.width as usize);
    if rows.len() > area.height as usize {
        rows.truncate(area.height as usize - 1);
        rows.push(MORE.into());
    }
    let lines: Vec<Line> = rows.into_iter().map(Line::raw).collect();
    fit::check_all("legend", &lines, area);
    f.render_widget(
        Paragraph::new(lines).style(Style::new().fg(Color::Gray)),
        area,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_share_rows_and_long_ones_wrap() {
        let items = ["red hit", "blue miss", "a much longer item that wraps"].map(String::from);
        assert_eq!(
            rows(&items, 20),
            ["red hit · blue miss", "a much longer item", "  that wraps"]
        );
        assert!(rows(&items, 20).iter().all(|r| fit::width(r) <= 20));
    }
}
