//! `--graphics` in a pseudo-terminal that never answers a query: auto
//! falls back to block symbols and says why; a protocol named on the
//! command line is used anyway, and the images go with the TUI on `q`.

use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;

const PATIENCE: Duration = Duration::from_secs(60);

fn run(args: &[&str], wait_for: &[u8]) -> (Option<std::process::ExitStatus>, Vec<u8>) {
    let dir = std::env::temp_dir();
    pty::run_tui(&dir, args, (120, 40), wait_for, b"q", PATIENCE)
}

fn contains(out: &[u8], needle: &[u8]) -> bool {
    out.windows(needle.len()).any(|w| w == needle)
}

#[test]
fn auto_falls_back_to_symbols_when_nothing_answers() {
    let start = Instant::now();
    let (status, out) = run(&["cornell"], b"the terminal answered no query");
    let waited = start.elapsed();
    eprintln!("fallback seen after {waited:?}");
    // The wait for answers is a second; loading and the first frame are
    // quick.
    assert!(waited < Duration::from_secs(20), "{waited:?}");
    // The colours' hint comes first, and the status line wraps before
    // "symbols".
    assert!(
        contains(&out, b"symbols: the terminal answered no query"),
        "{}",
        String::from_utf8_lossy(&out)
    );
    // The queries went out, and no image followed them.
    assert!(contains(&out, b"\x1b_Gi=31,s=1,v=1,a=q"));
    assert!(!contains(&out, b"\x1bP0;1;0q") && !contains(&out, b"\x1b_Ga=T"));
    // So did the glyph probes (`--symbols auto` by default); unanswered,
    // they leave half blocks, without a word about symbols.
    assert!(contains(&out, b"\x1b[>0q") && contains(&out, "\u{1CD00}\x1b[6n".as_bytes()));
    let text = String::from_utf8_lossy(&out);
    let count = |r: std::ops::RangeInclusive<char>| text.chars().filter(|c| r.contains(c)).count();
    assert_eq!(
        count('\u{1FB00}'..='\u{1FB3B}'),
        1,
        "sextants beyond the probe's"
    );
    assert_eq!(
        count('\u{1CD00}'..='\u{1CDE5}'),
        1,
        "octants beyond the probe's"
    );
    assert!(text.contains("half") && !text.contains("show as boxes"));
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
    assert!(contains(&out, b"\x1b[?1049l"), "the screen is restored");
}

#[test]
fn octants_asked_of_a_terminal_that_says_nothing_are_kept_and_the_risk_said() {
    let (status, out) = run(
        &["cornell", "--graphics", "symbols", "--symbols", "octant"],
        b"unless the font has them",
    );
    assert!(
        contains(
            &out,
            b"octants show as boxes or blanks unless the font has them"
        ),
        "{}",
        String::from_utf8_lossy(&out)
    );
    assert!(contains(&out, "\u{1CD00}".as_bytes()) && contains(&out, b"octants"));
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
}

#[test]
fn a_protocol_named_is_used_and_its_images_go_on_quitting() {
    // Sixel: images of the bands, cells of an assumed size.
    let (status, out) = run(&["cornell", "--graphics", "sixel"], b"\x1bP0;1;0q");
    assert!(contains(&out, b"\x1bP0;1;0q\"1;1;"), "no sixel image");
    assert!(contains(&out, b"cells 8x16 px (assumed"));
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
    // Kitty: its images outlive the text, so they are deleted on leaving.
    let (status, out) = run(&["cornell", "--graphics", "kitty"], b"\x1b_Ga=T");
    assert!(contains(&out, b"\x1b_Ga=T,f=24,o=z"), "no kitty image");
    let leave = out
        .windows(8)
        .rposition(|w| w == b"\x1b[?1049l")
        .expect("the screen is restored");
    assert!(
        contains(&out[..leave], b"\x1b_Ga=d,d=I"),
        "the images are deleted before leaving"
    );
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
}

