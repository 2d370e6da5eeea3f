//! A scrollable text window over the layout: the help, or a report table.

use super::keys;

pub struct Popup {
    pub title: String,
    pub lines: Vec<String>,
    /// First line shown.
    pub scroll: usize,
    /// Lines that fit, set from the layout.
    pub visible: usize,
}

impl Popup {
    pub fn new(title: String, lines: Vec<String>) -> Self {
        Self {
            title,
            lines,
            scroll: 0,
            visible: 1,
        }
    }

    /// Scrolls by `n` lines, keeping the last page in view.
    pub fn scroll_by(&mut self, n: i64) {
        self.scroll = (self.scroll as i64 + n).max(0) as usize;
        self.clamp();
    }

    pub fn set_visible(&mut self, visible: usize) {
        self.visible = visible.max(1);
        self.clamp();
    }

    fn clamp(&mut self) {
        self.scroll = self
            .scroll
            .min(self.lines.len().saturating_sub(self.visible));
    }
}

/// The help, generated from the key table.
pub fn help() -> Popup {
    let w = keys::ROWS
        .iter()
        .map(|r| keys::keys_label(r).chars().count())
        .max()
        .unwrap_or(0);
    let mut lines: Vec<String> = keys::ROWS
        .iter()
        .map(|r| format!("{:w$}  {}", keys::keys_label(r), r.help))
        .collect();
    lines.push(String::new());
    lines.push("mouse: click a pixel to inspect it; the wheel scrolls the debug pane".into());
    Popup::new("keys (↑↓ scroll, Esc closes)".into(), lines)
}
