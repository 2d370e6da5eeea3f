//! What the terminal can do, asked at startup: the kitty graphics protocol
//! (a query image, `a=q`), sixel (DA1 lists 4) and its colour registers
//! (XTSMGRAPHICS), a cell's size in pixels (`CSI 16t`, else the window
//! size ioctl), and 24-bit colour (XTGETTCAP `RGB`/`Tc`, and an RGB
//! background set and read back with DECRQSS, which terminals that keep
//! only 256 colours answer with a palette index), and for block symbols
//! the terminal's name and version (XTVERSION) and how far a sextant and
//! an octant move the cursor (see `glyphs`). DA1 goes last:
//! every terminal answers it, so its answer ends the wait, which is short
//! when nothing answers at all.

use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

use crate::tui::graphics::{passthrough, GraphicsArg, PixelMode, Protocol};

use super::input::{Input, Reader, Reply};

/// The longest wait for the answers.
pub(crate) const WAIT: Duration = Duration::from_millis(1000);
/// Inside tmux, answers passed through from the outer terminal may come
/// after tmux's own answer to DA1.
const TMUX_GRACE: Duration = Duration::from_millis(150);

/// A cell's width and height in pixels believed from an answer.
const CELL_PX: std::ops::RangeInclusive<u32> = 2..=256;

const KITTY_QUERY: &[u8] = b"\x1b_Gi=31,s=1,v=1,a=q,t=d,f=24;AAAA\x1b\\";
const CELL_SIZE: &[u8] = b"\x1b[16t";
const WINDOW_PIXELS: &[u8] = b"\x1b[14t";
const REGISTERS: &[u8] = b"\x1b[?1;1;0S";
/// XTSMGRAPHICS: the largest sixel image (xterm draws none wider than its
/// `maxGraphicSize`, 1000x1000 by default).
const SIXEL_GEOMETRY: &[u8] = b"\x1b[?2;1;0S";
/// XTGETTCAP for `RGB` and `Tc`, hex-encoded; then background RGB 1,2,3
/// set, read back (DECRQSS for SGR) and reset.
const TRUECOLOR: &[u8] = b"\x1bP+q524742;5463\x1b\\\x1b[48;2;1;2;3m\x1bP$qm\x1b\\\x1b[m";
/// XTVERSION: the terminal's name and version (`DCS >|kitty(0.40.1) ST`).
const VERSION: &[u8] = b"\x1b[>0q";
/// A sextant and an octant, each printed at the top left and followed by a
/// cursor position report, then the line cleared (the first frame is drawn
/// over it anyway).
const ADVANCES: &[u8] = "\x1b[H\u{1FB00}\x1b[6n\x1b[H\u{1CD00}\x1b[6n\x1b[H\x1b[2K".as_bytes();
const DA1: &[u8] = b"\x1b[c";

/// What to ask.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Ask {
    pub(crate) graphics: bool,
    pub(crate) colour: bool,
    /// Which block symbols the terminal draws.
    pub(crate) symbols: bool,
    /// Inside tmux: tmux takes an unwrapped kitty query (an APC string)
    /// for the pane's title, so it goes only through passthrough, if at all.
    pub(crate) tmux: bool,
    /// Inside tmux with passthrough: the graphics queries go through it.
    pub(crate) passthrough: bool,
}

impl Ask {
    pub(crate) fn any(&self) -> bool {
        self.graphics || self.colour || self.symbols
    }

    /// The queries, DA1 last. The cell's size is asked whatever is asked:
    /// block symbols keep the picture's proportions with it too.
    pub(crate) fn queries(&self) -> Vec<u8> {
        let mut q = Vec::new();
        let asked: &[&[u8]] = if self.graphics {
            &[
                KITTY_QUERY,
                CELL_SIZE,
                WINDOW_PIXELS,
                REGISTERS,
                SIXEL_GEOMETRY,
            ]
        } else {
            &[CELL_SIZE, WINDOW_PIXELS]
        };
        for &query in asked {
            if self.passthrough {
                q.extend(passthrough(query));
            }
            if !(self.tmux && query == KITTY_QUERY) {
                q.extend_from_slice(query);
            }
        }
        if self.colour {
            q.extend_from_slice(TRUECOLOR);
        }
        if self.symbols {
            q.extend_from_slice(VERSION);
            q.extend_from_slice(ADVANCES);
        }
        // The terminal tmux runs in says through passthrough whether it
        // draws sixel; tmux answers the bare DA1 at once, so its own
        // answer comes first.
        if self.passthrough {
            q.extend(passthrough(DA1));
        }
        q.extend_from_slice(DA1);
        q
    }

