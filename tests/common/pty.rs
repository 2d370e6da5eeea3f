//! Pseudo-terminals for tests that run the TUI as a user would.

use std::os::fd::{FromRawFd, OwnedFd};

/// A pty pair of `cols` x `rows`: (master, slave).
pub fn pty(cols: u16, rows: u16) -> (OwnedFd, OwnedFd) {
    let (mut master, mut slave) = (0, 0);
    let size = libc::winsize {
        ws_row: rows,
        ws_col: cols,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    // SAFETY: openpty writes two descriptors it opened; the null pointers
    // ask for no name and default terminal settings.
    let r = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            &size,
        )
    };
    assert_eq!(r, 0, "openpty failed");
    // Close-on-exec, so that programs other tests start at the same time do
    // not inherit (and keep open) this terminal.
    for fd in [master, slave] {
        // SAFETY: fcntl on the descriptors openpty just returned.
        unsafe { libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC) };
    }
    // SAFETY: both descriptors are fresh and owned here alone.
    unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) }
}

#[allow(dead_code)]
pub fn canonical(fd: &OwnedFd) -> bool {
    use std::os::fd::AsRawFd;
    // SAFETY: tcgetattr fills the zeroed struct for a valid terminal fd.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    assert_eq!(unsafe { libc::tcgetattr(fd.as_raw_fd(), &mut t) }, 0);
    t.c_lflag & libc::ICANON != 0
}

/// Runs `rayterm ARGS` in `dir` on a `cols` x `rows` pseudo-terminal, waits
/// until it has drawn `wait_for` (or `patience` passes), types `keys`, and
/// returns its exit status (None if it did not end within `patience` after
/// the keys) and everything it wrote.
#[allow(dead_code)]
pub fn run_tui(
    dir: &std::path::Path,
    args: &[&str],
    (cols, rows): (u16, u16),
    wait_for: &[u8],
    keys: &[u8],
    patience: std::time::Duration,
) -> (Option<std::process::ExitStatus>, Vec<u8>) {
    use std::io::Write;
    use std::time::Instant;
    let (master, slave) = pty(cols, rows);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(args)
        .current_dir(dir)
        .env("TERM", "xterm-256color")
        .stdin(slave.try_clone().unwrap())
        .stdout(slave.try_clone().unwrap())
        .stderr(slave.try_clone().unwrap())
        .spawn()
        .unwrap();
    let mut writer = std::fs::File::from(master.try_clone().unwrap());
    let rx = reader(master);
    let mut out = Vec::new();
    let deadline = Instant::now() + patience;
    let seen = |out: &[u8]| out.windows(wait_for.len()).any(|w| w == wait_for);
    while !seen(&out) && Instant::now() < deadline {
        if let Ok(b) = rx.recv_timeout(std::time::Duration::from_millis(50)) {
            out.extend(b);
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
    }
    let _ = writer.write_all(keys);
    let deadline = Instant::now() + patience;
    let status = loop {
        while let Ok(b) = rx.try_recv() {
            out.extend(b);
        }
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    while let Ok(b) = rx.recv_timeout(std::time::Duration::from_millis(100)) {
        out.extend(b);
    }
    (status, out)
}

/// Everything written to the terminal whose master side is `master`, read
/// on a thread as it comes, so the program never blocks on a full pty.
#[allow(dead_code)]
pub fn reader(master: OwnedFd) -> std::sync::mpsc::Receiver<Vec<u8>> {
    use std::io::Read;
    let mut reader = std::fs::File::from(master);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 1 << 16];
        while let Ok(n) = reader.read(&mut buf) {
            if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    rx
}
