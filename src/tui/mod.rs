//! The terminal UI: explore a scene with a progressively rendered viewport,
//! BVH, feature and render panels, and the selected pixel's ray tree.
//!
//! `app` holds the state and actions, split into `render_choice` (features,
//! plan, builder), `camera`, `display` (how the viewport reaches the screen),
//! `link` (to the render `worker` on its own thread), `inspector` (the
//! ray-tree pane), `overlays`, `status` (the status line), `jobs` (PNG
//! `export`, the stability battery), `popup`, `meter` (the output's rates)
//! and `reference`; `keys` is the one key table, `layout` places everything
//! before each draw, `widgets` draw (and only draw), `graphics` turns the
//! viewport's pixels into cells in the colours of `color`, `term` writes to
//! the terminal, and `bench` measures the pass time and terminal bandwidth.

pub mod app;
pub(crate) mod bench;
mod camera;
pub mod color;
mod config;
mod display;
mod export;
pub mod graphics;
mod inspector;
mod jobs;
mod keys;
mod layout;
mod link;
mod meter;
mod overlays;
mod popup;
mod reference;
mod render_choice;
mod status;
mod term;
pub mod widgets;
mod worker;

use std::io::{self, IsTerminal, Stdout, Write};
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::sync::Once;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ratatui::crossterm::event::{DisableMouseCapture, EnableMouseCapture};
use ratatui::crossterm::terminal::{
    disable_raw_mode, enable_raw_mode, EnterAlternateScreen, LeaveAlternateScreen,
};
use ratatui::crossterm::{cursor, execute};
use ratatui::layout::Rect;
use ratatui::Terminal;

use crate::render::{SceneRequest, Session};
use app::App;
use color::ColorMode;
use graphics::bands::{Bands, Picture};
use graphics::encoder::Encoder;
use graphics::symbols::SymbolsArg;
use graphics::{GraphicsArg, PixelMode};
use term::detect::{self, Ask};
use term::input::{Input, Reader, Reply};
use term::output::{Figures, Shown, TermOutput};
use term::screen::Screen;

/// At most this many frames per second are drawn.
const FRAME: Duration = Duration::from_millis(33);
/// How often the loop looks for new passes while rendering or waiting for
/// the terminal, and while idle (a resize is seen within that).
const POLL_BUSY: Duration = Duration::from_millis(8);
const POLL_IDLE: Duration = Duration::from_millis(100);
/// Over a slow link, a view's preview pass (see `render`) is sent as a
/// picture only if its full pass has not come within this long: the full
/// pass sent coarse shows as much, and one coarse picture is enough (two
/// would take twice as long).
const PREVIEW_WAIT: Duration = Duration::from_secs(1);
/// How long leaving waits for the terminal's last answers.
const LEAVE_WAIT: Duration = Duration::from_secs(1);

