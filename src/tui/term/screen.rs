//! A ratatui backend that keeps two pictures of the screen: what the app
//! wants shown and what has been written. [`Screen::pump`] writes the cells
//! that differ, a bounded number of bytes at a time, sweeping across the
//! screen so that every cell is brought up to date in turn; a new frame
//! drawn meanwhile replaces the cells not yet written, so nothing stale is
//! ever queued. Colours are written in the shortest form the mode allows:
//! SGR 30-37/90-97 and 40-47/100-107 for the 16 ANSI colours, `38;5` only
//! for the 256-colour palette, `38;2` for truecolor.

use std::io::{self, Write};

use ratatui::backend::{Backend, ClearType, WindowSize};
use ratatui::buffer::Cell;
use ratatui::layout::{Position, Rect, Size};
use ratatui::style::{Color, Modifier};
use unicode_width::UnicodeWidthStr;

/// The most of a terminal the TUI uses (from the top left): a window the
/// ioctl says is larger (up to 65535 x 65535 cells) would need gigabytes
/// of cells; this is an 8K display in a 6 x 12 px font.
pub(crate) const MAX_SIZE: Size = Size {
    width: 1280,
    height: 360,
};

pub(crate) struct Screen<W: Write> {
    out: W,
    /// A fixed size (tests, the benchmark), else the terminal's.
    fixed: Option<Size>,
    width: u16,
    height: u16,
    /// What the app drew, and what the terminal shows (`None`: unknown).
    wanted: Vec<Cell>,
    shown: Vec<Option<Cell>>,
    /// Where the next sweep starts, and how many cells were swept so far.
    sweep: usize,
    swept: u64,
    /// Control sequences (clears, cursor visibility) for the next write.
    control: Vec<u8>,
    cursor_visible: bool,
    cursor: Position,
    /// Bytes written since the start.
    written: u64,
    /// Rows where cells were written, and whether the screen was cleared,
    /// since last asked (images under them are gone).
    touched: Vec<bool>,
    cleared: bool,
}

impl<W: Write> Screen<W> {
    /// A screen on the terminal `out` writes to; its size is the
    /// terminal's, or `fixed`. The terminal is cleared by the first write.
    pub(crate) fn new(out: W, fixed: Option<Size>) -> io::Result<Screen<W>> {
        let mut s = Screen {
            out,
            fixed,
            width: 0,
            height: 0,
            wanted: Vec::new(),
            shown: Vec::new(),
            sweep: 0,
            swept: 0,
            control: Vec::new(),
            cursor_visible: true,
            cursor: Position::ORIGIN,
            written: 0,
            touched: Vec::new(),
            cleared: false,
        };
        s.clear_all()?;
        Ok(s)
    }

    /// Bytes written to the terminal so far.
    pub(crate) fn written(&self) -> u64 {
        self.written
    }

    /// Whether some cell differs from what the terminal shows.
    pub(crate) fn pending(&self) -> bool {
        !self.control.is_empty()
            || self
                .wanted
                .iter()
                .zip(&self.shown)
                .any(|(w, s)| s.as_ref() != Some(w))
    }

    #[cfg(test)]
    pub(crate) fn writer(&mut self) -> &mut W {
        &mut self.out
    }