    /// How many answers to DA1 end the round.
    fn da1_answers(&self) -> usize {
        1 + self.passthrough as usize
    }
}

/// The terminal's answers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Answers {
    /// DA1 came: the terminal answers queries.
    pub(crate) answered: bool,
    pub(crate) kitty: bool,
    /// The first answer to DA1 lists sixel: the terminal draws it (inside
    /// tmux, tmux itself does).
    pub(crate) sixel: bool,
    /// Inside tmux with passthrough, the second answer to DA1 (the
    /// terminal tmux runs in) lists sixel.
    pub(crate) outer_sixel: bool,
    /// Answers to DA1 so far.
    pub(crate) da1: usize,
    pub(crate) registers: Option<usize>,
    /// The largest sixel image, in pixels.
    pub(crate) sixel_max: Option<(u32, u32)>,
    /// A cell's size (width, height) in pixels, and the text area's.
    pub(crate) cell: Option<(u32, u32)>,
    pub(crate) window: Option<(u32, u32)>,
    /// Whether the terminal shows 24-bit colour, where it said.
    pub(crate) rgb: Option<bool>,
    /// The terminal's name and version (XTVERSION), as it said them.
    pub(crate) version: Option<String>,
    /// How many cells a sextant, then an octant, moved the cursor.
    pub(crate) advances: Vec<u16>,
}

impl Answers {
    /// Takes one answer; true when it was DA1's (the last).
    pub(crate) fn take(&mut self, reply: &Reply) -> bool {
        match reply {
            Reply::DeviceAttributes(attrs) => {
                self.answered = true;
                let sixel = attrs.iter().skip(1).any(|&a| a == 4);
                match self.da1 {
                    0 => self.sixel = sixel,
                    _ => self.outer_sixel |= sixel,
                }
                self.da1 += 1;
                return true;
            }
            Reply::Kitty(text) => self.kitty |= text.starts_with("i=31;OK"),
            Reply::CellSize(h, w) if *h > 0 && *w > 0 => self.cell = Some((*w as u32, *h as u32)),
            Reply::WindowPixels(h, w) if *h > 0 && *w > 0 => {
                self.window = Some((*w as u32, *h as u32))
            }
            Reply::ColourRegisters(n) if *n > 0 => self.registers = Some(*n as usize),
            Reply::SixelGeometry(w, h) if *w > 0 && *h > 0 => {
                self.sixel_max = Some((*w as u32, *h as u32))
            }
            // Only the glyph probes ask for the cursor during the round.
            Reply::CursorPosition(_, col) if self.advances.len() < 2 => {
                self.advances.push(col.saturating_sub(1))
            }
            Reply::Dcs(text) if text.starts_with(">|") => {
                self.version = Some(text[2..].trim().to_string())
            }
            Reply::Dcs(text) => {
                let said = if text.starts_with("1+r") {
                    Some(true)
                } else {
                    text.strip_prefix("1$r").map(keeps_rgb)
                };
                if let Some(said) = said {
                    self.rgb = Some(said || self.rgb == Some(true));
                }
            }
            _ => {}
        }
        false
    }
}

/// Whether the SGR settings a DECRQSS answer lists (`0;48:2::1:2:3m`,
/// `48;2;1;2;3m`; a terminal of 256 colours says `48;5;16m`) keep the RGB
/// background set before it.
fn keeps_rgb(sgr: &str) -> bool {
    let params: Vec<&str> = sgr.trim_end_matches('m').split([';', ':']).collect();
    params.windows(2).enumerate().any(|(i, w)| {
        w == ["48", "2"] && {
            // The colour space, empty or given, may come before the values.
            let rest: Vec<&str> = params[i + 2..]
                .iter()
                .copied()
                .filter(|p| !p.is_empty())
                .take(4)
                .collect();
            rest.starts_with(&["1", "2", "3"]) || rest.starts_with(&["0", "1", "2", "3"])
        }
    })
}