/// A terminal played by the test: rayterm on a pseudo-terminal whose
/// output is read (at `rate` bytes per second, if given, as through a slow
/// link) and whose queries are answered by `answer`.
struct Term {
    child: std::process::Child,
    master: std::fs::File,
    out: Vec<u8>,
    /// Output before this was scanned for queries.
    scanned: usize,
    answer: fn(&[u8]) -> &'static [u8],
    rate: Option<f64>,
    /// Bytes that may be read now, and when that was reckoned.
    credit: f64,
    reckoned: Instant,
}

/// The queries rayterm sends, the pacing request first.
const QUERIES: [&[u8]; 4] = [b"\x1b[6n", b"\x1b[c", b"a=q,", b"\x1b[16t"];

impl Term {
    fn start(args: &[&str], (cols, rows): (u16, u16), answer: fn(&[u8]) -> &'static [u8]) -> Term {
        let (master, slave) = pty::pty(cols, rows);
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(args)
            .current_dir(std::env::temp_dir())
            .env("TERM", "xterm-256color")
            .env_remove("TMUX")
            .stdin(slave.try_clone().unwrap())
            .stdout(slave.try_clone().unwrap())
            .stderr(slave)
            .spawn()
            .unwrap();
        Term {
            child,
            master: std::fs::File::from(master),
            out: Vec::new(),
            scanned: 0,
            answer,
            rate: None,
            credit: 0.0,
            reckoned: Instant::now(),
        }
    }

    /// Reads what the link lets through for up to 10 ms.
    fn read(&mut self) {
        use std::io::Read;
        use std::os::fd::AsRawFd;
        let now = Instant::now();
        let most = match self.rate {
            Some(rate) => {
                let since = now.duration_since(self.reckoned).as_secs_f64();
                self.credit = (self.credit + since * rate).min(4096.0);
                self.credit as usize
            }
            None => 1 << 16,
        };
        self.reckoned = now;
        let mut fds = libc::pollfd {
            fd: self.master.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd for a descriptor we own.
        let ready = unsafe { libc::poll(&mut fds, 1, 10) } > 0;
        if !ready || most == 0 {
            if most == 0 {
                std::thread::sleep(Duration::from_millis(5));
            }
            return;
        }
        let mut buf = vec![0u8; most];
        if let Ok(n) = self.master.read(&mut buf) {
            self.out.extend_from_slice(&buf[..n]);
            self.credit -= n as f64;
        }
    }

    /// Reads and answers for `time`, or until `until` holds of the output.
    fn run_until(&mut self, time: Duration, until: impl Fn(&[u8]) -> bool) -> bool {
        use std::io::Write;
        let end = Instant::now() + time;
        while Instant::now() < end {
            if until(&self.out) {
                return true;
            }
            self.read();
            // Answers in the order the queries came.
            let from = self.scanned.saturating_sub(7);
            let hay = &self.out[from..];
            let mut found: Vec<(usize, &[u8])> = Vec::new();
            for q in QUERIES {
                for i in 0..hay.len().saturating_sub(q.len() - 1) {
                    if hay[i..].starts_with(q) && from + i + q.len() > self.scanned {
                        found.push((i, q));
                    }
                }
            }
            found.sort();
            for (_, q) in found {
                let _ = self.master.write_all((self.answer)(q));
            }
            self.scanned = self.out.len();
        }
        until(&self.out)
    }

    fn resize(&self, cols: u16, rows: u16) {
        use std::os::fd::AsRawFd;
        let size = libc::winsize {
            ws_row: rows,
            ws_col: cols,
            ws_xpixel: 0,
            ws_ypixel: 0,
        };
        // SAFETY: TIOCSWINSZ reads one winsize from a valid pointer.
        unsafe { libc::ioctl(self.master.as_raw_fd(), libc::TIOCSWINSZ, &size) };
    }

    /// Types `q` and waits for rayterm to end: its exit code and output.
    fn quit(mut self) -> (Option<i32>, Vec<u8>) {
        use std::io::Write;
        let _ = self.master.write_all(b"q");
        let end = Instant::now() + PATIENCE;
        let status = loop {
            self.run_until(Duration::from_millis(20), |_| false);
            if let Some(s) = self.child.try_wait().unwrap() {
                break s.code();
            }
            if Instant::now() > end {
                let _ = self.child.kill();
                let _ = self.child.wait();
                panic!(
                    "rayterm did not quit: {}",
                    String::from_utf8_lossy(&self.out)
                );
            }
        };
        self.run_until(Duration::from_millis(200), |_| false);
        (status, self.out)
    }
}

/// A kitty terminal with cells of 8x16 pixels.
fn kitty(q: &[u8]) -> &'static [u8] {
    match q {
        b"\x1b[6n" => b"\x1b[1;1R",
        b"a=q," => b"\x1b_Gi=31;OK\x1b\\",
        b"\x1b[16t" => b"\x1b[6;16;8t",
        b"\x1b[c" => b"\x1b[?62;22c",
        _ => b"",
    }
}

