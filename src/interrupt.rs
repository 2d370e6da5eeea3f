//! SIGINT, SIGTERM and SIGHUP, turned into a flag the long-running parts
//! poll: a render stops within a sample and writes nothing, the TUI restores
//! the terminal and quits, exactly as on Ctrl-C or `q`. A second signal
//! while the first is being handled ends the process at once, still giving
//! the terminal back and removing a half-written output; one that follows
//! the first within [`REPEAT`] is taken for the same request (a wrapper
//! such as `timeout` forwards the terminal's Ctrl-C, which reached this
//! process too).
//!
//! For the TUI, SIGTSTP and SIGCONT too: a stop must wait until the
//! terminal is given back, and a continued process takes it again. For
//! `render`, SIGUSR1: write the checkpoint now.

use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicPtr, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use signal_hook::consts::{SIGCONT, SIGHUP, SIGINT, SIGTERM, SIGTSTP, SIGUSR1};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
/// The last signal received, for the exit status (128 + signal).
static LAST: AtomicI32 = AtomicI32::new(0);
/// When the first signal came, in nanoseconds of the monotonic clock.
static FIRST: AtomicU64 = AtomicU64::new(0);
/// A signal this soon after the first repeats its request.
const REPEAT: Duration = Duration::from_millis(300);

/// Installs the handlers (once) and returns the flag they set.
pub(crate) fn flag() -> Arc<AtomicBool> {
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        for sig in [SIGINT, SIGTERM, SIGHUP] {
            let asked = flag.clone();
            // Registering only fails for forbidden signals, which these are
            // not; without handlers the default action still ends the process.
            // SAFETY: the actions only read the clock, touch atomics and
            // make the async-signal-safe calls of `exit_now`.
            let _ = unsafe {
                signal_hook::low_level::register(sig, move || {
                    let now = monotonic_ns();
                    if !asked.load(Ordering::SeqCst) {
                        FIRST.store(now, Ordering::SeqCst);
                    } else if now.saturating_sub(FIRST.load(Ordering::SeqCst))
                        >= REPEAT.as_nanos() as u64
                    {
                        exit_now(sig);
                    }
                })
            };
            let _ = signal_hook::flag::register(sig, flag.clone());
            // SAFETY: the action only stores to an atomic.
            let _ = unsafe {
                signal_hook::low_level::register(sig, move || LAST.store(sig, Ordering::SeqCst))
            };
        }
        flag
    })
    .clone()
}

static CHECKPOINT: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Catches SIGUSR1 (once) and returns the flag it sets: a request for a
/// checkpoint now. Caught by every render, checkpointing or not, since its
/// default action would end the process (a batch system's warning signal
/// is often SIGUSR1).
pub(crate) fn checkpoint_flag() -> Arc<AtomicBool> {
    CHECKPOINT
        .get_or_init(|| {
            let flag = Arc::new(AtomicBool::new(false));
            // Without the handler the default action stands: nothing better.
            let _ = signal_hook::flag::register(SIGUSR1, flag.clone());
            flag
        })
        .clone()
}

/// The monotonic clock, read the async-signal-safe way.
fn monotonic_ns() -> u64 {
    // SAFETY: clock_gettime writes the zeroed struct it is given.
    unsafe {
        let mut t: libc::timespec = std::mem::zeroed();
        libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t);
        t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
    }
}

/// What the TUI changed in the terminal, to undo from a signal handler.
struct Terminal {
    /// The terminal device, and its modes before raw mode.
    fd: libc::c_int,
    modes: libc::termios,
    /// Bytes for standard output that leave the TUI's screen modes.
    leave: Vec<u8>,
}

static TERMINAL: OnceLock<Option<Terminal>> = OnceLock::new();
/// Whether the terminal is in the TUI's modes now.
static HELD: AtomicBool = AtomicBool::new(false);

/// Notes the terminal's modes before the TUI changes them (called before
/// raw mode; the modes read the first time stand for every later time),
/// and the bytes that undo its screen modes.
pub(crate) fn hold_terminal(leave: impl FnOnce() -> Vec<u8>) {
    TERMINAL.get_or_init(|| {
        // The device raw mode is set on: standard input where it is a
        // terminal, else the controlling terminal, opened here and kept
        // open for the handler.
        // SAFETY: isatty, open, tcgetattr and close on descriptors this
        // process holds.
        unsafe {
            let fd = match libc::isatty(0) {
                1 => 0,
                _ => libc::open(c"/dev/tty".as_ptr(), libc::O_RDWR | libc::O_CLOEXEC),
            };
            if fd < 0 {
                return None;
            }
            let mut modes: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(fd, &mut modes) != 0 {
                if fd != 0 {
                    libc::close(fd);
                }
                return None;
            }
            Some(Terminal {
                fd,
                modes,
                leave: leave(),
            })
        }
    });
    HELD.store(true, Ordering::SeqCst);
}

