//! In a real terminal: rayterm runs in `xterm -ti vt340` on a virtual X
//! display (Xvfb), finds sixel by asking, and the viewport in a screenshot
//! (xwd) is compared with the picture rayterm renders for it. Skips, saying
//! so, where xterm, Xvfb or xwd are not installed (`apt-get install xterm
//! xvfb x11-apps`).

use std::io::Read;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use ratatui::layout::Rect;
use rayterm::render::{Feature, Features, SceneRequest, Session};
use rayterm::tui::app::App;
use rayterm::tui::color::ColorMode;
use rayterm::tui::graphics::{PixelMode, Protocol};

/// The terminal: cells of xterm's `6x13` font.
const COLS: u16 = 100;
const ROWS: u16 = 30;
const CELL: (u32, u32) = (6, 13);
/// The bound on the mean difference per channel (0-255) between the
/// screenshot's viewport and the picture: the palette and its dithering
/// cost a few levels.
const BOUND: f64 = 6.0;
/// With 16 colour registers: dithering between fewer colours. (Half
/// blocks in place of the images measure about 22.)
const BOUND_16: f64 = 8.0;
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
/// with sixel and cells of [`CELL`]: its pixels, and where it lies in
/// cells.
fn expected(features: Features) -> (Vec<[u8; 3]>, u32, u32, Rect) {
    let req = SceneRequest {
        features,
        ..SceneRequest::new("cornell")
    };
    let (session, warnings) = Session::open(&req).unwrap();
    let mut app = App::new(session, warnings, ColorMode::Truecolor, None).unwrap();
    app.pixels = Some(PixelMode {
        protocol: Protocol::Sixel,
        cell: CELL,
        colours: 256,
        passthrough: false,
    });
    app.update(Rect::new(0, 0, COLS, ROWS));
    assert!(app.wait_frame(PATIENCE).unwrap(), "no pass");
    assert!(
        app.current_frame().unwrap().done,
        "one pass is the whole picture"
    );
    let pic = rayterm::tui::widgets::picture(&app).unwrap();
    (pic.px, pic.w, pic.h, app.layout.image)
}

/// The mean difference per channel between the picture and the screen
/// at `area` (cells), the screen shifted by `off` pixels (xterm's border).
fn difference(
    shot: &Shot,
    pic: &[[u8; 3]],
    (w, h): (u32, u32),
    area: Rect,
    off: (usize, usize),
) -> f64 {
    let (x0, y0) = (
        area.x as usize * CELL.0 as usize + off.0,
        area.y as usize * CELL.1 as usize + off.1,
    );
    let (sw, sh) = (
        area.width as usize * CELL.0 as usize,
        area.height as usize * CELL.1 as usize,
    );
    let mut sum = 0u64;
    if x0 + sw > shot.w || y0 + sh > shot.h {
        return f64::INFINITY;
    }
    for y in 0..sh {
        for x in 0..sw {
            let s = shot.px[(y0 + y) * shot.w + x0 + x];
            let p = pic[(y * h as usize / sh) * w as usize + x * w as usize / sw];
            sum += (0..3).map(|c| s[c].abs_diff(p[c]) as u64).sum::<u64>();
        }
    }
    sum as f64 / (sw * sh * 3) as f64
}

#[test]
fn sixel_in_xterm_shows_the_viewport() {
    let missing: Vec<&str> = ["xterm", "Xvfb", "xwd"]
        .into_iter()
        .filter(|t| !which(t))
        .collect();
    if !missing.is_empty() {
        eprintln!(
            "skipped: {} not installed (apt-get install xterm xvfb x11-apps)",
            missing.join(", ")
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("rayterm-xterm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut kill = Kill(Vec::new());
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
    kill.0.push(xvfb);
    let mut number = String::new();
    let mut byte = [0u8; 1];
    while pipe.read(&mut byte).unwrap_or(0) == 1 && byte[0] != b'\n' {
        number.push(byte[0] as char);
    }
    assert!(!number.is_empty(), "Xvfb did not start");
    let display = format!(":{}", number.trim());
    // One pass is the whole picture without supersampling, so the screen
    // settles on the picture computed here.
    let expected = expected(Features::all().without(&[Feature::Supersampling]));
    let (_, w, h, area) = &expected;
    assert_eq!(
        (*w, *h),
        (area.width as u32 * CELL.0, area.height as u32 * CELL.1)
    );
    // xterm's default colour registers (1024, of which 256 are used), and
    // the 16 of a real VT340.
    let mut failed = Vec::new();
    for (registers, bound) in [(None, BOUND), (Some(16), BOUND_16)] {
        let (best, sixel) = in_xterm(&display, &dir, registers, &expected, bound);
        let name = registers.map_or("default".to_string(), |n| n.to_string());
        eprintln!(
            "xterm -ti vt340, {name} colour registers: viewport {w}x{h} px, \
             mean difference {best:.2} levels per channel (bound {bound})"
        );
        if !sixel {
            failed.push(format!("{name} registers: rayterm wrote no sixel image"));
        }
        if best >= bound {
            failed.push(format!("{name} registers: mean difference {best:.2}"));
        }
    }
    drop(kill);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failed.is_empty(), "{failed:?}");
}

/// Runs rayterm in xterm on `display` until the viewport's mean difference
/// from the picture is below `bound` (or [`PATIENCE`] passes); returns the
/// last difference and whether rayterm wrote sixel images.
fn in_xterm(
    display: &str,
    dir: &std::path::Path,
    registers: Option<u32>,
    (pic, w, h, area): &(Vec<[u8; 3]>, u32, u32, Rect),
    bound: f64,
) -> (f64, bool) {
    let log: PathBuf = dir.join("xterm.log");
    let _ = std::fs::remove_file(&log);
    let mut xterm = Command::new("xterm");
    xterm
        .env("DISPLAY", display)
        .env_remove("TMUX")
        .args([
            "-ti",
            "vt340",
            "-fn",
            "6x13",
            "-geometry",
            &format!("{COLS}x{ROWS}+0+0"),
        ])
        .args(["-l", "-lf"])
        .arg(&log);
    if let Some(n) = registers {
        xterm.args(["-xrm", &format!("XTerm*numColorRegisters: {n}")]);
    }
    let child = xterm
        .args([
            "-e",
            env!("CARGO_BIN_EXE_rayterm"),
            "cornell",
            "--no",
            "supersampling",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let kill = Kill(vec![child]);
    let start = Instant::now();
    let shot_path = dir.join("shot.xwd");
    let mut best = f64::INFINITY;
    while start.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(500));
        let ok = Command::new("xwd")
            .env("DISPLAY", display)
            .args(["-root", "-silent", "-out"])
            .arg(&shot_path)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            continue;
        }
        let shot = parse_xwd(&std::fs::read(&shot_path).unwrap()).unwrap();
        // xterm's inner border: the best of a few offsets.
        best = (0..4)
            .flat_map(|dy| (0..4).map(move |dx| (dx, dy)))
            .map(|off| difference(&shot, pic, (*w, *h), *area, off))
            .fold(f64::INFINITY, f64::min);
        if best < bound {
            break;
        }
    }
    drop(kill);
    let written = std::fs::read(&log).unwrap_or_default();
    (best, written.windows(8).any(|s| s == b"\x1bP0;1;0q"))
}