/// Sends the queries with `send` and collects the answers from `reader`
/// until DA1's (or [`WAIT`], or an input `quits` says ends the program);
/// keys typed meanwhile are kept for later.
pub(crate) fn ask(
    ask: Ask,
    mut send: impl FnMut(&[u8]) -> std::io::Result<()>,
    reader: &Reader,
    tmux: bool,
    quits: impl Fn(&Input) -> bool,
) -> std::io::Result<(Answers, Vec<Input>)> {
    let mut answers = Answers::default();
    let mut kept = Vec::new();
    if !ask.any() {
        return Ok((answers, kept));
    }
    send(&ask.queries())?;
    let mut end = Instant::now() + WAIT;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match reader.rx.recv_timeout(left) {
            Ok(Input::Reply(r)) => {
                if answers.take(&r) && answers.da1 >= ask.da1_answers() {
                    if !tmux || ask.passthrough {
                        break;
                    }
                    end = end.min(Instant::now() + TMUX_GRACE);
                }
            }
            Ok(input) => {
                let quit = quits(&input);
                kept.push(input);
                if quit {
                    break;
                }
            }
            Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => break,
        }
    }
    Ok((answers, kept))
}

/// The pixel protocol `arg` and the answers lead to, and what to say about
/// it. `cell_ioctl` is a cell's size from the window size ioctl; `env`
/// reads the environment; `tmux_passthrough` is `Some(on)` inside tmux.
pub(crate) fn choose(
    arg: GraphicsArg,
    answers: &Answers,
    cell_ioctl: Option<(u32, u32)>,
    cols_rows: (u16, u16),
    env: impl Fn(&str) -> Option<String>,
    tmux_passthrough: Option<bool>,
) -> (Option<PixelMode>, String) {
    let iterm = ["TERM_PROGRAM", "LC_TERMINAL"]
        .iter()
        .any(|v| env(v).is_some_and(|t| t == "iTerm.app" || t == "iTerm2" || t == "WezTerm"));
    let protocol = match arg {
        GraphicsArg::Symbols => return (None, String::new()),
        GraphicsArg::Kitty => Protocol::Kitty,
        GraphicsArg::Sixel => Protocol::Sixel,
        GraphicsArg::Iterm2 => Protocol::Iterm2,
        GraphicsArg::Auto if answers.kitty => Protocol::Kitty,
        GraphicsArg::Auto if answers.sixel || answers.outer_sixel => Protocol::Sixel,
        GraphicsArg::Auto if iterm => Protocol::Iterm2,
        GraphicsArg::Auto => {
            let why = match tmux_passthrough {
                Some(false) => {
                    "inside tmux without allow-passthrough (tmux set -g allow-passthrough on)"
                }
                _ if !answers.answered => "the terminal answered no query",
                _ => "the terminal has no kitty graphics, sixel or iTerm2 images",
            };
            return (None, format!("block symbols: {why}"));
        }
    };
    // Sixel through tmux needs nothing when tmux draws sixel itself (its
    // DA1 lists 4); everything else needs passthrough.
    let native = protocol == Protocol::Sixel && answers.sixel;
    let passthrough = tmux_passthrough.is_some() && !native;
    if tmux_passthrough == Some(false) && !native {
        return (
            None,
            format!(
                "block symbols: {} needs tmux's allow-passthrough (tmux set -g allow-passthrough on)",
                protocol.name()
            ),
        );
    }
    let measured = cell_size(answers, cell_ioctl, cols_rows);
    let cell = measured.unwrap_or((8, 16));
    let colours = answers.registers.unwrap_or(256).min(256);
    let mut said = format!("{}, cells {}x{} px", protocol.name(), cell.0, cell.1);
    if measured.is_none() {
        said += " (assumed: the terminal did not say)";
    }
    let claimed = match protocol {
        Protocol::Kitty => answers.kitty,
        Protocol::Sixel => answers.sixel || answers.outer_sixel,
        Protocol::Iterm2 => iterm,
    };
    if answers.answered && !claimed {
        said += " (as asked: the terminal does not claim it)";
    }
    let sixel_max = answers.sixel_max.filter(|_| protocol == Protocol::Sixel);
    if protocol == Protocol::Sixel {
        said += &format!(", {colours} colours");
    }
    if let Some((w, h)) = sixel_max {
        said += &format!(", images up to {w}x{h} px");
    }
    if passthrough {
        said += ", through tmux";
    }
    (
        Some(PixelMode {
            protocol,
            cell,
            colours,
            passthrough,
            pane: None,
            max: sixel_max,
        }),
        said,
    )
}

