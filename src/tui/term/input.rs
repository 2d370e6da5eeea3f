//! What the terminal sends: keys, mouse reports and the replies to our
//! queries (cursor position for output pacing, device attributes, cell
//! size, kitty graphics, capability strings). Keys come as crossterm
//! events so the key table stays the same; the replies, which crossterm
//! keeps to itself, come to us.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
};

/// A reply to one of our queries.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Reply {
    /// `CSI row ; col R`: the terminal has processed everything before our
    /// `CSI 6n`.
    CursorPosition(u16, u16),
    /// `CSI ? attrs c` (DA1); 4 among them means sixel.
    DeviceAttributes(Vec<u16>),
    /// `CSI 6 ; height ; width t`: a cell's size in pixels.
    CellSize(u16, u16),
    /// `CSI 4 ; height ; width t`: the text area's size in pixels.
    WindowPixels(u16, u16),
    /// `CSI ? 1 ; 0 ; n S` (XTSMGRAPHICS): sixel colour registers.
    ColourRegisters(u16),
    /// `CSI ? 2 ; 0 ; width ; height S` (XTSMGRAPHICS): the largest sixel
    /// image in pixels.
    SixelGeometry(u16, u16),
    /// `APC G ... ST`: a kitty graphics reply, without the `G`.
    Kitty(String),
    /// `DCS ... ST`: capability (XTGETTCAP) and setting (DECRQSS) replies.
    Dcs(String),
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Input {
    Event(Event),
    Reply(Reply),
}

/// A lone ESC is the Esc key when nothing follows it this soon.
const ESC_WAIT: Duration = Duration::from_millis(40);
/// An unfinished sequence is dropped after this long.
const SEQUENCE_WAIT: Duration = Duration::from_millis(1000);

/// Splits the terminal's bytes into [`Input`]s.
#[derive(Default)]
pub(crate) struct Parser {
    buf: Vec<u8>,
}

enum Step {
    /// `n` bytes made this input (or nothing useful when `None`).
    Done(usize, Option<Input>),
    /// More bytes are needed.
    More,
}

impl Parser {
    /// Adds bytes and returns every input they complete.
    pub(crate) fn feed(&mut self, bytes: &[u8]) -> Vec<Input> {
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        while let Step::Done(n, input) = parse(&self.buf) {
            self.buf.drain(..n);
            out.extend(input);
        }
        out
    }

    /// Whether an unfinished sequence is waiting.
    pub(crate) fn pending(&self) -> bool {
        !self.buf.is_empty()
    }

    /// Gives up on what is waiting: a lone ESC is the Esc key, anything
    /// else unfinished is dropped.
    pub(crate) fn flush(&mut self) -> Option<Input> {
        let lone_esc = self.buf == [0x1b];
        self.buf.clear();
        lone_esc.then(|| key(KeyCode::Esc, KeyModifiers::NONE))
    }
}

fn key(code: KeyCode, modifiers: KeyModifiers) -> Input {
    Input::Event(Event::Key(KeyEvent::new(code, modifiers)))
}

/// Parses the first input of `b`.
fn parse(b: &[u8]) -> Step {
    let Some(&first) = b.first() else {
        return Step::More;
    };
    let none = KeyModifiers::NONE;
    match first {
        0x1b => parse_escape(b),
        b'\r' | b'\n' => Step::Done(1, Some(key(KeyCode::Enter, none))),
        b'\t' => Step::Done(1, Some(key(KeyCode::Tab, none))),
        0x7f | 0x08 => Step::Done(1, Some(key(KeyCode::Backspace, none))),
        0x00 => Step::Done(1, Some(key(KeyCode::Char(' '), KeyModifiers::CONTROL))),
        0x01..=0x1a => Step::Done(
            1,
            Some(key(
                KeyCode::Char((first + 0x60) as char),
                KeyModifiers::CONTROL,
            )),
        ),
        0x1c..=0x1f => Step::Done(1, None),
        _ => parse_char(b).map_or(Step::More, |(c, n)| {
            Step::Done(n, c.map(|c| key(KeyCode::Char(c), none)))
        }),
    }
}

