//! The TUI in a real pseudo-terminal, ended by a signal: the terminal must
//! come back exactly as `q` leaves it (alternate screen left, cursor shown,
//! mouse capture off, canonical mode on), and the exit status says which
//! signal it was. Stopped by one (SIGTSTP, Ctrl-Z), it gives the terminal
//! back the same way first, and takes it again on SIGCONT.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;
use pty::{canonical, pty};

/// The TUI ended by `signal`, sent `times` times `gap` apart.
fn ended_by(signal: i32, times: usize, gap: Duration) {
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
    for i in 0..times {
        if i > 0 {
            std::thread::sleep(gap);
        }
        // SAFETY: sending a signal to the child we started.
        assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
    }
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
    ended_by(libc::SIGTERM, 1, Duration::ZERO);
}

/// A wrapper that forwards the terminal's signal (`timeout`), or an
/// impatient user: the repeat is the same request, and the terminal is
/// restored all the same.
#[test]
fn a_signal_repeated_at_once_restores_the_terminal() {
    // Delivered apart, not merged into one pending signal.
    ended_by(libc::SIGTERM, 2, Duration::from_millis(20));
    ended_by(libc::SIGINT, 3, Duration::from_millis(5));
}

#[test]
fn sighup_restores_the_terminal() {
    ended_by(libc::SIGHUP, 1, Duration::ZERO);
}