/// What tmux says of itself and of the terminal it runs in.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Tmux {
    /// `allow-passthrough` is on.
    pub(crate) passthrough: bool,
    /// Whether the terminal it runs in has 24-bit colour (its `RGB`
    /// feature), when a client is attached.
    pub(crate) rgb: Option<bool>,
    /// That terminal's name and version, as it told tmux (tmux 3.3 and
    /// later ask it with XTVERSION).
    pub(crate) terminal: Option<String>,
    /// This pane's top-left cell (column, row) in that terminal.
    pub(crate) pane: Option<(u16, u16)>,
}

/// A cell's size in pixels: the terminal's answer, else the window size
/// ioctl's, else the window's pixels over its cells; sizes no font has are
/// garbage (they would make images of gigapixels) and skipped.
pub(crate) fn cell_size(
    answers: &Answers,
    cell_ioctl: Option<(u32, u32)>,
    cols_rows: (u16, u16),
) -> Option<(u32, u32)> {
    let from_window = answers
        .window
        .map(|(w, h)| (w / cols_rows.0.max(1) as u32, h / cols_rows.1.max(1) as u32));
    let sane = |&(w, h): &(u32, u32)| CELL_PX.contains(&w) && CELL_PX.contains(&h);
    answers
        .cell
        .filter(sane)
        .or(cell_ioctl.filter(sane))
        .or(from_window.filter(sane))
}

/// Inside tmux, what it says (one `tmux` command).
pub(crate) fn tmux() -> Option<Tmux> {
    std::env::var_os("TMUX")?;
    let mut cmd = std::process::Command::new("tmux");
    cmd.args(["show-options", "-Apv", "allow-passthrough", ";"])
        .args([
            "display-message",
            "-p",
            "features:#{client_termfeatures}\ntermtype:#{client_termtype}",
            ";",
        ])
        .args(pane_query());
    Some(parse_tmux(&ask_tmux(cmd)?))
}

