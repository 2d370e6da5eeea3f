//! SIGINT, SIGTERM and SIGHUP, turned into a flag the long-running parts
//! poll: a render stops within a sample and writes nothing, the TUI restores
//! the terminal and quits, exactly as on Ctrl-C or `q`. A second signal of
//! the same kind while the first is being handled ends the process at once.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Arc, OnceLock};

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

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

/// Lets a closed pipe end the process quietly (status 141), as it does
/// other Unix tools, instead of failing every later write.
pub fn default_sigpipe() {
    // SAFETY: restoring the default disposition of SIGPIPE before any thread
    // is started; nothing else depends on it being ignored.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