/// One UTF-8 character: `None` while incomplete; an invalid byte is skipped.
fn parse_char(b: &[u8]) -> Option<(Option<char>, usize)> {
    let len = match b[0] {
        0x00..=0x7f => 1,
        0xc0..=0xdf => 2,
        0xe0..=0xef => 3,
        0xf0..=0xf7 => 4,
        _ => return Some((None, 1)),
    };
    if b.len() < len {
        return None;
    }
    match std::str::from_utf8(&b[..len]) {
        Ok(s) => Some((s.chars().next(), len)),
        Err(_) => Some((None, 1)),
    }
}

fn parse_escape(b: &[u8]) -> Step {
    let Some(&second) = b.get(1) else {
        return Step::More;
    };
    match second {
        b'[' => parse_csi(b),
        b'O' => match b.get(2) {
            None => Step::More,
            Some(&c) => Step::Done(3, cursor_key(c, KeyModifiers::NONE)),
        },
        b'P' | b'_' | b']' => parse_string(b),
        0x1b => Step::Done(1, Some(key(KeyCode::Esc, KeyModifiers::NONE))),
        _ => match parse_char(&b[1..]) {
            None => Step::More,
            Some((c, n)) => Step::Done(1 + n, c.map(|c| key(KeyCode::Char(c), KeyModifiers::ALT))),
        },
    }
}

/// A string sequence (DCS, APC, OSC) up to its terminator, ST or BEL.
fn parse_string(b: &[u8]) -> Step {
    let body = &b[2..];
    let end = body.iter().enumerate().find_map(|(i, &c)| match c {
        0x07 => Some((i, 1)),
        0x1b if body.get(i + 1) == Some(&b'\\') => Some((i, 2)),
        _ => None,
    });
    let Some((i, term)) = end else {
        return Step::More;
    };
    let text = String::from_utf8_lossy(&body[..i]).into_owned();
    let reply = match b[1] {
        b'P' => Some(Reply::Dcs(text)),
        b'_' => text.strip_prefix('G').map(|t| Reply::Kitty(t.to_string())),
        _ => None,
    };
    Step::Done(2 + i + term, reply.map(Input::Reply))
}

fn cursor_key(c: u8, m: KeyModifiers) -> Option<Input> {
    let code = match c {
        b'A' => KeyCode::Up,
        b'B' => KeyCode::Down,
        b'C' => KeyCode::Right,
        b'D' => KeyCode::Left,
        b'H' => KeyCode::Home,
        b'F' => KeyCode::End,
        b'P' => KeyCode::F(1),
        b'Q' => KeyCode::F(2),
        b'S' => KeyCode::F(4),
        _ => return None,
    };
    Some(key(code, m))
}

/// xterm's modifier parameter: 1 + (shift 1, alt 2, ctrl 4).
fn modifiers(p: Option<u16>) -> KeyModifiers {
    let bits = p.unwrap_or(1).saturating_sub(1);
    let mut m = KeyModifiers::NONE;
    if bits & 1 != 0 {
        m |= KeyModifiers::SHIFT;
    }
    if bits & 2 != 0 {
        m |= KeyModifiers::ALT;
    }
    if bits & 4 != 0 {
        m |= KeyModifiers::CONTROL;
    }
    m
}

