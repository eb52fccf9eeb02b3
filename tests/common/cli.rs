//! Running the binary from the command-line suites: one way to start it (validation on, so
//! any message fails the command) and one place for each test's files.

use std::path::PathBuf;
use std::process::Command;

/// The rangesynth binary, with Vulkan validation on.
pub fn rangesynth_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rangesynth"));
    command.env("RANGESYNTH_VALIDATION", "1");
    command
}

/// An empty directory for one test's files: `suite/name` under the target's temporary
/// directory, emptied first.
pub fn fresh_dir(suite: &str, name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(suite).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
