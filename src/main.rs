//! The `rangesynth` binary: errors are printed with their causes and give exit code 1.
//! Exit codes: 0 success, 1 any error (bad input, refused work, device failure), 2 a usage
//! error (clap), and death by SIGPIPE when stdout is closed early.

mod cli;

use clap::Parser;
use cli::console::note;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Like any Unix filter: when the reader of our output goes away (`rangesynth … | head`),
    // end quietly by SIGPIPE instead of panicking in println!. Outputs are written
    // atomically, so this never leaves a torn file.
    // SAFETY: restoring the default disposition of one signal, before any thread starts.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    match cli::run(cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // The messages escape what they quote from inputs; this is the last line of that
            // defence, so that no input reaches the terminal raw.
            let message = format!("{e:#}");
            let lines: Vec<String> = message.lines().map(|line| rangesynth::untrusted::escaped(line, 2000)).collect();
            note!("error: {}", lines.join("\n"));
            ExitCode::FAILURE
        }
    }
}