/// Opens the TUI on the scene; returns when the user quits. Colours,
/// symbols and graphics not given here come from the configuration file
/// and the environment (`config`), else from asking the terminal.
pub(crate) fn run(
    req: &SceneRequest,
    color: Option<ColorMode>,
    symbols: Option<SymbolsArg>,
    graphics: Option<GraphicsArg>,
    reference: Option<&Path>,
) -> Result<ExitCode> {
    if !io::stdout().is_terminal() {
        bail!("the TUI needs an interactive terminal; `rayterm render` writes images without one");
    }
    // A dumb terminal (Emacs' shell, some serial consoles) prints escape
    // sequences as text.
    if std::env::var("TERM").is_ok_and(|t| t == "dumb") {
        bail!(
            "the TUI needs a terminal that moves the cursor, and TERM=dumb says this one does \
             not; `rayterm render` writes images without one"
        );
    }
    let var = |v: &str| std::env::var(v).ok();
    let defaults = config::load(config::path(var).as_deref(), var)?;
    let color = color.or(defaults.color);
    let symbols = symbols.or(defaults.symbols).unwrap_or_default();
    let graphics = graphics.or(defaults.graphics).unwrap_or_default();
    if io::stderr().is_terminal() {
        // Large scenes take seconds to load; say so before the screen changes.
        crate::console::say("rayterm", &format!("loading {}...", req.spec));
    }
    let (session, warnings) = Session::open(req)?;
    for w in &warnings {
        crate::console::say("warning", w);
    }
    // The colours are decided once the terminal has answered.
    let mut app = App::new(
        session,
        warnings,
        color.unwrap_or(ColorMode::Palette256),
        reference,
    )?;
    app.jobs.export_size = req.size;
    // SIGTERM, SIGHUP and an outside SIGINT quit like `q`: the loop sees the
    // flag and the guard below restores the terminal. SIGTSTP suspends like
    // Ctrl-Z.
    crate::interrupt::flag();
    crate::interrupt::catch_stops();
    let guard = TerminalGuard::enter()?;
    let result = Keyboard::open().and_then(|keyboard| {
        let reader = Reader::spawn(keyboard.fd())?;
        let mut terminal = Screen::new(io::stdout(), None)
            .and_then(Terminal::new)
            .context("cannot set up the terminal")?;
        // What the terminal can do, asked before the first frame.
        let tmux = detect::tmux();
        let ask = Ask {
            graphics: graphics != GraphicsArg::Symbols,
            colour: color.is_none(),
            symbols: !matches!(symbols, SymbolsArg::Set(s) if s.grid().1 <= 2),
            tmux: tmux.is_some(),
            passthrough: tmux.as_ref().is_some_and(|t| t.passthrough),
        };
        let screen = terminal.backend_mut();
        let (answers, kept) = detect::ask(ask, |b| screen.send(b), &reader, tmux.is_some(), quits)?;
        let hint = match color {
            Some(_) => None,
            None => {
                let tmux_rgb = tmux.as_ref().and_then(|t| t.rgb);
                let (mode, hint) = term::choose_colour(answers.rgb, tmux_rgb, var);
                app.display.color = mode;
                hint
            }
        };
        let size = terminal.size()?;
        let (pixels, said) = detect::choose(
            graphics,
            &answers,
            cell_from_ioctl(),
            (size.width, size.height),
            var,
            tmux.as_ref().map(|t| t.passthrough),
        );
        // Inside tmux, XTVERSION names tmux; the terminal is what tmux was
        // told by the one it runs in.
        let named = match &tmux {
            Some(t) => t.terminal.as_deref(),
            None => answers.version.as_deref(),
        };
        let (set, symbols_hint) = term::glyphs::choose(symbols, named, &answers.advances);
        app.display.symbols = set;
        // Through tmux, images are placed from the pane's corner.
        app.display.pixels = pixels.map(|m| PixelMode {
            pane: tmux.as_ref().and_then(|t| t.pane),
            ..m
        });
        if let Some(cell) =
            detect::cell_size(&answers, cell_from_ioctl(), (size.width, size.height))
        {
            app.display.cell = cell;
        }
        // The colours' hint first: the status line wraps, and it is the
        // one to keep whole.
        let colour_hint = hint.filter(|_| app.display.pixels.is_none());
        let symbols_hint = symbols_hint.filter(|_| app.display.pixels.is_none());
        let mut said: Vec<String> = colour_hint
            .into_iter()
            .chain(symbols_hint)
            .chain([app.status.message().to_string(), said])
            .collect();
        said.retain(|s| !s.is_empty());
        app.say(said.join(" · "));
        let mut out = TermOutput::default();
        out.start(terminal.backend_mut(), Instant::now())?;
        let mut images = match app.display.pixels {
            Some(_) => Some(Images::new()?),
            None => None,
        };
        let result = event_loop(
            &mut terminal,
            &mut app,
            &reader,
            &mut out,
            images.as_mut(),
            kept,
        );
        let pictures = app.display.pixels.zip(images.as_mut());
        leave(terminal.backend_mut(), &reader, &mut out, pictures);
        result
    });
    drop(guard);
    if app.jobs.cancel_export() {
        crate::noteln!("rayterm: an unfinished PNG export was cancelled");
    }
    result?;
    Ok(if crate::interrupt::requested() {
        ExitCode::from(crate::interrupt::exit_code())
    } else {
        ExitCode::SUCCESS
    })
}