    /// The text the app drew, row by row (for tests).
    #[cfg(test)]
    pub(crate) fn wanted_text(&self) -> String {
        self.wanted
            .chunks(self.width.max(1) as usize)
            .map(|row| row.iter().map(Cell::symbol).collect::<String>())
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// Whether any cell of row `y` within `area` shows something: text, or
    /// a background colour.
    pub(crate) fn row_has_text(&self, y: u16, area: Rect) -> bool {
        let w = self.width as usize;
        (area.x..area.x + area.width).any(|x| {
            self.wanted
                .get(y as usize * w + x as usize)
                .is_some_and(|c| c.symbol() != " " || c.bg != Color::Reset)
        })
    }

    /// The rows where cells were written since the last call, and whether
    /// the screen was cleared.
    pub(crate) fn take_touched(&mut self) -> (Vec<bool>, bool) {
        let rows = vec![false; self.touched.len()];
        (
            std::mem::replace(&mut self.touched, rows),
            std::mem::take(&mut self.cleared),
        )
    }

    /// Cells on the screen.
    pub(crate) fn cells(&self) -> usize {
        self.wanted.len()
    }

    /// Cells swept so far: every cell has been brought up to date since
    /// this was `k` once it reaches `k + cells()`.
    pub(crate) fn swept(&self) -> u64 {
        self.swept
    }

    /// Writes `bytes` (a request, a picture) straight to the terminal.
    pub(crate) fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.out.write_all(bytes)?;
        self.out.flush()?;
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// Writes the cells that differ, from where the last call stopped,
    /// until about `budget` bytes are written (at least one cell) or the
    /// screen is up to date. Returns the bytes written and whether the
    /// sweep went all the way round (the screen is up to date).
    pub(crate) fn pump(&mut self, budget: usize) -> io::Result<(usize, bool)> {
        let mut buf = std::mem::take(&mut self.control);
        let n = self.wanted.len();
        let mut pen = Pen::default();
        let mut done = true;
        let mut visited = 0;
        while visited < n {
            if buf.len() >= budget {
                done = false;
                break;
            }
            let i = self.sweep;
            let skip = self.write_cell(i, &mut buf, &mut pen);
            visited += 1 + skip;
            self.swept += 1 + skip as u64;
            self.sweep = (i + 1 + skip) % n.max(1);
        }
        if pen.used {
            buf.extend_from_slice(b"\x1b[0m");
        }
        if self.cursor_visible && !buf.is_empty() {
            cup(&mut buf, self.cursor.x, self.cursor.y);
        }
        if !buf.is_empty() {
            self.out.write_all(&buf)?;
            self.out.flush()?;
            self.written += buf.len() as u64;
        }
        Ok((buf.len(), done && !self.pending()))
    }

    /// Brings cell `i` up to date; returns how many following cells it
    /// covered (one for a double-width symbol).
    fn write_cell(&mut self, i: usize, buf: &mut Vec<u8>, pen: &mut Pen) -> usize {
        let w = self.width as usize;
        let cell = &self.wanted[i];
        if self.shown[i].as_ref() == Some(cell) {
            return 0;
        }
        // The picture's image is sent over it: writing a blank would erase
        // it there (and show the terminal's background until it comes).
        if is_hole(cell) {
            self.shown[i] = Some(cell.clone());
            return 0;
        }
        let width = cell.symbol().width();
        let covered = if width > 1 && (i % w) + 1 < w { 1 } else { 0 };
        if width > 0 {
            let (x, y) = ((i % w) as u16, (i / w) as u16);
            pen.move_to(buf, x, y);
            pen.style(buf, cell.fg, cell.bg, cell.modifier);
            buf.extend_from_slice(cell.symbol().as_bytes());
            pen.at = (x as usize + width < w && !unsure_width(cell.symbol()))
                .then(|| (x + width as u16, y));
        }
        if let Some(t) = self.touched.get_mut(i / w) {
            *t = true;
        }
        self.shown[i] = Some(cell.clone());
        if covered == 1 {
            self.shown[i + 1] = Some(self.wanted[i + 1].clone());
        }
        covered
    }

    /// Forgets the screen: everything blank and to be cleared.
    fn clear_all(&mut self) -> io::Result<()> {
        let size = self.size()?;
        self.width = size.width;
        self.height = size.height;
        let n = size.width as usize * size.height as usize;
        self.wanted = vec![Cell::default(); n];
        self.shown = vec![Some(Cell::default()); n];
        self.sweep = 0;
        self.touched = vec![false; size.height as usize];
        self.cleared = true;
        self.control.extend_from_slice(b"\x1b[0m\x1b[H\x1b[2J");
        Ok(())
    }
}

/// Makes `cell` a hole: a place the viewport's image shows through, which
/// the screen never writes. Blank cells are written, so that a popup over
/// a sixel picture hides it.
pub(crate) fn make_hole(cell: &mut Cell) {
    cell.reset();
    cell.modifier = Modifier::HIDDEN;
}

fn is_hole(cell: &Cell) -> bool {
    cell.modifier == Modifier::HIDDEN
        && cell.symbol() == " "
        && cell.fg == Color::Reset
        && cell.bg == Color::Reset
}

/// Whether the terminal may not know how wide `symbol` is: octants came
/// with Unicode 16 (2024), and a terminal whose tables are older may draw
/// nothing or two columns. The next cell is then placed explicitly, so
/// that the rest of the screen stays in place.
fn unsure_width(symbol: &str) -> bool {
    symbol
        .chars()
        .any(|c| ('\u{1CC00}'..='\u{1CEBF}').contains(&c))
}

/// The terminal's cursor and colours while a chunk is written.
#[derive(Default)]
struct Pen {
    /// Where the cursor is, when known.
    at: Option<(u16, u16)>,
    /// The colours and attributes set, once any is.
    style: Option<(Color, Color, Modifier)>,
    used: bool,
}

impl Pen {
    fn move_to(&mut self, buf: &mut Vec<u8>, x: u16, y: u16) {
        match self.at {
            Some((ax, ay)) if ay == y && ax == x => {}
            Some((ax, ay)) if ay == y && ax < x => {
                let n = x - ax;
                if n == 1 {
                    buf.extend_from_slice(b"\x1b[C");
                } else {
                    let _ = write!(buf, "\x1b[{n}C");
                }
            }
            _ => cup(buf, x, y),
        }
        self.at = Some((x, y));
    }

