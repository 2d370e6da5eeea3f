//! In real terminals: rayterm runs in `xterm -ti vt340` and in kitty on a
//! virtual X display (Xvfb), finds sixel or the kitty protocol by asking,
//! and the viewport in a screenshot of the window (xwd) is compared with
//! the picture rayterm renders for it. Skips, saying so, where xterm (or
//! kitty), Xvfb or xwd are not installed (`apt-get install xterm xvfb
//! x11-apps`; kitty draws with OpenGL, which Mesa's software renderer
//! provides under Xvfb).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use ratatui::layout::Rect;
use rayterm::render::{Feature, Features, SceneRequest, Session};
use rayterm::tui::app::App;
use rayterm::tui::color::ColorMode;
use rayterm::tui::graphics::{PixelMode, Protocol};

/// The terminal's size in cells.
const COLS: u16 = 100;
const ROWS: u16 = 30;
/// The window's title, to find it by.
const TITLE: &str = "rayterm-under-test";
/// How long the picture may take to appear.
const PATIENCE: Duration = Duration::from_secs(60);

fn which(tool: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(tool).is_file()))
}

/// Children ended when the test ends, however it ends: asked to
/// terminate (xterm then hangs up on rayterm and closes its log), killed
/// if they linger.
struct Kill(Vec<Child>);

