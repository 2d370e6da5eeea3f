//! Files on disk for loader tests: a temporary folder removed on drop,
//! special files (FIFOs, symbolic links), and the binary run with a
//! deadline, so that a regression shows as a failure and never as a hang.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Longer than any load or small render takes; only a hang reaches it.
pub const DEADLINE: Duration = Duration::from_secs(30);

/// A folder under the system's temporary directory, removed on drop.
pub struct Dir(pub PathBuf);

impl Dir {
    pub fn new(name: &str) -> Self {
        let p = std::env::temp_dir().join(format!("rayterm-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        Dir(p)
    }

    pub fn path(&self, rel: &str) -> PathBuf {
        self.0.join(rel)
    }

    /// Writes `bytes` to `rel` (folders created); returns the path as a string.
    pub fn write(&self, rel: &str, bytes: impl AsRef<[u8]>) -> String {
        let p = self.path(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, bytes).unwrap();
        p.to_str().unwrap().to_string()
    }

    /// A FIFO at `rel`, or `None` (with a message) where `mkfifo` is missing.
    pub fn fifo(&self, rel: &str) -> Option<String> {
        let p = self.path(rel);
        let ok = Command::new("mkfifo")
            .arg(&p)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("skipping a FIFO case: mkfifo is not available");
            return None;
        }
        Some(p.to_str().unwrap().to_string())
    }

    /// A symbolic link at `rel` pointing to `target`.
    pub fn link(&self, rel: &str, target: impl AsRef<Path>) -> String {
        let p = self.path(rel);
        std::os::unix::fs::symlink(target, &p).unwrap();
        p.to_str().unwrap().to_string()
    }

    /// A sparse file of `len` bytes (no disk space used).
    pub fn sparse(&self, rel: &str, len: u64) -> String {
        let p = self.path(rel);
        std::fs::File::create(&p).unwrap().set_len(len).unwrap();
        p.to_str().unwrap().to_string()
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `f` on its own thread: panics with a clear message when it panics
/// or is still running at the [`DEADLINE`].
pub fn within_deadline<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(DEADLINE) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: still running after {DEADLINE:?}"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: panicked"),
    }
}

/// What the binary did.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    pub fn ok(&self) -> bool {
        self.code == Some(0)
    }
}

/// Runs the built binary in `cwd` with `args`, killing it at the deadline
/// (the test then fails); output goes through files, so a full pipe
/// cannot stall it.
pub fn rayterm(cwd: &Path, args: &[&str]) -> Run {
    run(Command::new(env!("CARGO_BIN_EXE_rayterm")), cwd, args)
}

/// [`rayterm`] with its address space limited to `bytes` (`ulimit -v`).
pub fn rayterm_within(bytes: u64, cwd: &Path, args: &[&str]) -> Run {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rayterm"));
    let limit = libc::rlimit {
        rlim_cur: bytes,
        rlim_max: bytes,
    };
    // SAFETY: setrlimit is async-signal-safe, as the child's code between
    // fork and exec must be.
    unsafe {
        cmd.pre_exec(move || match libc::setrlimit(libc::RLIMIT_AS, &limit) {
            0 => Ok(()),
            _ => Err(std::io::Error::last_os_error()),
        });
    }
    run(cmd, cwd, args)
}

fn run(mut cmd: Command, cwd: &Path, args: &[&str]) -> Run {
    let out = output_file("stdout");
    let err = output_file("stderr");
    let mut child = cmd
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("run rayterm");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > DEADLINE {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "rayterm {args:?} in {}: still running after {DEADLINE:?}",
                cwd.display()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let read = |p: &Path| {
        let s = String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
        let _ = std::fs::remove_file(p);
        s
    };
    Run {
        code: status.code(),
        stdout: read(&out),
        stderr: read(&err),
    }
}

/// A fresh file name for one run's output.
fn output_file(what: &str) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "rayterm-run-{}-{}-{what}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ))
}