    fn style(&mut self, buf: &mut Vec<u8>, fg: Color, bg: Color, modifier: Modifier) {
        let mut params: Vec<u8> = Vec::with_capacity(24);
        let (old_fg, old_bg) = match self.style {
            Some((f, b, m)) if m == modifier => (Some(f), Some(b)),
            // A new set of attributes starts from a reset.
            _ => {
                params.push(b'0');
                for (flag, code) in ATTRIBUTES {
                    if modifier.contains(flag) {
                        let _ = write!(params, ";{code}");
                    }
                }
                (None, None)
            }
        };
        if old_fg != Some(fg) && !(old_fg.is_none() && fg == Color::Reset) {
            sep(&mut params);
            colour(&mut params, fg, false);
        }
        if old_bg != Some(bg) && !(old_bg.is_none() && bg == Color::Reset) {
            sep(&mut params);
            colour(&mut params, bg, true);
        }
        if !params.is_empty() {
            buf.extend_from_slice(b"\x1b[");
            buf.extend_from_slice(&params);
            buf.push(b'm');
        }
        self.style = Some((fg, bg, modifier));
        self.used = true;
    }
}

const ATTRIBUTES: [(Modifier, u8); 9] = [
    (Modifier::BOLD, 1),
    (Modifier::DIM, 2),
    (Modifier::ITALIC, 3),
    (Modifier::UNDERLINED, 4),
    (Modifier::SLOW_BLINK, 5),
    (Modifier::RAPID_BLINK, 6),
    (Modifier::REVERSED, 7),
    (Modifier::HIDDEN, 8),
    (Modifier::CROSSED_OUT, 9),
];

fn sep(params: &mut Vec<u8>) {
    if !params.is_empty() {
        params.push(b';');
    }
}

/// Cursor position, 0-based in, 1-based out, defaults left out.
fn cup(buf: &mut Vec<u8>, x: u16, y: u16) {
    let _ = match (x, y) {
        (0, 0) => write!(buf, "\x1b[H"),
        (0, y) => write!(buf, "\x1b[{}H", y + 1),
        (x, y) => write!(buf, "\x1b[{};{}H", y + 1, x + 1),
    };
}

/// The SGR parameters of a colour: the 16 ANSI colours as 30-37 and 90-97
/// (40-47 and 100-107 for the background), the palette as `38;5;N`, RGB as
/// `38;2;R;G;B`.
pub(crate) fn colour(params: &mut Vec<u8>, c: Color, background: bool) {
    let base = if background { 40 } else { 30 };
    let ext = if background { 48 } else { 38 };
    let ansi = |i: u8| {
        if i < 8 {
            base + i
        } else {
            base + 60 + i - 8
        }
    };
    let _ = match c {
        Color::Reset => write!(params, "{}", base + 9),
        Color::Black => write!(params, "{}", ansi(0)),
        Color::Red => write!(params, "{}", ansi(1)),
        Color::Green => write!(params, "{}", ansi(2)),
        Color::Yellow => write!(params, "{}", ansi(3)),
        Color::Blue => write!(params, "{}", ansi(4)),
        Color::Magenta => write!(params, "{}", ansi(5)),
        Color::Cyan => write!(params, "{}", ansi(6)),
        Color::Gray => write!(params, "{}", ansi(7)),
        Color::DarkGray => write!(params, "{}", ansi(8)),
        Color::LightRed => write!(params, "{}", ansi(9)),
        Color::LightGreen => write!(params, "{}", ansi(10)),
        Color::LightYellow => write!(params, "{}", ansi(11)),
        Color::LightBlue => write!(params, "{}", ansi(12)),
        Color::LightMagenta => write!(params, "{}", ansi(13)),
        Color::LightCyan => write!(params, "{}", ansi(14)),
        Color::White => write!(params, "{}", ansi(15)),
        Color::Indexed(i) => write!(params, "{ext};5;{i}"),
        Color::Rgb(r, g, b) => write!(params, "{ext};2;{r};{g};{b}"),
    };
}

impl<W: Write> Backend for Screen<W> {
    type Error = io::Error;