#[test]
fn sigint_from_outside_restores_the_terminal() {
    ended_by(libc::SIGINT, 1, Duration::ZERO);
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

/// The TUI as a shell's job: its own process group (the kernel drops a
/// stop aimed at a group no shell could continue), on a terminal played
/// by the test that answers the cursor position and DA1 requests. Killed
/// when dropped, stopped or not.
struct Job {
    child: std::process::Child,
    master: std::fs::File,
    slave: std::os::fd::OwnedFd,
    out: Vec<u8>,
    /// Output before this was scanned for requests.
    scanned: usize,
}

impl Job {
    fn start() -> Job {
        use std::os::unix::process::CommandExt;
        let (master, slave) = pty(100, 30);
        let child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(["tui", "cornell"])
            .env("TERM", "xterm-256color")
            // The colour question is asked at startup, and must not be again.
            .env_remove("COLORTERM")
            .env_remove("TMUX")
            .stdin(Stdio::from(slave.try_clone().unwrap()))
            .stdout(Stdio::from(slave.try_clone().unwrap()))
            .stderr(Stdio::from(slave.try_clone().unwrap()))
            .process_group(0)
            .spawn()
            .unwrap();
        Job {
            child,
            master: std::fs::File::from(master),
            slave,
            out: Vec::new(),
            scanned: 0,
        }
    }

    /// Reads and answers until `until` holds of the job (20 s at most).
    fn until(&mut self, what: &str, until: impl Fn(&mut Job) -> bool) {
        use std::io::{Read, Write};
        use std::os::fd::AsRawFd;
        let end = Instant::now() + Duration::from_secs(20);
        while !until(self) {
            assert!(
                Instant::now() < end,
                "{what}: {:?}",
                String::from_utf8_lossy(&self.out[self.out.len().saturating_sub(600)..])
            );
            let mut fds = libc::pollfd {
                fd: self.master.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            // SAFETY: one valid pollfd for a descriptor we own.
            if unsafe { libc::poll(&mut fds, 1, 10) } > 0 {
                let mut buf = [0u8; 1 << 16];
                if let Ok(n) = self.master.read(&mut buf) {
                    self.out.extend_from_slice(&buf[..n]);
                }
            }
            let from = self.scanned.saturating_sub(3);
            for i in from..self.out.len() {
                let rest = &self.out[i..];
                if rest.starts_with(b"\x1b[6n") && i + 4 > self.scanned {
                    let _ = self.master.write_all(b"\x1b[1;1R");
                } else if rest.starts_with(b"\x1b[c") && i + 3 > self.scanned {
                    let _ = self.master.write_all(b"\x1b[?62;22c");
                }
            }
            self.scanned = self.out.len();
        }
    }

    /// Whether the job is stopped, by SIGTSTP.
    fn stopped(&mut self) -> bool {
        let mut status = 0;
        // SAFETY: waitpid on our own child, which does not wait; it reaps
        // the child only if it ended, which fails the test.
        let pid = unsafe {
            libc::waitpid(
                self.child.id() as i32,
                &mut status,
                libc::WUNTRACED | libc::WNOHANG,
            )
        };
        assert!(
            pid == 0 || libc::WIFSTOPPED(status),
            "the TUI ended instead of stopping: {status:#x}"
        );
        pid > 0 && libc::WSTOPSIG(status) == libc::SIGTSTP
    }

    fn signal(&self, signal: i32) {
        // SAFETY: a signal to the child we started.
        assert_eq!(unsafe { libc::kill(self.child.id() as i32, signal) }, 0);
    }

    /// Stopped: the terminal is given back as `q` leaves it, and every
    /// request was answered and its answer read, so that none is left in
    /// the terminal for the shell.
    fn suspended(&mut self, how: &str) {
        use std::os::fd::AsRawFd;
        self.until(&format!("{how} did not stop the TUI"), Job::stopped);
        let settled = Instant::now() + Duration::from_millis(300);
        self.until("reading the last output", |_| Instant::now() >= settled);
        assert!(
            self.out.ends_with(b"\x1b[?1049l\x1b[?25h"),
            "{how}: the alternate screen was not left last: {:?}",
            String::from_utf8_lossy(&self.out[self.out.len().saturating_sub(200)..])
        );
        let last = |seq: &[u8]| self.out.windows(seq.len()).rposition(|w| w == seq);
        assert!(
            last(b"\x1b[?1000l") > last(b"\x1b[?1000h"),
            "{how}: mouse on"
        );
        assert!(canonical(&self.slave), "{how}: left in raw mode");
        let mut unread: libc::c_int = 0;
        // SAFETY: FIONREAD writes one int for a valid terminal descriptor.
        unsafe { libc::ioctl(self.slave.as_raw_fd(), libc::FIONREAD, &mut unread) };
        assert_eq!(unread, 0, "{how}: answers left for the shell");
    }

    /// Continued: the terminal is taken again and the screen drawn anew,
    /// without asking the startup questions again.
    fn continued(&mut self) {
        let mark = self.out.len();
        self.signal(libc::SIGCONT);
        let after = |j: &mut Job, seq: &[u8]| j.out[mark..].windows(seq.len()).any(|w| w == seq);
        self.until("SIGCONT did not bring the TUI back", |j| {
            after(j, b"\x1b[?1049h") && after(j, b"\x1b[2J") && after(j, b"quit")
        });
        assert!(!canonical(&self.slave), "not in raw mode again");
        assert!(after(self, b"\x1b[?1000h"), "mouse reporting not on again");
        assert!(
            !after(self, b"\x1b[c"),
            "the startup questions were asked again"
        );
    }
}

impl Drop for Job {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Ctrl-Z and SIGTSTP suspend the TUI as a shell's job control expects,
/// SIGCONT brings it back, and `q` still quits cleanly.
#[test]
fn sigtstp_and_ctrl_z_suspend_and_sigcont_resumes() {
    use std::io::Write;
    let mut job = Job::start();
    job.until("the TUI never drew", |j| {
        let has = |seq: &[u8]| j.out.windows(seq.len()).any(|w| w == seq);
        has(b"\x1b[?1049h") && has(b"quit")
    });
    assert!(
        job.out.windows(3).any(|w| w == b"\x1b[c"),
        "no startup question"
    );
    job.signal(libc::SIGTSTP);
    job.suspended("SIGTSTP");
    job.continued();
    job.master.write_all(b"\x1a").unwrap();
    job.suspended("Ctrl-Z");
    job.continued();
    job.master.write_all(b"q").unwrap();
    job.until("q did not quit", |j| j.child.try_wait().unwrap().is_some());
    let status = job.child.wait().unwrap();
    assert_eq!(status.code(), Some(0), "{status:?}");
    assert!(canonical(&job.slave), "left in raw mode");
}