/// Every kitty image sent is deleted after its last transmission, every
/// transmission is finished, and then the screen is restored.
fn no_image_left(out: &[u8]) {
    let leave = out
        .windows(8)
        .rposition(|w| w == b"\x1b[?1049l")
        .expect("the screen is restored");
    let mut last_sent = std::collections::HashMap::new();
    let mut last_deleted = std::collections::HashMap::new();
    let mut open = false;
    let mut at = 0;
    while let Some(i) = out[at..leave].windows(3).position(|w| w == b"\x1b_G") {
        let start = at + i + 3;
        let end = start
            + out[start..]
                .iter()
                .position(|&c| c == b';' || c == 0x1b)
                .unwrap();
        let keys = String::from_utf8_lossy(&out[start..end]).into_owned();
        let id = keys
            .split(',')
            .find_map(|k| k.strip_prefix("i="))
            .map(String::from);
        if keys.contains("a=T") {
            last_sent.insert(id.clone().unwrap(), start);
        }
        if keys.contains("a=d") {
            last_deleted.insert(id.clone().unwrap(), start);
        }
        if keys.contains("m=1") {
            open = true;
        } else if keys.contains("m=0") {
            open = false;
        }
        at = end;
    }
    assert!(!open, "a transmission is left unfinished");
    assert!(!last_sent.is_empty(), "no image was sent");
    for (id, sent) in &last_sent {
        assert!(
            last_deleted.get(id).is_some_and(|d| d > sent),
            "image {id} is not deleted after it was last sent"
        );
    }
}

#[test]
fn resize_storms_leave_no_kitty_image_behind() {
    let mut t = Term::start(&["cornell", "--graphics", "auto"], (100, 30), kitty);
    assert!(
        t.run_until(PATIENCE, |o| contains(o, b"\x1b_Ga=T")),
        "no image"
    );
    assert!(contains(&t.out, b"kitty graphics, cells 8x16 px"));
    // Sizes from 1x1 to wider than the pixel budget, faster than frames.
    let mut x = 12345u32;
    for _ in 0..150 {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
        t.resize(1 + (x >> 8) as u16 % 300, 1 + (x >> 20) as u16 % 90);
        t.run_until(Duration::from_millis(3), |_| false);
    }
    t.resize(90, 28);
    let before = t.out.len();
    assert!(
        t.run_until(PATIENCE, |o| contains(&o[before..], b"\x1b_Ga=T")),
        "no image after the storm"
    );
    let (status, out) = t.quit();
    assert_eq!(status, Some(0));
    no_image_left(&out);
}

#[test]
fn quitting_while_images_crawl_through_a_slow_link_leaves_none() {
    let mut t = Term::start(&["env", "--graphics", "kitty"], (160, 48), kitty);
    t.rate = Some(32_000.0);
    // Quit in the middle of an image's chunks.
    assert!(t.run_until(PATIENCE, |o| contains(o, b"\x1b_Gm=1;")));
    let (status, out) = t.quit();
    assert_eq!(status, Some(0));
    no_image_left(&out);
}

