//! Running the binary from the command-line suites: one way to start it (validation on, so
//! any message fails the command) and one place for each test's files.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The rangesynth binary, with Vulkan validation on, and on the device the suite expects
/// where it expects one (`RANGESYNTH_EXPECT_DEVICE`, which CI sets): the binary is told to
/// use the device of that name (`RANGESYNTH_DEVICE`), and fails where there is none.
pub fn rangesynth_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rangesynth"));
    command.env("RANGESYNTH_VALIDATION", "1");
    if let Ok(expected) = std::env::var("RANGESYNTH_EXPECT_DEVICE") {
        command.env("RANGESYNTH_DEVICE", expected);
    }
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

/// A child's output, stdout or stderr, as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Asserts a clean refusal — exit code 1, an `error: ` message, no panic — whose message holds
/// `expected`; returns the message.
pub fn refused(out: &Output, what: &str, expected: &str) -> String {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{what}: expected exit code 1, got {:?}:\n{stderr}", out.status);
    assert!(stderr.starts_with("error: ") && !stderr.contains("panicked"), "{what}: {stderr}");
    assert!(stderr.contains(expected), "{what}: expected {expected:?} in:\n{stderr}");
    stderr
}