/// Whether an input is a key that quits (in the view, as at startup).
fn quits(input: &Input) -> bool {
    let Input::Event(ratatui::crossterm::event::Event::Key(k)) = input else {
        return false;
    };
    keys::Key::from_event(k).and_then(|k| keys::action(k, keys::Mode::View))
        == Some(keys::Action::Quit)
}

/// A cell's size in pixels from the window size ioctl, where the terminal
/// fills it in.
fn cell_from_ioctl() -> Option<(u32, u32)> {
    let w = ratatui::crossterm::terminal::window_size().ok()?;
    let cell = (
        w.width as u32 / w.columns.max(1) as u32,
        w.height as u32 / w.rows.max(1) as u32,
    );
    (cell.0 > 0 && cell.1 > 0).then_some(cell)
}

/// Where keys come from: standard input when it is the terminal, else the
/// controlling terminal.
enum Keyboard {
    Stdin,
    Tty(std::fs::File),
}

impl Keyboard {
    fn open() -> Result<Keyboard> {
        if io::stdin().is_terminal() {
            return Ok(Keyboard::Stdin);
        }
        let tty = std::fs::File::open("/dev/tty").context("cannot read keys from /dev/tty")?;
        Ok(Keyboard::Tty(tty))
    }

    fn fd(&self) -> i32 {
        use std::os::fd::AsRawFd;
        match self {
            Keyboard::Stdin => io::stdin().as_raw_fd(),
            Keyboard::Tty(f) => f.as_raw_fd(),
        }
    }
}

/// Draws at most every [`FRAME`] when something changed, writes what the
/// link has room for, and takes keys and the terminal's answers as they
/// come: a key acts within a loop turn, whatever the link's speed.
fn event_loop<W: Write>(
    terminal: &mut Terminal<Screen<W>>,
    app: &mut App,
    reader: &Reader,
    out: &mut TermOutput,
    mut images: Option<&mut Images>,
    kept: Vec<Input>,
) -> Result<()> {
    let mut dirty = true;
    let mut last_draw = Instant::now() - FRAME;
    let mut size = terminal.size()?;
    // The picture waits to be sent as images.
    let mut picture_due = false;
    for input in kept {
        if let Input::Event(ev) = input {
            app.handle_event(&ev);
        }
    }
    // Quit typed before the first frame: none is drawn.
    if app.quit {
        return Ok(());
    }
    loop {
        dirty |= app.poll()?;
        let now_size = terminal.size()?;
        if std::mem::replace(&mut size, now_size) != now_size {
            dirty = true;
            // A pane that tmux resized may have moved too.
            if let Some(m) = app.display.pixels.as_mut().filter(|m| m.passthrough) {
                m.pane = detect::tmux_pane().or(m.pane);
            }
        }
        dirty |= app.note_output(out.figures());
        if dirty && last_draw.elapsed() >= FRAME {
            picture_due |= draw_frame(terminal, app, out)?;
            last_draw = Instant::now();
            dirty = false;
        }
        if let (Some(mode), Some(images)) = (app.display.pixels, images.as_mut()) {
            images.step(terminal.backend_mut(), app, out, &mode, &mut picture_due);
        }
        out.pump(terminal.backend_mut(), Instant::now())?;
        let wait = if dirty {
            FRAME.saturating_sub(last_draw.elapsed())
        } else if app.idle() && !out.waiting() && !images.as_ref().is_some_and(|i| i.busy()) {
            POLL_IDLE
        } else {
            POLL_BUSY
        };
        let mut next = match reader.rx.recv_timeout(wait) {
            Ok(input) => Some(input),
            Err(RecvTimeoutError::Timeout) => None,
            // The terminal is gone.
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        };
        // Take everything that came before drawing again.
        while let Some(input) = next {
            match input {
                Input::Event(ev) => {
                    app.handle_event(&ev);
                    dirty = true;
                }
                Input::Reply(Reply::CursorPosition(..)) => out.answered(Instant::now()),
                Input::Reply(_) => {}
            }
            // Keys typed after Ctrl-Z wait until the TUI is back.
            if app.quit || app.suspend {
                break;
            }
            next = reader.rx.try_recv().ok();
        }
        if app.quit || crate::interrupt::requested() {
            return Ok(());
        }
        // Both flags are taken: one suspend answers a Ctrl-Z and a SIGTSTP.
        if std::mem::take(&mut app.suspend) | crate::interrupt::stop_requested() {
            if !crate::interrupt::catch_stops() {
                app.say("no suspending: rayterm was started with SIGTSTP ignored (no job control)");
            } else if !suspend(
                terminal,
                reader,
                out,
                app.display.pixels.zip(images.as_deref_mut()),
            )? {
                return Ok(());
            }
            dirty = true;
            last_draw = Instant::now() - FRAME;
        } else if crate::interrupt::continued() {
            // Stopped without warning (SIGSTOP): the shell may have reset
            // the terminal's modes and drawn over the screen.
            take_back(terminal, out)?;
            dirty = true;
            last_draw = Instant::now() - FRAME;
        }
    }
}

