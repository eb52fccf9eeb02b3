//! What the command line prints: its report on standard output, which a failed write must
//! fail (a full disk, `> /dev/full`: exit 1, naming it), and its notes and warnings on
//! standard error, which are best effort. `println!` and `eprintln!` panic when a write
//! fails, which would end the run with a panic's message and exit 101. (A reader that goes
//! away, `| head`, ends the process by SIGPIPE before a write returns: main.rs.)

use anyhow::{Context, Result};
use std::io::Write;

/// One line of the report on standard output.
pub fn report_line(line: std::fmt::Arguments) -> Result<()> {
    report_text(format_args!("{line}\n"))
}

/// Text of the report on standard output, as it is (its own line ends).
pub fn report_text(text: impl std::fmt::Display) -> Result<()> {
    write!(std::io::stdout().lock(), "{text}").context("writing to standard output")
}

/// One line on standard error, or nothing where it cannot be written.
pub fn note_line(line: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// `println!`'s arguments, as a line of the report: a `Result` to pass on with `?`.
macro_rules! report {
    ($($arg:tt)*) => {
        $crate::cli::console::report_line(format_args!($($arg)*))
    };
}

/// `eprintln!`'s arguments, as a note on standard error.
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::cli::console::note_line(format_args!($($arg)*))
    };
}

pub(crate) use {note, report};