/// What a tmux command prints, if it ends within [`WAIT`]: a tmux server
/// that does not answer must not hold the TUI up.
fn ask_tmux(mut cmd: std::process::Command) -> Option<String> {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let end = Instant::now() + WAIT;
    // Its few lines fit the pipe: it can end before they are read.
    while child.try_wait().ok()?.is_none() {
        if Instant::now() >= end {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let mut text = String::new();
    child.stdout.take()?.read_to_string(&mut text).ok()?;
    Some(text)
}

/// Inside tmux, where this pane is now: it moves when panes are split,
/// resized or zoomed.
pub(crate) fn tmux_pane() -> Option<(u16, u16)> {
    std::env::var_os("TMUX")?;
    let mut cmd = std::process::Command::new("tmux");
    cmd.args(pane_query());
    parse_tmux(&ask_tmux(cmd)?).pane
}

/// Asks for this pane's place (`TMUX_PANE` names it: the client's current
/// pane may be another).
fn pane_query() -> Vec<String> {
    let mut q = vec!["display-message".to_string(), "-p".into()];
    if let Some(p) = std::env::var("TMUX_PANE").ok().filter(|p| !p.is_empty()) {
        q.extend(["-t".into(), p]);
    }
    q.push("pane:#{pane_left},#{pane_top}".into());
    q
}

fn parse_tmux(text: &str) -> Tmux {
    let features = text
        .lines()
        .find_map(|l| l.strip_prefix("features:"))
        .filter(|f| !f.trim().is_empty());
    Tmux {
        passthrough: text.lines().any(|l| matches!(l.trim(), "on" | "all")),
        rgb: features.map(|f| f.split(',').any(|f| f.trim() == "RGB")),
        terminal: text
            .lines()
            .find_map(|l| l.strip_prefix("termtype:"))
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .map(str::to_string),
        pane: text
            .lines()
            .find_map(|l| l.strip_prefix("pane:"))
            .and_then(|p| p.trim().split_once(','))
            .and_then(|(x, y)| Some((x.parse().ok()?, y.parse().ok()?))),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::tui::term::input::Parser;

    /// The terminal's answers to the probe round, as bytes.
    pub(crate) fn answers(bytes: &[u8]) -> Answers {
        let mut a = Answers::default();
        for i in Parser::default().feed(bytes) {
            if let Input::Reply(r) = i {
                a.take(&r);
            }
        }
        a
    }

    fn none(_: &str) -> Option<String> {
        None
    }

    #[test]
    fn kitty_sixel_and_nothing_are_told_apart() {
        // kitty: the query image is accepted, cells 9x18.
        let a = answers(b"\x1b_Gi=31;OK\x1b\\\x1b[6;18;9t\x1bP1+r524742=38\x1b\\\x1b[?62;22c");
        assert!(a.answered && a.kitty && a.rgb == Some(true) && !a.sixel);
        let (m, said) = choose(GraphicsArg::Auto, &a, None, (80, 24), none, None);
        let m = m.unwrap();
        assert_eq!((m.protocol, m.cell), (Protocol::Kitty, (9, 18)));
        assert!(said.contains("kitty"), "{said}");
        // xterm -ti vt340: DA1 lists 4, 16 registers, no cell size answer
        // but the ioctl knows.
        let a = answers(b"\x1b_Gi=31;EINVAL\x1b\\\x1b[?1;0;16S\x1b[?63;1;2;4;6;9;15;22c");
        let (m, _) = choose(GraphicsArg::Auto, &a, Some((6, 13)), (80, 24), none, None);
        let m = m.unwrap();
        assert_eq!(
            (m.protocol, m.cell, m.colours),
            (Protocol::Sixel, (6, 13), 16)
        );
        // A plain terminal.
        let a = answers(b"\x1b[?1;2c");
        let (m, said) = choose(GraphicsArg::Auto, &a, None, (80, 24), none, None);
        assert!(m.is_none() && said.contains("no kitty"), "{said}");
        // No answer at all.
        let (m, said) = choose(
            GraphicsArg::Auto,
            &Answers::default(),
            None,
            (80, 24),
            none,
            None,
        );
        assert!(m.is_none() && said.contains("answered no query"), "{said}");
    }

    #[test]
    fn the_terminal_says_whether_it_keeps_24_bit_colour() {
        // xterm with direct colour, kitty, and a terminal that mapped the
        // colour to its palette; XTGETTCAP's yes wins.
        for (reply, rgb) in [
            (&b"\x1bP1$r0;48:2::1:2:3m\x1b\\"[..], Some(true)),
            (b"\x1bP1$r48;2;1;2;3m\x1b\\", Some(true)),
            (b"\x1bP1$r0;48;5;16m\x1b\\", Some(false)),
            (b"\x1bP1+r524742=38\x1b\\\x1bP1$r48;5;16m\x1b\\", Some(true)),
            // Not understood: nothing said.
            (b"\x1bP0$r\x1b\\\x1bP0+r524742\x1b\\", None),
        ] {
            let mut bytes = reply.to_vec();
            bytes.extend_from_slice(b"\x1b[?62c");
            assert_eq!(
                answers(&bytes).rgb,
                rgb,
                "{}",
                String::from_utf8_lossy(reply)
            );
        }
    }

    #[test]
    fn tmux_says_passthrough_and_rgb() {
        let t = parse_tmux(
            "on\nfeatures:256,RGB,title,clipboard\ntermtype:kitty(0.40.1)\npane:81,12\n",
        );
        assert_eq!(
            t,
            Tmux {
                passthrough: true,
                rgb: Some(true),
                terminal: Some("kitty(0.40.1)".into()),
                pane: Some((81, 12)),
            }
        );
        // A place that is not two numbers is no place.
        for bad in ["pane:81\n", "pane:,\n", "pane:-1,2\n", "pane:99999,1\n"] {
            assert_eq!(parse_tmux(bad).pane, None, "{bad}");
        }
        let t = parse_tmux("off\nfeatures:256,title\n");
        assert_eq!((t.passthrough, t.rgb), (false, Some(false)));
        // No client attached: nothing known of the terminal.
        assert_eq!(parse_tmux("off\nfeatures:\n").rgb, None);
        assert_eq!(parse_tmux("off\nfeatures:\ntermtype:\n").terminal, None);
    }

    #[test]
    fn inside_tmux_the_kitty_query_goes_only_through_passthrough() {
        let apc = |q: &[u8]| q.windows(2).filter(|w| w == b"\x1b_").count();
        let bare = Ask {
            graphics: true,
            ..Ask::default()
        };
        assert_eq!(apc(&bare.queries()), 1);
        let tmux = Ask { tmux: true, ..bare };
        assert_eq!(apc(&tmux.queries()), 0);
        let through = Ask {
            passthrough: true,
            ..tmux
        };
        let q = through.queries();
        // The one there is wrapped: its ESC doubled.
        assert_eq!(apc(&q), 1);
        assert!(q.windows(3).any(|w| w == b"\x1b\x1b_"));
        // DA1 goes both ways, tmux's last, and two answers end the round.
        assert!(q.ends_with(&[&passthrough(DA1)[..], DA1].concat()));
        assert_eq!((tmux.da1_answers(), through.da1_answers()), (1, 2));
    }

    #[test]
    fn tmux_needs_passthrough_unless_it_draws_sixel_itself() {
        // tmux 3.3 in xterm -ti vt340: tmux answers first, without sixel,
        // then xterm through passthrough, with it.
        let outer = answers(b"\x1b[?1;2c\x1b[?1;0;1024S\x1b[?63;1;2;4;6;9;15;16;22;28c");
        assert!(!outer.sixel && outer.outer_sixel && outer.da1 == 2);
        let (m, said) = choose(GraphicsArg::Auto, &outer, None, (80, 24), none, Some(true));
        let m = m.unwrap();
        assert_eq!(
            (m.protocol, m.passthrough, m.colours),
            (Protocol::Sixel, true, 256)
        );
        assert!(!said.contains("does not claim"), "{said}");
        // With the largest image it draws: kept, and said.
        let mut sized = outer.clone();
        sized.take(&Reply::SixelGeometry(1000, 1000));
        let (m, said) = choose(GraphicsArg::Auto, &sized, None, (80, 24), none, Some(true));
        assert_eq!(m.unwrap().max, Some((1000, 1000)));
        assert!(said.contains("up to 1000x1000 px"), "{said}");
        let kitty = answers(b"\x1b_Gi=31;OK\x1b\\\x1b[?62c");
        let (m, said) = choose(GraphicsArg::Auto, &kitty, None, (80, 24), none, Some(false));
        assert!(m.is_none() && said.contains("allow-passthrough"), "{said}");
        let (m, _) = choose(GraphicsArg::Auto, &kitty, None, (80, 24), none, Some(true));
        assert!(m.unwrap().passthrough);
        let sixel = answers(b"\x1b[?62;4c");
        let (m, _) = choose(GraphicsArg::Auto, &sixel, None, (80, 24), none, Some(false));
        assert!(!m.unwrap().passthrough);
        // Forced, with a cell size from the window's pixels.
        let a = answers(b"\x1b[4;480;800t\x1b[?62c");
        let (m, said) = choose(GraphicsArg::Iterm2, &a, None, (100, 30), none, None);
        assert_eq!(m.unwrap().cell, (8, 16));
        assert!(!said.contains("assumed"), "{said}");
        let (m, said) = choose(
            GraphicsArg::Kitty,
            &Answers::default(),
            None,
            (100, 30),
            none,
            None,
        );
        assert_eq!(m.unwrap().cell, (8, 16));
        assert!(said.contains("assumed"), "{said}");
        // Garbage sizes are not believed: the next source is.
        let a = answers(b"\x1b[6;65535;65535t\x1b[4;480;800t\x1b[?62c");
        let (m, said) = choose(GraphicsArg::Sixel, &a, Some((0, 7)), (100, 30), none, None);
        assert_eq!(m.unwrap().cell, (8, 16));
        assert!(!said.contains("assumed"), "{said}");
        let a = answers(b"\x1b[6;1;9000t\x1b[?62c");
        let (m, said) = choose(GraphicsArg::Kitty, &a, None, (100, 30), none, None);
        assert_eq!(m.unwrap().cell, (8, 16));
        assert!(said.contains("assumed"), "{said}");
        // Sixel asked of a terminal whose DA1 lacks it: used, and said so.
        let (m, said) = choose(GraphicsArg::Sixel, &a, None, (100, 30), none, None);
        assert_eq!(m.unwrap().protocol, Protocol::Sixel);
        assert!(said.contains("does not claim it"), "{said}");
        // iTerm2 known from the environment.
        let env = |v: &str| (v == "LC_TERMINAL").then(|| "iTerm2".to_string());
        let (m, _) = choose(
            GraphicsArg::Auto,
            &answers(b"\x1b[?62c"),
            None,
            (80, 24),
            env,
            None,
        );
        assert_eq!(m.unwrap().protocol, Protocol::Iterm2);
    }
}
