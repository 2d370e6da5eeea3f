//! The terminal UI: explore a scene with a progressively rendered viewport,
//! BVH, feature and render panels, and the selected pixel's ray tree.
//!
//! `app` holds the state and actions, split into `camera`, `link` (to the
//! render `worker` on its own thread), `inspector` (the ray-tree pane),
//! `jobs` (PNG `export`, the stability battery) and `popup`; `keys` is the
//! one key table, `layout` places everything before each draw, `widgets`
//! draw (and only draw), `graphics` turns the viewport's pixels into cells
//! in the colours of `color`, `term` writes to the terminal, and `bench`
//! measures the pass time and terminal bandwidth.

pub mod app;
pub mod bench;
pub mod camera;
pub mod color;
pub mod export;
pub mod graphics;
pub mod inspector;
pub mod jobs;
pub mod keys;
pub mod layout;
pub mod link;
pub mod popup;
pub mod term;
pub mod widgets;
pub mod worker;

use std::io::{self, IsTerminal, Stdout, Write};
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use ratatui::crossterm::event::{self, DisableMouseCapture, EnableMouseCapture};
use ratatui::crossterm::terminal::{
    disable_raw_mode, enable_raw_mode, EnterAlternateScreen, LeaveAlternateScreen,
};
use ratatui::crossterm::{cursor, execute};
use ratatui::layout::Rect;
use ratatui::Terminal;

use crate::render::{SceneRequest, Session};
use app::App;
use color::ColorMode;
use graphics::symbols::Symbols;
use term::screen::Screen;

/// At most this many frames per second are drawn.
const FRAME: Duration = Duration::from_millis(33);
/// How often the loop looks for new passes while rendering, and while idle.
const POLL_BUSY: Duration = Duration::from_millis(8);
const POLL_IDLE: Duration = Duration::from_millis(250);

/// Opens the TUI on the scene; returns when the user quits.
pub fn run(
    req: &SceneRequest,
    color: Option<ColorMode>,
    symbols: Symbols,
    reference: Option<&Path>,
) -> Result<ExitCode> {
    if !io::stdout().is_terminal() {
        bail!("the TUI needs an interactive terminal; `rayterm render` writes images without one");
    }
    if io::stderr().is_terminal() {
        // Large scenes take seconds to load; say so before the screen changes.
        eprintln!("rayterm: loading {}...", req.spec);
    }
    let (session, warnings) = Session::open(req)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let (detected, hint) = term::detect_colour(|v| std::env::var(v).ok());
    let mut app = App::new(session, warnings, color.unwrap_or(detected), reference)?;
    app.export_size = req.size;
    app.symbols = symbols;
    if let (None, Some(hint)) = (color, hint) {
        let said = match app.status.as_str() {
            "" => hint.to_string(),
            s => format!("{s} · {hint}"),
        };
        app.say(said);
    }
    // SIGTERM, SIGHUP and an outside SIGINT quit like `q`: the loop sees the
    // flag and the guard below restores the terminal.
    crate::interrupt::flag();
    let guard = TerminalGuard::enter()?;
    let result = Screen::new(io::stdout(), None)
        .and_then(Terminal::new)
        .context("cannot set up the terminal")
        .and_then(|mut t| event_loop(&mut t, &mut app));
    drop(guard);
    if app.jobs.cancel_export() {
        eprintln!("rayterm: an unfinished PNG export was cancelled");
    }
    result?;
    Ok(if crate::interrupt::requested() {
        ExitCode::from(crate::interrupt::exit_code())
    } else {
        ExitCode::SUCCESS
    })
}

fn event_loop<W: Write>(terminal: &mut Terminal<Screen<W>>, app: &mut App) -> Result<()> {
    let mut dirty = true;
    let mut last_draw = Instant::now() - FRAME;
    loop {
        dirty |= app.poll()?;
        dirty |= app.note_bytes(terminal.backend().written());
        if dirty && last_draw.elapsed() >= FRAME {
            draw(terminal, app)?;
            terminal.backend_mut().pump(usize::MAX)?;
            last_draw = Instant::now();
            dirty = false;
        }
        let idle = app.idle();
        let wait = if dirty {
            FRAME.saturating_sub(last_draw.elapsed())
        } else if idle {
            POLL_IDLE
        } else {
            POLL_BUSY
        };
        if event::poll(wait)? {
            // Take every pending event before drawing again.
            loop {
                app.handle_event(&event::read()?);
                if app.quit || !event::poll(Duration::ZERO)? {
                    break;
                }
            }
            dirty = true;
        }
        if app.quit || crate::interrupt::requested() {
            return Ok(());
        }
    }
}

/// Lays out the screen for the terminal's size, brings the app in line
/// with it, then draws (drawing only reads the app).
pub fn draw<B: ratatui::backend::Backend>(terminal: &mut Terminal<B>, app: &mut App) -> Result<()>
where
    B::Error: Send + Sync + 'static,
{
    let size = terminal.size()?;
    app.update(Rect::new(0, 0, size.width, size.height));
    terminal.draw(|f| widgets::draw(f, app))?;
    Ok(())
}

/// Whether the terminal is in the TUI's state (raw mode, alternate screen).
static ACTIVE: AtomicBool = AtomicBool::new(false);

/// Puts the terminal back; safe to call more than once and from a panic.
fn restore() {
    if ACTIVE.swap(false, Ordering::SeqCst) {
        let mut out: Stdout = io::stdout();
        let _ = disable_raw_mode();
        let _ = execute!(out, DisableMouseCapture, LeaveAlternateScreen, cursor::Show);
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
        enable_raw_mode().context("cannot switch the terminal to raw mode")?;
        ACTIVE.store(true, Ordering::SeqCst);
        let guard = TerminalGuard;
        execute!(
            io::stdout(),
            EnterAlternateScreen,
            EnableMouseCapture,
            cursor::Hide
        )
        .context("cannot set up the terminal")?;
        Ok(guard)
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        restore();
    }
}

#[cfg(test)]
mod tests;
