//! A scrollable text window over the layout: the help, or a report table.

use super::keys;

pub(crate) struct Popup {
    pub(crate) title: String,
    /// Lines that stay at the top while the rest scrolls (a table's
    /// header), as given and as shown.
    header_text: Vec<String>,
    pub(crate) header: Vec<String>,
    /// The text as given, and as shown (wrapped to the popup's width when
    /// `wrap_indent` is set; tables are cut instead, to keep their columns).
    text: Vec<String>,
    pub(crate) lines: Vec<String>,
    /// Continuation lines start this far in.
    pub(crate) wrap_indent: Option<usize>,
    /// A table whose last column starts here: it wraps under itself, or,
    /// too narrow for that, goes on lines of its own under its row.
    pub(crate) last_column: Option<usize>,
    /// First line shown.
    pub(crate) scroll: usize,
    /// Lines that fit, set from the layout.
    pub(crate) visible: usize,
}

impl Popup {
    pub(crate) fn new(title: String, lines: Vec<String>) -> Self {
        Self {
            title,
            header_text: Vec::new(),
            header: Vec::new(),
            text: lines.clone(),
            lines,
            wrap_indent: None,
            last_column: None,
            scroll: 0,
            visible: 1,
        }
    }

    /// Scrolls by `n` lines, keeping the last page in view.
    pub(crate) fn scroll_by(&mut self, n: i64) {
        self.scroll = (self.scroll as i64 + n).max(0) as usize;
        self.clamp();
    }

    /// Sets the rows inside the frame; the header takes its share.
    pub(crate) fn set_visible(&mut self, rows: usize) {
        self.visible = rows.saturating_sub(self.header.len()).max(1);
        self.clamp();
    }

    /// The first `n` lines become a header that does not scroll.
    pub(crate) fn with_header(mut self, n: usize) -> Self {
        let n = n.min(self.text.len());
        self.header_text = self.text.drain(..n).collect();
        self.header = self.header_text.clone();
        self.lines = self.text.clone();
        self
    }

    /// Wraps the text to `width` columns when it wraps at all.
    pub(crate) fn set_width(&mut self, width: usize) {
        if let Some(col) = self.last_column {
            let row = |l: &String| table_row(l, col, width);
            self.header = self.header_text.iter().flat_map(row).collect();
            self.lines = self.text.iter().flat_map(row).collect();
            self.clamp();
            return;
        }
        let Some(indent) = self.wrap_indent else {
            return;
        };
        self.lines = self
            .text
            .iter()
            .flat_map(|l| wrap(l, width.max(indent + 8), indent))
            .collect();
        self.clamp();
    }

    fn clamp(&mut self) {
        self.scroll = self
            .scroll
            .min(self.lines.len().saturating_sub(self.visible));
    }
}

/// The narrowest last column worth wrapping under itself.
const LAST_COLUMN_LEAST: usize = 30;

/// A table row `width` wide whose last column starts at `col`.
fn table_row(line: &str, col: usize, width: usize) -> Vec<String> {
    if width >= col + LAST_COLUMN_LEAST {
        return wrap(line, width, col);
    }
    let at = line.char_indices().nth(col).map_or(line.len(), |(i, _)| i);
    let (row, last) = line.split_at(at);
    let mut out = vec![row.trim_end().to_string()];
    if !last.trim().is_empty() {
        out.extend(wrap(&format!("    {}", last.trim()), width, 4));
    }
    out
}

/// `line` broken at spaces into lines of at most `width` characters, the
/// continuations indented by `indent`.
pub(crate) fn wrap(line: &str, width: usize, indent: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    // Splitting at single spaces keeps runs of spaces (the key column).
    for (i, word) in line.split(' ').enumerate() {
        let sep = if i == 0 { "" } else { " " };
        let len = cur.chars().count();
        if !word.is_empty() && len > indent && len + 1 + word.chars().count() > width {
            out.push(std::mem::replace(&mut cur, " ".repeat(indent)));
        } else {
            cur.push_str(sep);
        }
        cur.push_str(word);
    }
    out.push(cur);
    out
}

/// The help, generated from the key table.
pub(crate) fn help() -> Popup {
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
    let mut p = Popup::new("keys".into(), lines);
    p.wrap_indent = Some(w + 2);
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lines_wrap_under_their_text() {
        let lines = wrap("q Ctrl-C  quit the application now please", 22, 10);
        assert_eq!(
            lines,
            [
                "q Ctrl-C  quit the",
                "          application",
                "          now please"
            ]
        );
        assert!(lines.iter().all(|l| l.chars().count() <= 22));
        assert_eq!(wrap("short", 20, 4), ["short"]);
    }

    #[test]
    fn a_tables_last_column_wraps_under_itself_or_its_row() {
        let row = "case a   pass  the detail of this case, in several words";
        let wide = table_row(row, 14, 50);
        assert_eq!(
            wide[0],
            "case a   pass  the detail of this case, in several"
        );
        assert!(wide[1..].iter().all(|l| l.starts_with(&" ".repeat(14))));
        let narrow = table_row(row, 14, 30);
        assert_eq!(narrow[0], "case a   pass");
        assert!(narrow[1].starts_with("    the detail"));
        assert!(narrow.iter().all(|l| l.chars().count() <= 30));
    }
}