/// Gives the terminal back as quitting does, stops the process for the
/// shell's job control, and takes the terminal again once continued;
/// false when told to quit while stopped (the terminal stays the shell's).
fn suspend<W: Write>(
    terminal: &mut Terminal<Screen<W>>,
    reader: &Reader,
    out: &mut TermOutput,
    pictures: Option<(PixelMode, &mut Images)>,
) -> Result<bool> {
    leave(terminal.backend_mut(), reader, out, pictures);
    restore();
    crate::interrupt::stop();
    if crate::interrupt::requested() {
        return Ok(false);
    }
    take_back(terminal, out)?;
    // The SIGCONT that ended the stop asks for nothing more.
    crate::interrupt::continued();
    Ok(true)
}

/// Takes the terminal again after a stop: its modes as at startup, and the
/// whole screen drawn anew. The startup questions are not asked again: the
/// terminal is the same, and answers unanswered before the stop are
/// forgotten (they may have gone to the shell).
fn take_back<W: Write>(terminal: &mut Terminal<Screen<W>>, out: &mut TermOutput) -> Result<()> {
    // After a SIGSTOP crossterm still takes raw mode to be on.
    let _ = disable_raw_mode();
    TerminalGuard::setup()?;
    terminal.clear()?;
    out.pacer.forget();
    Ok(())
}

/// The viewport's picture as images: which bands are on screen, and the
/// encoder making the next ones.
struct Images {
    bands: Bands,
    encoder: Encoder,
    /// What the picture being encoded shows.
    encoding: Option<Shown>,
    /// The view whose full pass was last sent coarse, over a slow link;
    /// and whether the sharp picture is still to follow it.
    coarse_for: Option<u64>,
    refine: bool,
    /// The newest view's generation, and when its first picture was due.
    view: Option<(u64, Instant)>,
    /// The last coarse picture (its view, pixels and size): sent again
    /// where text kept some of its bands off the screen, only those change.
    coarse: Option<(u64, Vec<[u8; 3]>, u32, u32)>,
}

impl Images {
    fn new() -> Result<Images> {
        Ok(Images {
            bands: Bands::default(),
            encoder: Encoder::spawn().context("cannot start the image encoder")?,
            encoding: None,
            coarse_for: None,
            refine: false,
            view: None,
            coarse: None,
        })
    }

    fn busy(&self) -> bool {
        self.encoder.busy()
    }