/// The terminal is back in its own modes.
pub(crate) fn release_terminal() {
    HELD.store(false, Ordering::SeqCst);
}

/// The temporary file an output is being written to, if any.
static PENDING: AtomicPtr<libc::c_char> = AtomicPtr::new(std::ptr::null_mut());

/// Notes the temporary file being written (`Some`) or that it is gone
/// (`None`), for [`exit_now`] to remove. A name once noted is never
/// freed: the handler may be reading it on another thread (a few bytes
/// per output written).
pub(crate) fn writing(tmp: Option<&Path>) {
    note(&PENDING, tmp);
}

/// The lock file of a claim held, if any.
static CLAIM: AtomicPtr<libc::c_char> = AtomicPtr::new(std::ptr::null_mut());

/// Notes the lock file of a claim held (`Some`) or given up (`None`), for
/// [`exit_now`] to remove as [`writing`]'s file.
pub(crate) fn claiming(lock: Option<&Path>) {
    note(&CLAIM, lock);
}

fn note(slot: &AtomicPtr<libc::c_char>, path: Option<&Path>) {
    let name = path
        .and_then(|p| CString::new(p.as_os_str().as_bytes()).ok())
        .map_or(std::ptr::null_mut(), CString::into_raw);
    slot.store(name, Ordering::SeqCst);
}

/// Ends the process on a second signal: the terminal is given back, and a
/// half-written output and a claim's lock file removed first. Only async-signal-safe calls.
fn exit_now(sig: i32) -> ! {
    // SAFETY: write, tcsetattr, unlink and _exit are async-signal-safe;
    // the terminal and the file name were set before the handler could
    // read them and are never freed.
    unsafe {
        if HELD.load(Ordering::SeqCst) {
            if let Some(Some(t)) = TERMINAL.get() {
                libc::write(1, t.leave.as_ptr().cast(), t.leave.len());
                libc::tcsetattr(t.fd, libc::TCSANOW, &t.modes);
            }
        }
        for slot in [&PENDING, &CLAIM] {
            let name = slot.load(Ordering::SeqCst);
            if !name.is_null() {
                libc::unlink(name);
            }
        }
        let note = b"\nrayterm: stopped at once by a second signal\n";
        libc::write(2, note.as_ptr().cast(), note.len());
        libc::_exit(128 + sig);
    }
}

/// The error of work stopped on request (a signal, or a caller's
/// [`Cancel`]); its callers write nothing.
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
pub(crate) struct Interrupted;

/// Whether long work should stop: the one way every layer is asked to.
/// Work that can take long takes one as a parameter and polls it where it
/// may stop; only the commands (`cli/`, `tui/`) choose which, so nothing
/// below them reads the signal flag on its own.
#[derive(Clone, Copy, Default)]
pub enum Cancel<'a> {
    /// Never stops: tests, tools, work too short to stop.
    #[default]
    Never,
    /// Stops once the caller's closure says so (a newer view, a deadline).
    When(&'a (dyn Fn() -> bool + Sync)),
    /// Stops once a signal asked the process to ([`requested`]).
    Signal,
}

impl Cancel<'_> {
    /// Whether the work should stop now.
    pub(crate) fn is_set(self) -> bool {
        match self {
            Cancel::Never => false,
            Cancel::When(f) => f(),
            Cancel::Signal => requested(),
        }
    }

    /// [`Cancel::is_set`] as the error of work stopped on request.
    pub(crate) fn check(self) -> Result<(), Interrupted> {
        match self.is_set() {
            true => Err(Interrupted),
            false => Ok(()),
        }
    }
}

/// Whether a signal asked the process to stop.
pub(crate) fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::Relaxed))
}

/// The conventional exit status for the signal received: 128 + its number
/// (130 for SIGINT); 130 when none was.
pub(crate) fn exit_code() -> u8 {
    match LAST.load(Ordering::SeqCst) {
        0 => 130,
        s => (128 + s) as u8,
    }
}

/// The flags SIGTSTP and SIGCONT set.
struct JobControl {
    stop: Arc<AtomicBool>,
    cont: Arc<AtomicBool>,
}

static JOBS: OnceLock<Option<JobControl>> = OnceLock::new();

