//! Lines for standard output and standard error. `println!` panics when
//! its stream cannot be written (a full disk behind a redirection, a
//! terminal gone); here a command's output that cannot be written ends it
//! with an error, and a note that cannot be written is dropped: there is
//! nowhere left to say it.

use std::fmt;
use std::io::{self, Write};

/// Writes to standard output, flushed, or says why it cannot.
pub(crate) fn out(args: fmt::Arguments) -> anyhow::Result<()> {
    let mut o = io::stdout().lock();
    // The I/O error stays in the chain: a reader gone away is no failure.
    o.write_fmt(args)
        .and_then(|()| o.flush())
        .map_err(|e| anyhow::Error::new(e).context("cannot write to standard output"))
}

/// Writes to standard error, if it can.
pub(crate) fn note(args: fmt::Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// `text` on stderr after `prefix`, its control characters but newline
/// and tab made printable: errors and warnings quote paths from the command
/// line and names from files.
pub fn say(prefix: &str, text: &str) {
    note(format_args!(
        "{prefix}: {}\n",
        crate::words::printable_but(text, "\n\t")
    ));
}

/// `print!` through [`out`]: evaluates to its `Result`.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::console::out(format_args!($($t)*)) };
}

/// `println!` through [`out`]: evaluates to its `Result`.
#[macro_export]
macro_rules! outln {
    () => { $crate::console::out(format_args!("\n")) };
    ($($t:tt)*) => { $crate::console::out(format_args!("{}\n", format_args!($($t)*))) };
}

/// `eprintln!` through [`note`].
#[macro_export]
macro_rules! noteln {
    ($($t:tt)*) => { $crate::console::note(format_args!("{}\n", format_args!($($t)*))) };
}