    /// Notes text written over images, queues encoded bands that are still
    /// right, and plans the newest picture once the last one is written
    /// (never more than one queued).
    fn step<W: Write>(
        &mut self,
        screen: &mut Screen<W>,
        app: &App,
        out: &mut TermOutput,
        mode: &PixelMode,
        due: &mut bool,
    ) {
        let area = app.display.layout.image;
        // Text written over sixel or iTerm2 images erased them there.
        let (rows, cleared) = screen.take_touched();
        if cleared {
            self.bands.forget();
        }
        self.bands.overwritten(mode, &rows);
        *due |= cleared || rows.iter().any(|&r| r);
        if rows.iter().any(|&r| r) {
            out.queue_first(self.bands.uncover(mode, !out.pieces_written(), |row| {
                screen.row_has_text(row, area)
            }));
        }
        if let Some(pieces) = self.encoder.done() {
            let (pieces, dropped) = self
                .bands
                .accept(pieces, |row| screen.row_has_text(row, area));
            out.queue(pieces);
            if let Some(shown) = self.encoding.take() {
                out.drawn(screen, shown);
            }
            *due |= dropped;
        }
        if self.encoder.busy() || !out.pieces_written() {
            return;
        }
        // The sharp picture follows a coarse one once that is written.
        if !std::mem::take(&mut self.refine) && !*due {
            return;
        }
        let mut shown = shown(app);
        let Some(pic) = widgets::picture(app) else {
            *due = false;
            out.drawn(screen, shown);
            return;
        };
        // Until a view's full pass has gone coarse, its pictures go coarse
        // where the link would take over a second for them (or is not
        // measured yet); the next picture after it is sharp.
        let cells = (area.width, area.height);
        let rate = out.figures().link_rate;
        let k = match self.coarse_for {
            Some(g) if g == shown.generation => 1,
            _ => graphics::coarse_factor(mode, (pic.w, pic.h), cells, rate),
        };
        let since = match self.view {
            Some((g, at)) if g == shown.generation => at.elapsed(),
            _ => {
                self.view = Some((shown.generation, Instant::now()));
                Duration::ZERO
            }
        };
        if k > 1 && !shown.full && since < PREVIEW_WAIT {
            *due = true;
            return;
        }
        *due = false;
        let coarse = if k > 1 {
            let (px, w, h) = graphics::downscale(&pic.px, pic.w, pic.h, k);
            if shown.full {
                self.coarse_for = Some(shown.generation);
            }
            Some(self.coarse.insert((shown.generation, px, w, h)).clone())
        } else {
            // Bands the coarse picture left off (text lay over them then)
            // go coarse, once, before the sharp picture: only they change.
            let holes = self.bands.holes(|row| screen.row_has_text(row, area));
            self.coarse
                .take()
                .filter(|c| holes && c.0 == shown.generation)
        };
        let sharp = coarse.is_none();
        if !sharp {
            self.refine = true;
            shown.sharp = false;
        }
        let (px, w, h) = coarse
            .as_ref()
            .map_or((&pic.px[..], pic.w, pic.h), |(_, px, w, h)| {
                (&px[..], *w, *h)
            });
        let picture = Picture {
            px,
            w,
            h,
            area,
            coarse: !sharp,
        };
        let (now, plan) = self
            .bands
            .plan(mode, &picture, |row| screen.row_has_text(row, area));
        out.queue(now);
        if plan.is_empty() {
            out.drawn(screen, shown);
        } else {
            self.encoding = Some(shown);
            self.encoder.start(plan);
        }
    }
}

/// What the viewport shows: the newest pass's view, and whether it is a
/// full pass of the current one.
/// Draws the app; with block symbols, notes what the viewport shows for
/// the output to follow. True when a picture waits to be sent as images.
fn draw_frame<W: Write>(
    terminal: &mut Terminal<Screen<W>>,
    app: &mut App,
    out: &mut TermOutput,
) -> Result<bool> {
    app.display.coarse_color = coarse_color(app, &out.figures());
    draw(terminal, app)?;
    if app.display.pixels.is_some() {
        return Ok(true);
    }
    let shown = Shown {
        sharp: !app.display.coarse_color,
        ..shown(app)
    };
    out.drawn(terminal.backend(), shown);
    Ok(false)
}

/// Whether to paint block symbols in 256 colours for now: in 24-bit colour
/// over a link too slow for the picture in it, until the view's first full
/// picture is on screen (then, a change in the output's figures, the
/// picture is drawn again in 24-bit colour).
fn coarse_color(app: &App, figures: &Figures) -> bool {
    let area = app.display.layout.image;
    app.display.pixels.is_none()
        && app.display.color == ColorMode::Truecolor
        && figures.picture.is_none_or(|(g, _)| g != app.generation())
        && graphics::truecolor_is_slow((area.width, area.height), figures.link_rate)
}