/// Catches SIGTSTP and SIGCONT (once), unless SIGTSTP is ignored: whoever
/// started the process then asked that it never stop. Returns whether the
/// process may stop.
pub(crate) fn catch_stops() -> bool {
    JOBS.get_or_init(|| {
        // SAFETY: sigaction with a null new action only reads the current
        // one into the zeroed struct.
        let ignored = unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            libc::sigaction(SIGTSTP, std::ptr::null(), &mut old) == 0
                && old.sa_sigaction == libc::SIG_IGN
        };
        if ignored {
            return None;
        }
        let stop = Arc::new(AtomicBool::new(false));
        let cont = Arc::new(AtomicBool::new(false));
        signal_hook::flag::register(SIGTSTP, stop.clone()).ok()?;
        signal_hook::flag::register(SIGCONT, cont.clone()).ok()?;
        Some(JobControl { stop, cont })
    })
    .is_some()
}

/// Whether a SIGTSTP came since last asked.
pub(crate) fn stop_requested() -> bool {
    JOBS.get()
        .and_then(Option::as_ref)
        .is_some_and(|j| j.stop.swap(false, Ordering::SeqCst))
}

/// Whether a SIGCONT came since last asked.
pub(crate) fn continued() -> bool {
    JOBS.get()
        .and_then(Option::as_ref)
        .is_some_and(|j| j.cont.swap(false, Ordering::SeqCst))
}

/// Stops the process group as SIGTSTP's default action does (the terminal's
/// Ctrl-Z stops every process of the job: `cargo run` too), and returns
/// once this process is continued. SIGTSTP itself rather than SIGSTOP: the
/// shell reports the job suspended as after any Ctrl-Z, and the kernel
/// drops the stop of a process group no shell would continue (this then
/// returns at once).
pub(crate) fn stop() {
    let stopped = Instant::now();
    // SAFETY: this process ignores the signal the group is sent (an ignored
    // signal is discarded as it is generated), then takes the default action
    // for the one raise, which delivers to this thread before it returns;
    // the action before (signal-hook's handler) is put back as it was.
    unsafe {
        let mut ignore: libc::sigaction = std::mem::zeroed();
        ignore.sa_sigaction = libc::SIG_IGN;
        let mut handler: libc::sigaction = std::mem::zeroed();
        if libc::sigaction(SIGTSTP, &ignore, &mut handler) != 0 {
            return;
        }
        libc::kill(0, SIGTSTP);
        let mut default: libc::sigaction = std::mem::zeroed();
        default.sa_sigaction = libc::SIG_DFL;
        libc::sigaction(SIGTSTP, &default, std::ptr::null_mut());
        libc::raise(SIGTSTP);
        libc::sigaction(SIGTSTP, &handler, std::ptr::null_mut());
    }
    note_stopped(stopped.elapsed());
}

fn note_stopped(d: Duration) {
    STOPPED_NS.fetch_add(d.as_nanos() as u64, Ordering::Relaxed);
}

/// Nanoseconds the process spent suspended by [`stop`].
static STOPPED_NS: AtomicU64 = AtomicU64::new(0);

/// A clock that stands still while the process is suspended by [`stop`]:
/// what the TUI's figures of elapsed time read, so that a pass across a
/// Ctrl-Z does not look long.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Running {
    at: Instant,
    stopped: u64,
}

impl Running {
    pub(crate) fn now() -> Self {
        Running {
            at: Instant::now(),
            stopped: STOPPED_NS.load(Ordering::Relaxed),
        }
    }

    /// The time since `now`, less any time suspended since.
    pub(crate) fn elapsed(&self) -> Duration {
        let stopped = STOPPED_NS
            .load(Ordering::Relaxed)
            .saturating_sub(self.stopped);
        self.at
            .elapsed()
            .saturating_sub(Duration::from_nanos(stopped))
    }
}

/// Lets a closed pipe end the process quietly (status 141), as it does
/// other Unix tools, instead of failing every later write.
pub(crate) fn default_sigpipe() {
    // SAFETY: restoring the default disposition of SIGPIPE before any thread
    // is started; nothing else depends on it being ignored.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Time suspended after a clock started is left out of it; a clock
    /// started after a suspension counts from then.
    #[test]
    fn running_time_leaves_out_time_suspended() {
        let before = Running::now();
        note_stopped(Duration::from_secs(3600));
        assert_eq!(before.elapsed(), Duration::ZERO);
        let after = Running::now();
        std::thread::sleep(Duration::from_millis(5));
        assert!(after.elapsed() >= Duration::from_millis(5));
    }
}