fn parse_csi(b: &[u8]) -> Step {
    // Parameters and intermediates, then a final byte.
    let Some(end) = b[2..].iter().position(|c| (0x40..=0x7e).contains(c)) else {
        return if b.len() > 64 {
            Step::Done(b.len(), None)
        } else {
            Step::More
        };
    };
    let n = 2 + end + 1;
    let final_byte = b[n - 1];
    let body = &b[2..n - 1];
    let (private, params) = match body.first() {
        Some(&p @ (b'<' | b'?' | b'>' | b'=')) => (Some(p), &body[1..]),
        _ => (None, body),
    };
    let nums: Vec<Option<u16>> = std::str::from_utf8(params)
        .unwrap_or("")
        .split(';')
        .map(|s| s.parse().ok())
        .collect();
    let num = |i: usize| nums.get(i).copied().flatten();
    let input = match (private, final_byte) {
        (Some(b'<'), b'M' | b'm') => mouse(num(0), num(1), num(2), final_byte == b'M'),
        (Some(b'?'), b'S') => match (num(0), num(1), num(2)) {
            (Some(1), Some(0), Some(n)) => Some(Input::Reply(Reply::ColourRegisters(n))),
            (Some(2), Some(0), Some(w)) => num(3).map(|h| Input::Reply(Reply::SixelGeometry(w, h))),
            _ => None,
        },
        (Some(b'?'), b'c') => Some(Input::Reply(Reply::DeviceAttributes(
            nums.iter().flatten().copied().collect(),
        ))),
        (None, b'R') => match (num(0), num(1)) {
            (Some(r), Some(c)) => Some(Input::Reply(Reply::CursorPosition(r, c))),
            _ => None,
        },
        (None, b't') => match (num(0), num(1), num(2)) {
            (Some(6), Some(h), Some(w)) => Some(Input::Reply(Reply::CellSize(h, w))),
            (Some(4), Some(h), Some(w)) => Some(Input::Reply(Reply::WindowPixels(h, w))),
            _ => None,
        },
        (None, b'~') => {
            let code = match num(0) {
                Some(5) => Some(KeyCode::PageUp),
                Some(6) => Some(KeyCode::PageDown),
                Some(3) => Some(KeyCode::Delete),
                Some(2) => Some(KeyCode::Insert),
                Some(1 | 7) => Some(KeyCode::Home),
                Some(4 | 8) => Some(KeyCode::End),
                _ => None,
            };
            code.map(|c| key(c, modifiers(num(1))))
        }
        (None, b'Z') => Some(key(KeyCode::BackTab, KeyModifiers::SHIFT)),
        (None, c) => cursor_key(c, modifiers(num(1))),
        _ => None,
    };
    Step::Done(n, input)
}

/// An SGR mouse report (`CSI < b ; x ; y M/m`).
fn mouse(b: Option<u16>, x: Option<u16>, y: Option<u16>, press: bool) -> Option<Input> {
    let (b, x, y) = (b?, x?, y?);
    let mut modifiers = KeyModifiers::NONE;
    if b & 4 != 0 {
        modifiers |= KeyModifiers::SHIFT;
    }
    if b & 8 != 0 {
        modifiers |= KeyModifiers::ALT;
    }
    if b & 16 != 0 {
        modifiers |= KeyModifiers::CONTROL;
    }
    let button = match b & 3 {
        0 => MouseButton::Left,
        1 => MouseButton::Middle,
        _ => MouseButton::Right,
    };
    let kind = if b & 64 != 0 {
        match b & 3 {
            0 => MouseEventKind::ScrollUp,
            1 => MouseEventKind::ScrollDown,
            2 => MouseEventKind::ScrollLeft,
            _ => MouseEventKind::ScrollRight,
        }
    } else if b & 32 != 0 {
        MouseEventKind::Drag(button)
    } else if press {
        MouseEventKind::Down(button)
    } else {
        MouseEventKind::Up(button)
    };
    Some(Input::Event(Event::Mouse(MouseEvent {
        kind,
        column: x.saturating_sub(1),
        row: y.saturating_sub(1),
        modifiers,
    })))
}