fn shown(app: &App) -> Shown {
    let frame = app.link.frame.as_deref();
    Shown {
        generation: frame.map_or(0, |f| f.generation),
        full: frame.is_some_and(|f| !f.coarse && f.generation == app.generation()),
        sharp: true,
    }
}

/// Leaves the alternate screen behind whatever is still on its way, and
/// waits (a second at most) for the answers still due, so that none
/// arrives at the shell. With images, those still queued stay unsent, and
/// those on screen go at once, whatever the link's room: kitty's outlive
/// the screen.
fn leave<W: Write>(
    screen: &mut Screen<W>,
    reader: &Reader,
    out: &mut TermOutput,
    images: Option<(PixelMode, &mut Images)>,
) {
    // Given back already: stopped, then told to quit.
    if !ACTIVE.load(Ordering::SeqCst) {
        return;
    }
    if let Some((mode, images)) = images {
        out.drop_pieces();
        let _ = screen.send(&images.bands.leave(&mode));
    }
    let mut bytes = leave_modes();
    if out.pacer.paced() {
        bytes.extend_from_slice(term::pace::PROBE);
    }
    if screen.send(&bytes).is_err() {
        return;
    }
    out.pacer.sent(bytes.len(), Instant::now());
    let end = Instant::now() + LEAVE_WAIT;
    while out.waiting() {
        let left = end.saturating_duration_since(Instant::now());
        match reader.rx.recv_timeout(left) {
            Ok(Input::Reply(Reply::CursorPosition(..))) => out.answered(Instant::now()),
            Ok(_) => {}
            Err(_) => return,
        }
    }
}

/// Lays out the screen for the terminal's size, brings the app in line
/// with it, then draws (drawing only reads the app).
pub(crate) fn draw<B: ratatui::backend::Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
) -> Result<()>
where
    B::Error: Send + Sync + 'static,
{
    let size = terminal.size()?;
    app.update(Rect::new(0, 0, size.width, size.height));
    terminal.draw(|f| widgets::draw(f, app))?;
    Ok(())
}

/// The bytes that leave the TUI's screen modes: mouse capture, the
/// alternate screen, the hidden cursor.
fn leave_modes() -> Vec<u8> {
    let mut bytes = Vec::new();
    let _ = ratatui::crossterm::queue!(
        bytes,
        DisableMouseCapture,
        LeaveAlternateScreen,
        cursor::Show
    );
    bytes
}

/// Whether the terminal is in the TUI's state (raw mode, alternate screen).
static ACTIVE: AtomicBool = AtomicBool::new(false);

/// Puts the terminal back; safe to call more than once and from a panic.
fn restore() {
    if ACTIVE.swap(false, Ordering::SeqCst) {
        let mut out: Stdout = io::stdout();
        let _ = disable_raw_mode();
        let _ = out.write_all(&leave_modes()).and_then(|()| out.flush());
        crate::interrupt::release_terminal();
    }
}

/// Raw mode, alternate screen, mouse capture and a hidden cursor while it
/// lives; the terminal is restored when it drops, and by a panic hook
/// before any panic message is printed.
struct TerminalGuard;

impl TerminalGuard {
    fn enter() -> Result<Self> {
        static HOOK: Once = Once::new();
        HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                restore();
                previous(info);
            }));
        });
        // Made first, so that a failure below still restores what was set.
        let guard = TerminalGuard;
        Self::setup()?;
        Ok(guard)
    }

    /// The TUI's terminal modes, on entering and after a stop.
    fn setup() -> Result<()> {
        crate::interrupt::hold_terminal(leave_modes);
        enable_raw_mode().context("cannot switch the terminal to raw mode")?;
        ACTIVE.store(true, Ordering::SeqCst);
        execute!(
            io::stdout(),
            EnterAlternateScreen,
            EnableMouseCapture,
            cursor::Hide
        )
        .context("cannot set up the terminal")
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        restore();
    }
}

#[cfg(test)]
mod tests;