/// The widths (`s=`) of the kitty images transmitted, in order.
fn kitty_widths(out: &[u8]) -> Vec<u32> {
    let text = String::from_utf8_lossy(out);
    text.split("\x1b_Ga=T,")
        .skip(1)
        .filter_map(|t| {
            let keys = t.split(';').next()?;
            keys.split(',')
                .find_map(|k| k.strip_prefix("s=")?.parse().ok())
        })
        .collect()
}

#[test]
fn a_slow_link_gets_a_coarse_picture_first_then_the_sharp_one() {
    let mut t = Term::start(&["cornell", "--graphics", "kitty"], (80, 24), kitty);
    t.rate = Some(32_000.0);
    // Every band goes coarse first (a fraction of the width), then sharp.
    let sharp_follows = |o: &[u8]| {
        let widths = kitty_widths(o);
        let Some(&coarse) = widths.first() else {
            return false;
        };
        let bands = widths.iter().take_while(|&&w| w == coarse).count();
        widths.iter().filter(|&&w| w >= 2 * coarse).count() >= bands
    };
    assert!(t.run_until(PATIENCE, sharp_follows), "no sharp picture");
    let (status, out) = t.quit();
    assert_eq!(status, Some(0));
    no_image_left(&out);
}

#[test]
fn garbage_answers_and_huge_windows_neither_hang_nor_abort() {
    // A cell of 65535 x 65535 pixels (sixel images of terapixels, were it
    // believed), junk around, then DA1 with sixel.
    fn junk(q: &[u8]) -> &'static [u8] {
        match q {
            b"\x1b[c" => {
                b"\x1b[6;65535;65535t\x1b_Gi=31;EINVAL\x1b\\\x1bP1+r\x1b\\\x1b[?1;0;0S\x1b[?62;4c"
            }
            _ => b"",
        }
    }
    let mut t = Term::start(&["cornell"], (100, 30), junk);
    assert!(
        t.run_until(PATIENCE, |o| contains(o, b"\x1bP0;1;0q")),
        "no sixel image: {}",
        String::from_utf8_lossy(&t.out)
    );
    assert!(contains(&t.out, b"sixel, cells 8x16 px (assumed"));
    let (status, out) = t.quit();
    assert_eq!(status, Some(0));
    assert!(contains(&out, b"\x1b[?1049l"));
    // The largest window a terminal can report, and the smallest.
    for size in [(u16::MAX, u16::MAX), (1, 1)] {
        let mut t = Term::start(&["cornell", "--graphics", "kitty"], size, kitty);
        assert!(t.run_until(PATIENCE, |o| contains(o, b"\x1b[?1049h")));
        t.run_until(Duration::from_millis(500), |_| false);
        let (status, out) = t.quit();
        assert_eq!(
            status,
            Some(0),
            "{size:?}: {}",
            String::from_utf8_lossy(&out)
        );
        assert!(contains(&out, b"\x1b[?1049l"));
    }
}

#[test]
fn quit_typed_while_the_terminal_is_asked_ends_the_wait() {
    // A terminal that answers nothing but the pacing requests: the wait
    // for answers would last a second; `q` typed during it ends it, and
    // rayterm leaves before drawing anything.
    fn silent(q: &[u8]) -> &'static [u8] {
        match q {
            b"\x1b[6n" => b"\x1b[1;1R",
            _ => b"",
        }
    }
    let mut t = Term::start(&["cornell"], (100, 30), silent);
    assert!(t.run_until(PATIENCE, |o| contains(o, b"\x1b[c")));
    let (status, out) = t.quit();
    assert_eq!(status, Some(0));
    assert!(contains(&out, b"\x1b[?1049l"));
    assert!(
        !contains(&out, b"block symbols:") && !contains(&out, b"cornell \xc2\xb7"),
        "a frame was drawn: {}",
        String::from_utf8_lossy(&out)
    );
}