    fn draw<'a, I>(&mut self, content: I) -> io::Result<()>
    where
        I: Iterator<Item = (u16, u16, &'a Cell)>,
    {
        for (x, y, cell) in content {
            if x < self.width && y < self.height {
                self.wanted[y as usize * self.width as usize + x as usize] = cell.clone();
            }
        }
        Ok(())
    }

    fn hide_cursor(&mut self) -> io::Result<()> {
        if self.cursor_visible {
            self.control.extend_from_slice(b"\x1b[?25l");
            self.cursor_visible = false;
        }
        Ok(())
    }

    fn show_cursor(&mut self) -> io::Result<()> {
        if !self.cursor_visible {
            self.control.extend_from_slice(b"\x1b[?25h");
            self.cursor_visible = true;
        }
        Ok(())
    }

    fn get_cursor_position(&mut self) -> io::Result<Position> {
        Ok(self.cursor)
    }

    fn set_cursor_position<P: Into<Position>>(&mut self, position: P) -> io::Result<()> {
        self.cursor = position.into();
        Ok(())
    }

    fn clear(&mut self) -> io::Result<()> {
        self.clear_all()
    }

    fn clear_region(&mut self, clear_type: ClearType) -> io::Result<()> {
        match clear_type {
            ClearType::All => self.clear_all(),
            // Only the full screen is ever cleared; anything else is
            // redrawn in full.
            _ => {
                self.shown.iter_mut().for_each(|s| *s = None);
                Ok(())
            }
        }
    }

    fn size(&self) -> io::Result<Size> {
        match self.fixed {
            Some(s) => Ok(s),
            None => {
                let (width, height) = ratatui::crossterm::terminal::size()?;
                Ok(Size {
                    width: width.min(MAX_SIZE.width),
                    height: height.min(MAX_SIZE.height),
                })
            }
        }
    }

    fn window_size(&mut self) -> io::Result<WindowSize> {
        let size = self.size()?;
        Ok(WindowSize {
            columns_rows: size,
            pixels: Size::default(),
        })
    }

    /// Writes everything that differs: the event loop paces with
    /// [`Screen::pump`] instead where the link is slow.
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::style::Style;
    use ratatui::Terminal;

    fn screen(w: u16, h: u16) -> Terminal<Screen<Vec<u8>>> {
        Terminal::new(Screen::new(Vec::new(), Some(Size::new(w, h))).unwrap()).unwrap()
    }

    fn out(t: &mut Terminal<Screen<Vec<u8>>>) -> String {
        let s = t.backend_mut();
        s.pump(usize::MAX).unwrap();
        String::from_utf8(std::mem::take(s.writer())).unwrap()
    }

    #[test]
    fn holes_are_never_written_and_blanks_over_them_are() {
        let mut t = screen(6, 1);
        let holes = |t: &mut Terminal<Screen<Vec<u8>>>, popup: Option<&str>| {
            t.draw(|f| {
                let b = f.buffer_mut();
                for x in 0..6 {
                    make_hole(&mut b[(x, 0)]);
                }
                // A popup clears the cells under it first.
                if let Some(p) = popup {
                    for x in 1..1 + p.len() as u16 {
                        b[(x, 0)].reset();
                    }
                    b.set_string(1, 0, p, Style::new());
                }
            })
            .unwrap();
        };
        holes(&mut t, None);
        out(&mut t);
        // A popup's blanks erase the picture under them, its text too.
        holes(&mut t, Some("a  b"));
        assert_eq!(out(&mut t), "\x1b[1;2H\x1b[0ma  b\x1b[0m");
        // Closed: nothing is written (no blank flashes before the image
        // comes back), and the row holds no text.
        holes(&mut t, None);
        assert_eq!(out(&mut t), "");
        assert!(!t.backend().row_has_text(0, Rect::new(0, 0, 6, 1)));
    }

    #[test]
    fn ansi_colours_use_the_short_codes() {
        let mut t = screen(4, 1);
        t.draw(|f| {
            let b = f.buffer_mut();
            b.set_string(0, 0, "a", Style::new().fg(Color::Red).bg(Color::LightBlue));
            b.set_string(1, 0, "b", Style::new().fg(Color::White).bg(Color::Black));
            b.set_string(2, 0, "c", Style::new().fg(Color::Indexed(200)));
            b.set_string(3, 0, "d", Style::new().fg(Color::Rgb(1, 2, 3)));
        })
        .unwrap();
        let s = out(&mut t);
        assert!(s.starts_with("\x1b[0m\x1b[H\x1b[2J"), "{s:?}");
        assert!(s.contains("\x1b[0;31;104ma\x1b[97;40mb"), "{s:?}");
        assert!(s.contains("\x1b[38;5;200;49mc\x1b[38;2;1;2;3md"), "{s:?}");
    }

    #[test]
    fn only_changes_are_written_in_bounded_sweeps() {
        let mut t = screen(10, 3);
        let frame = |t: &mut Terminal<Screen<Vec<u8>>>, rows: [&str; 3]| {
            t.draw(|f| {
                for (y, r) in rows.iter().enumerate() {
                    f.buffer_mut().set_string(0, y as u16, r, Style::new());
                }
            })
            .unwrap();
        };
        frame(&mut t, ["0123456789", "", ""]);
        out(&mut t);
        // Nothing changed: nothing written.
        frame(&mut t, ["0123456789", "", ""]);
        assert_eq!(out(&mut t), "");
        // Two cells on one row: one move, a forward step, no clear.
        frame(&mut t, ["0123456789", "  X  Y", ""]);
        assert_eq!(out(&mut t), "\x1b[2;3H\x1b[0mX\x1b[2CY\x1b[0m");
        // After an octant the next cell is placed explicitly.
        frame(&mut t, ["0123456789", "  X  Y", "\u{1CD00}\u{1CD01}"]);
        assert_eq!(
            out(&mut t),
            "\x1b[3H\x1b[0m\u{1CD00}\x1b[3;2H\u{1CD01}\x1b[0m"
        );
        frame(&mut t, ["0123456789", "  X  Y", ""]);
        out(&mut t);
        // A small budget writes a few cells per call and resumes where it
        // stopped, until the sweep is complete; a frame drawn meanwhile
        // replaces what was not yet written.
        frame(&mut t, ["0123456789", "  X  Y", "ABCDEFGHIJ"]);
        let mut rounds = 0;
        loop {
            rounds += 1;
            if rounds == 2 {
                frame(&mut t, ["0123456789", "  X  Y", "abcdefghij"]);
            }
            let (n, done) = t.backend_mut().pump(8).unwrap();
            assert!(n <= 8 + 10, "{n}");
            if done {
                break;
            }
        }
        assert!(rounds > 2, "{rounds}");
        assert!(!t.backend().pending());
        let shown: String = t.backend().shown[20..30]
            .iter()
            .map(|c| c.as_ref().unwrap().symbol().to_string())
            .collect();
        assert_eq!(shown, "abcdefghij");
    }
}
