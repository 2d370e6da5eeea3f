//! SIGINT, SIGTERM and SIGHUP, turned into a flag the long-running parts
//! poll: a render stops within a sample and writes nothing, the TUI restores
//! the terminal and quits, exactly as on Ctrl-C or `q`. A second signal of
//! the same kind while the first is being handled ends the process at once.
//!
//! For the TUI, SIGTSTP and SIGCONT too: a stop must wait until the
//! terminal is given back, and a continued process takes it again.

use std::sync::atomic::{AtomicBool, AtomicI32, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use signal_hook::consts::{SIGCONT, SIGHUP, SIGINT, SIGTERM, SIGTSTP};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
/// The last signal received, for the exit status (128 + signal).
static LAST: AtomicI32 = AtomicI32::new(0);

/// Installs the handlers (once) and returns the flag they set.
pub fn flag() -> Arc<AtomicBool> {
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        for sig in [SIGINT, SIGTERM, SIGHUP] {
            // Registering only fails for forbidden signals, which these are
            // not; without handlers the default action still ends the process.
            let _ = signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, flag.clone());
            let _ = signal_hook::flag::register(sig, flag.clone());
            // SAFETY: the action only stores to an atomic, which is
            // async-signal-safe.
            let _ = unsafe {
                signal_hook::low_level::register(sig, move || LAST.store(sig, Ordering::SeqCst))
            };
        }
        flag
    })
    .clone()
}

/// The error of work a signal cut short; its callers write nothing.
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

/// Whether a signal asked the process to stop.
pub fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::Relaxed))
}

/// The conventional exit status for the signal received: 128 + its number
/// (130 for SIGINT); 130 when none was.
pub fn exit_code() -> u8 {
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
pub fn catch_stops() -> bool {
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
pub fn stop_requested() -> bool {
    JOBS.get()
        .and_then(Option::as_ref)
        .is_some_and(|j| j.stop.swap(false, Ordering::SeqCst))
}

/// Whether a SIGCONT came since last asked.
pub fn continued() -> bool {
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
pub fn stop() {
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
pub struct Running {
    at: Instant,
    stopped: u64,
}

impl Running {
    pub fn now() -> Self {
        Running {
            at: Instant::now(),
            stopped: STOPPED_NS.load(Ordering::Relaxed),
        }
    }

    /// The time since `now`, less any time suspended since.
    pub fn elapsed(&self) -> Duration {
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
pub fn default_sigpipe() {
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
