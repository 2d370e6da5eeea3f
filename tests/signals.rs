//! The TUI in a real pseudo-terminal, ended by a signal: the terminal must
//! come back exactly as `q` leaves it (alternate screen left, cursor shown,
//! mouse capture off, canonical mode on), and the exit status says which
//! signal it was.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;
use pty::{canonical, pty};

fn ended_by(signal: i32) {
    let (master, slave) = pty(100, 30);
    assert!(canonical(&slave));
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["tui", "cornell"])
        .env("TERM", "xterm-256color")
        .stdin(Stdio::from(slave.try_clone().unwrap()))
        .stdout(Stdio::from(slave.try_clone().unwrap()))
        .stderr(Stdio::from(slave.try_clone().unwrap()))
        .spawn()
        .unwrap();
    // Everything the TUI writes, read as it comes so it never blocks.
    let rx = pty::reader(master);
    let mut out = Vec::new();
    let collect = |until: Instant, out: &mut Vec<u8>| {
        while let Ok(b) = rx.recv_timeout(until.saturating_duration_since(Instant::now())) {
            out.extend(b);
        }
    };
    // Wait until it has entered the alternate screen and drawn a frame.
    let deadline = Instant::now() + Duration::from_secs(20);
    while !out.windows(8).any(|w| w == b"\x1b[?1049h") && Instant::now() < deadline {
        collect(Instant::now() + Duration::from_millis(100), &mut out);
    }
    assert!(!canonical(&slave), "the TUI did not enter raw mode");
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: sending a signal to the child we started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(
            Instant::now() < deadline,
            "the TUI did not quit on signal {signal}"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    collect(Instant::now() + Duration::from_millis(300), &mut out);
    let tail = &out[out.len().saturating_sub(400)..];
    let has = |seq: &[u8]| tail.windows(seq.len()).any(|w| w == seq);
    assert!(has(b"\x1b[?1049l"), "alternate screen not left: {tail:?}");
    assert!(has(b"\x1b[?25h"), "cursor not shown again: {tail:?}");
    assert!(has(b"\x1b[?1000l"), "mouse capture not disabled: {tail:?}");
    assert!(canonical(&slave), "the terminal was left in raw mode");
    assert_eq!(status.code(), Some(128 + signal), "{status:?}");
}

#[test]
fn sigterm_restores_the_terminal() {
    ended_by(libc::SIGTERM);
}

#[test]
fn sighup_restores_the_terminal() {
    ended_by(libc::SIGHUP);
}

#[test]
fn sigint_from_outside_restores_the_terminal() {
    ended_by(libc::SIGINT);
}

/// The terminal closes under the TUI (the ssh connection drops, the tmux
/// pane is killed) without a signal reaching it: it must notice and end,
/// not spin on a dead terminal.
#[test]
fn a_closed_terminal_ends_the_tui() {
    let (master, slave) = pty(100, 30);
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["tui", "cornell"])
        .env("TERM", "xterm-256color")
        .stdin(Stdio::from(slave.try_clone().unwrap()))
        .stdout(Stdio::from(slave.try_clone().unwrap()))
        .stderr(Stdio::from(slave))
        .spawn()
        .unwrap();
    // Read here rather than on a thread, so that no copy of the master
    // outlives the hangup.
    let mut term = std::fs::File::from(master);
    let mut out: Vec<u8> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !out.windows(8).any(|w| w == b"\x1b[?1049h") && Instant::now() < deadline {
        let mut fds = libc::pollfd {
            fd: std::os::fd::AsRawFd::as_raw_fd(&term),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd for a descriptor we own.
        if unsafe { libc::poll(&mut fds, 1, 100) } > 0 {
            let mut buf = [0u8; 1 << 16];
            let n = std::io::Read::read(&mut term, &mut buf).unwrap();
            out.extend(&buf[..n]);
        }
    }
    assert!(Instant::now() < deadline, "the TUI never started");
    // Hang up the line: the last descriptor of the master side closed.
    drop(term);
    let deadline = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the TUI kept running after its terminal closed");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.code().is_some(), "{status:?}");
}

/// A terminal that says it cannot move the cursor gets a clear refusal
/// and not one escape sequence.
#[test]
fn a_dumb_terminal_is_refused() {
    let (master, slave) = pty(80, 24);
    let rx = pty::reader(master);
    let status = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["tui", "cornell"])
        .env("TERM", "dumb")
        .stdin(slave.try_clone().unwrap())
        .stdout(slave.try_clone().unwrap())
        .stderr(slave.try_clone().unwrap())
        .status()
        .unwrap();
    drop(slave);
    let mut out = Vec::new();
    while let Ok(b) = rx.recv_timeout(Duration::from_millis(300)) {
        out.extend(b);
    }
    let text = String::from_utf8_lossy(&out);
    assert_eq!(status.code(), Some(1), "{text}");
    assert!(text.contains("TERM=dumb"), "{text}");
    assert!(!out.contains(&0x1b), "{text:?}");
}