/// The thread that reads the terminal and parses what it sends.
pub(crate) struct Reader {
    pub(crate) rx: Receiver<Input>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Reader {
    /// Reads file descriptor `fd` (the terminal, in raw mode) until dropped.
    pub(crate) fn spawn(fd: i32) -> Result<Reader> {
        let (tx, rx) = mpsc::channel();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("rayterm-input".into())
            .spawn(move || read_loop(fd, &tx, &flag))
            .context("cannot start the input thread")?;
        Ok(Reader {
            rx,
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for Reader {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn read_loop(fd: i32, tx: &Sender<Input>, stop: &AtomicBool) {
    let mut parser = Parser::default();
    let mut buf = [0u8; 4096];
    let mut since = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        // Short waits while a sequence is unfinished, to tell Esc apart.
        let wait = if parser.pending() {
            ESC_WAIT
        } else {
            Duration::from_millis(50)
        };
        let mut pfd = libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd for the duration of the call.
        let ready = unsafe { libc::poll(&mut pfd, 1, wait.as_millis() as i32) };
        if ready < 0 {
            if std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return;
        }
        if ready == 0 || pfd.revents & libc::POLLIN == 0 {
            if pfd.revents & (libc::POLLHUP | libc::POLLERR | libc::POLLNVAL) != 0 {
                return;
            }
            let waited = since.elapsed();
            if parser.pending() && (parser.buf == [0x1b] || waited >= SEQUENCE_WAIT) {
                if let Some(i) = parser.flush() {
                    if tx.send(i).is_err() {
                        return;
                    }
                }
            }
            continue;
        }
        // SAFETY: reads into a buffer we own, at most its length.
        let n = unsafe { libc::read(fd, buf.as_mut_ptr().cast(), buf.len()) };
        if n <= 0 {
            if n < 0 && std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return;
        }
        since = Instant::now();
        for input in parser.feed(&buf[..n as usize]) {
            if tx.send(input).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(bytes: &[u8]) -> Vec<Input> {
        Parser::default().feed(bytes)
    }

    #[test]
    fn keys_and_replies_are_told_apart() {
        let got = keys(b"q\x1b[A\x1b[12;40R\x1b[5~\x03\x1b[?62;4;22c\x1b[6;16;8t");
        assert_eq!(
            got,
            vec![
                key(KeyCode::Char('q'), KeyModifiers::NONE),
                key(KeyCode::Up, KeyModifiers::NONE),
                Input::Reply(Reply::CursorPosition(12, 40)),
                key(KeyCode::PageUp, KeyModifiers::NONE),
                key(KeyCode::Char('c'), KeyModifiers::CONTROL),
                Input::Reply(Reply::DeviceAttributes(vec![62, 4, 22])),
                Input::Reply(Reply::CellSize(16, 8)),
            ]
        );
        assert_eq!(
            keys(b"\x1b[?1;0;16S\x1b[?1;3;0S"),
            vec![Input::Reply(Reply::ColourRegisters(16))]
        );
        assert_eq!(
            keys(b"\x1b[?2;0;1000;800S\x1b[?2;0;1000S\x1b[?2;3;0S"),
            vec![Input::Reply(Reply::SixelGeometry(1000, 800))]
        );
        let got = keys(b"\x1b_Gi=31;OK\x1b\\\x1bP1+r524742=\x1b\\\x1b[<0;10;5M");
        assert_eq!(got[0], Input::Reply(Reply::Kitty("i=31;OK".into())));
        assert_eq!(got[1], Input::Reply(Reply::Dcs("1+r524742=".into())));
        let Input::Event(Event::Mouse(m)) = &got[2] else {
            panic!("{got:?}")
        };
        assert_eq!(
            (m.kind, m.column, m.row),
            (MouseEventKind::Down(MouseButton::Left), 9, 4)
        );
    }

    #[test]
    fn split_sequences_wait_and_a_lone_esc_is_the_key() {
        let mut p = Parser::default();
        assert!(p.feed(b"\x1b[1").is_empty());
        assert_eq!(
            p.feed(b"2;3R"),
            vec![Input::Reply(Reply::CursorPosition(12, 3))]
        );
        assert!(p.feed(b"\x1b").is_empty() && p.pending());
        assert_eq!(p.flush(), Some(key(KeyCode::Esc, KeyModifiers::NONE)));
        assert!(p.feed("é".as_bytes()[..1].as_ref()).is_empty());
        assert_eq!(
            p.feed(&"é".as_bytes()[1..]),
            vec![key(KeyCode::Char('é'), KeyModifiers::NONE)]
        );
    }
}