impl Drop for Kill {
    fn drop(&mut self) {
        for c in self.0.iter_mut().rev() {
            // SAFETY: kill(2) on the id of a child not yet waited for.
            unsafe { libc::kill(c.id() as i32, libc::SIGTERM) };
            let end = Instant::now() + Duration::from_secs(3);
            while c.try_wait().is_ok_and(|s| s.is_none()) && Instant::now() < end {
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// An XWD screenshot as RGB rows.
struct Shot {
    w: usize,
    h: usize,
    px: Vec<[u8; 3]>,
}

/// Reads xwd's output: a ZPixmap of 24 or 32 bits per pixel.
fn parse_xwd(data: &[u8]) -> Result<Shot, String> {
    let field = |i: usize| -> Result<u32, String> {
        data.get(i * 4..i * 4 + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| "short XWD header".to_string())
    };
    let header = field(0)? as usize;
    let (format, w, h) = (field(2)?, field(4)? as usize, field(5)? as usize);
    let (byte_order, bpp, line) = (field(7)?, field(11)?, field(12)? as usize);
    let masks = [field(14)?, field(15)?, field(16)?];
    let colours = field(19)? as usize;
    if format != 2 || !(bpp == 24 || bpp == 32) {
        return Err(format!("XWD format {format} at {bpp} bits per pixel"));
    }
    let start = header + colours * 12;
    let bytes = (bpp / 8) as usize;
    let mut px = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let at = start + y * line + x * bytes;
            let b = data.get(at..at + bytes).ok_or("short XWD pixels")?;
            let mut v = 0u32;
            for k in 0..bytes {
                let byte = if byte_order == 0 {
                    b[k]
                } else {
                    b[bytes - 1 - k]
                };
                v |= (byte as u32) << (8 * k);
            }
            px.push(masks.map(|m| ((v & m) >> m.trailing_zeros()) as u8));
        }
    }
    Ok(Shot { w, h, px })
}

/// The picture rayterm shows for the viewport of a `COLS x ROWS` terminal
/// with `protocol` and cells of `cell` pixels: its pixels, size, and
/// where it lies in cells.
struct Expected {
    px: Vec<[u8; 3]>,
    w: u32,
    h: u32,
    area: Rect,
}

fn expected(protocol: Protocol, cell: (u32, u32)) -> Expected {
    // One pass is the whole picture without supersampling, so the screen
    // settles on the picture computed here.
    let req = SceneRequest {
        features: Features::all().without(&[Feature::Supersampling]),
        ..SceneRequest::new("cornell")
    };
    let (session, warnings) = Session::open(&req).unwrap();
    let mut app = App::new(session, warnings, ColorMode::Truecolor, None).unwrap();
    app.display.pixels = Some(PixelMode {
        protocol,
        cell,
        colours: 256,
        passthrough: false,
        pane: None,
        max: None,
    });
    app.update(Rect::new(0, 0, COLS, ROWS));
    assert!(app.wait_frame(PATIENCE).unwrap(), "no pass");
    assert!(
        app.current_frame().unwrap().done,
        "one pass is the whole picture"
    );
    let pic = rayterm::tui::widgets::picture(&app).unwrap();
    let area = app.display.layout.image;
    // Within the budget the picture has the cells' pixels.
    assert_eq!(
        (pic.w, pic.h),
        (area.width as u32 * cell.0, area.height as u32 * cell.1)
    );
    Expected {
        px: pic.px,
        w: pic.w,
        h: pic.h,
        area,
    }
}

/// The mean difference per channel between the picture and the window's
/// pixels over its area, the window shifted by `off` pixels (a border).
fn difference(shot: &Shot, e: &Expected, cell: (u32, u32), off: (usize, usize)) -> f64 {
    let (x0, y0) = (
        e.area.x as usize * cell.0 as usize + off.0,
        e.area.y as usize * cell.1 as usize + off.1,
    );
    let (sw, sh) = (e.w as usize, e.h as usize);
    if x0 + sw > shot.w || y0 + sh > shot.h {
        return f64::INFINITY;
    }
    let mut sum = 0u64;
    for y in 0..sh {
        for x in 0..sw {
            let s = shot.px[(y0 + y) * shot.w + x0 + x];
            let p = e.px[y * sw + x];
            sum += (0..3).map(|c| s[c].abs_diff(p[c]) as u64).sum::<u64>();
        }
    }
    sum as f64 / (sw * sh * 3) as f64
}

/// The window titled [`TITLE`] on `display`, once it is there.
fn screenshot(display: &str, path: &Path) -> Option<Shot> {
    let ok = Command::new("xwd")
        .env("DISPLAY", display)
        .args(["-name", TITLE, "-silent", "-out"])
        .arg(path)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    ok.then(|| parse_xwd(&std::fs::read(path).ok()?).ok())
        .flatten()
}

/// A terminal to run rayterm in.
struct Case {
    name: &'static str,
    protocol: Protocol,
    /// The command, given where it may log what it is sent.
    command: fn(&Path) -> Command,
    /// What rayterm's images start with in that log, if it keeps one.
    marker: Option<&'static [u8]>,
    bound: f64,
}

fn rayterm_args() -> [&'static str; 4] {
    [
        env!("CARGO_BIN_EXE_rayterm"),
        "cornell",
        "--no",
        "supersampling",
    ]
}

fn xterm(log: &Path, registers: Option<u32>) -> Command {
    let mut c = Command::new("xterm");
    c.args(["-ti", "vt340", "-fn", "6x13", "-T", TITLE])
        .args(["-geometry", &format!("{COLS}x{ROWS}+0+0"), "-l", "-lf"])
        .arg(log);
    if let Some(n) = registers {
        c.args(["-xrm", &format!("XTerm*numColorRegisters: {n}")]);
    }
    c.arg("-e").args(rayterm_args());
    c
}

const CASES: &[Case] = &[
    // xterm's default colour registers (1024, of which 256 are used).
    Case {
        name: "xterm -ti vt340",
        protocol: Protocol::Sixel,
        command: |log| xterm(log, None),
        marker: Some(b"\x1bP0;1;0q"),
        bound: 6.0,
    },
    // The 16 of a real VT340: dithering between fewer colours.
    Case {
        name: "xterm -ti vt340, 16 colour registers",
        protocol: Protocol::Sixel,
        command: |log| xterm(log, Some(16)),
        marker: Some(b"\x1bP0;1;0q"),
        bound: 8.0,
    },
    Case {
        name: "kitty",
        protocol: Protocol::Kitty,
        command: |_| {
            let mut c = Command::new("kitty");
            c.args([
                "--title",
                TITLE,
                "-o",
                "font_size=8",
                "-o",
                "remember_window_size=no",
            ])
            .args(["-o", &format!("initial_window_width={COLS}c")])
            .args(["-o", &format!("initial_window_height={ROWS}c")])
            .args([
                "-o",
                "window_padding_width=0",
                "-o",
                "placement_strategy=top-left",
            ])
            .args(["-o", "allow_remote_control=no", "-e"])
            .args(rayterm_args());
            c
        },
        // RGB: exactly the picture, give or take the odd pixel.
        marker: None,
        bound: 0.5,
    },
];

#[test]
fn pixel_protocols_in_real_terminals_show_the_viewport() {
    let missing: Vec<&str> = ["Xvfb", "xwd"].into_iter().filter(|t| !which(t)).collect();
    if !missing.is_empty() {
        eprintln!(
            "skipped: {} not installed (apt-get install xterm xvfb x11-apps)",
            missing.join(", ")
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("rayterm-terminals-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut xvfb_kill = Kill(Vec::new());
    // Xvfb picks a free display and says which on the pipe.
    let mut xvfb = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "800x600x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut pipe = xvfb.stdout.take().unwrap();
    xvfb_kill.0.push(xvfb);
    let mut number = String::new();
    let mut byte = [0u8; 1];
    while pipe.read(&mut byte).unwrap_or(0) == 1 && byte[0] != b'\n' {
        number.push(byte[0] as char);
    }
    assert!(!number.is_empty(), "Xvfb did not start");
    let display = format!(":{}", number.trim());
    let mut failed = Vec::new();
    for case in CASES {
        let program = (case.command)(&dir).get_program().to_owned();
        if !which(&program.to_string_lossy()) {
            eprintln!(
                "{}: skipped, {} not installed",
                case.name,
                program.to_string_lossy()
            );
            continue;
        }
        match in_terminal(&display, &dir, case) {
            Err(e) => failed.push(format!("{}: {e}", case.name)),
            Ok(best) => {
                eprintln!(
                    "{}: mean difference {best:.2} levels per channel (bound {})",
                    case.name, case.bound
                );
                if best >= case.bound {
                    failed.push(format!("{}: mean difference {best:.2}", case.name));
                }
            }
        }
    }
    drop(xvfb_kill);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failed.is_empty(), "{failed:?}");
}

/// Runs rayterm in the case's terminal on `display` until the viewport's
/// mean difference from the picture settles below the bound (or
/// [`PATIENCE`] passes); returns the last difference.
fn in_terminal(display: &str, dir: &Path, case: &Case) -> Result<f64, String> {
    let log: PathBuf = dir.join("terminal.log");
    let _ = std::fs::remove_file(&log);
    let child = (case.command)(&log)
        .env("DISPLAY", display)
        .env_remove("TMUX")
        .env_remove("TERM_PROGRAM")
        .env_remove("LC_TERMINAL")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| e.to_string())?;
    let kill = Kill(vec![child]);
    let start = Instant::now();
    let shot_path = dir.join("shot.xwd");
    // The cells' size from the window's: the terminal's font decides it.
    let (mut cell, mut picture) = ((0, 0), None);
    let (mut best, mut last) = (f64::INFINITY, f64::NAN);
    while start.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(300));
        let Some(shot) = screenshot(display, &shot_path) else {
            continue;
        };
        let now = (shot.w as u32 / COLS as u32, shot.h as u32 / ROWS as u32);
        if picture.is_none() || now != cell {
            cell = now;
            picture = Some(expected(case.protocol, cell));
        }
        let e = picture.as_ref().unwrap();
        // A border around the cells: the best of a few offsets.
        best = (0..4)
            .flat_map(|dy| (0..4).map(move |dx| (dx, dy)))
            .map(|off| difference(&shot, e, cell, off))
            .fold(f64::INFINITY, f64::min);
        // Settled: the same twice, within the bound.
        if best < case.bound && best == last {
            break;
        }
        last = best;
    }
    drop(kill);
    if let Some(marker) = case.marker {
        let written = std::fs::read(&log).unwrap_or_default();
        if !written.windows(marker.len()).any(|s| s == marker) {
            return Err("rayterm wrote no image".into());
        }
    }
    if best.is_infinite() {
        return Err(format!(
            "no window within {PATIENCE:?}, or smaller than the view"
        ));
    }
    Ok(best)
}
