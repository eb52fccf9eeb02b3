//! Reading an input file without trusting it: only a regular file is read, and never more
//! than the memory budget allows.
//!
//! A path can name `/dev/zero` (endless), a FIFO (opening it for reading blocks until a writer
//! comes, forever), a directory or a socket. The file is opened with `O_NONBLOCK`, so opening
//! a FIFO returns at once, and the *opened* handle is checked to be a regular file, so the
//! path cannot be swapped between a check and the open. The file's bytes are checked against
//! the run's ledger (limits.rs) before a byte is read, and charged once read; the read itself
//! stops one byte past what the budget has left, so a file that grows meanwhile is refused
//! too. (What parsing the bytes takes, each parser charges as it counts it.) The ledger notes
//! the file's identity, so that no output of the run replaces it.

use crate::error::{Error, Result};
use crate::limits::{Bytes, FileId, Ledger};
use std::io::Read;
use std::path::Path;

/// The whole content of the regular file at `path`; refused when its bytes would take the
/// run past its budget, and else charged to `ledger`. `what` names the file's role in
/// messages ("model", "sensed image").
pub fn read_input_file(path: &Path, what: &str, ledger: &Ledger) -> Result<Vec<u8>> {
    read_identified_file(path, what, ledger).map(|(bytes, _)| bytes)
}

/// [`read_input_file`], with the identity of the file that was read.
pub fn read_identified_file(path: &Path, what: &str, ledger: &Ledger) -> Result<(Vec<u8>, FileId)> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let file = options.open(path).map_err(|e| Error::io(path, e))?;
    let metadata = file.metadata().map_err(|e| Error::io(path, e))?;
    if !metadata.is_file() {
        return Err(Error::file(
            path,
            format!(
                "the {what} is not a regular file ({}); only regular files are read",
                super::file_kind(metadata.file_type())
            ),
        ));
    }
    let id = FileId::of(&metadata);
    ledger.record_input(id);
    let describe = |size: u64| format!("loading the {what} {} ({})", path.display(), Bytes(size));
    ledger.check(describe(metadata.len()), metadata.len())?;
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    file.take(ledger.available().saturating_add(1)).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    // Refuses a file that grew past what the budget allows while it was read.
    ledger.charge(describe(bytes.len() as u64), bytes.len() as u64)?;
    Ok((bytes, id))
}

/// The same as [`read_input_file`], as UTF-8 text.
pub fn read_input_text(path: &Path, what: &str, ledger: &Ledger) -> Result<String> {
    String::from_utf8(read_input_file(path, what, ledger)?)
        .map_err(|e| Error::file(path, format!("the {what} is not UTF-8 text ({e})")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::MemoryBudget;

    #[test]
    fn devices_directories_and_fifos_are_refused_without_blocking() {
        let dir = crate::io::scratch_dir("input-kinds");
        let fifo = dir.join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file system node.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        for (path, kind) in
            [(Path::new("/dev/zero"), "a character device"), (dir.as_path(), "a directory"), (&fifo, "a FIFO")]
        {
            let e = read_input_file(path, "model", &Ledger::default()).unwrap_err().to_string();
            assert!(e.contains(kind) && e.contains("only regular files"), "{e}");
        }
    }

    #[test]
    fn a_file_that_would_not_fit_the_budget_is_refused_before_it_is_read() {
        let path = crate::io::scratch_dir("input-limit").join("big");
        std::fs::write(&path, vec![b'x'; 1000]).unwrap();
        let ledger = Ledger::new(MemoryBudget::new(1500));
        assert_eq!(read_input_file(&path, "model", &ledger).unwrap().len(), 1000);
        assert_eq!(ledger.held(), 1000);
        let e = read_input_file(&path, "model", &Ledger::new(MemoryBudget::new(999))).unwrap_err().to_string();
        assert!(e.contains("(1000 bytes) needs about 1000 bytes, more than the memory budget of 999 bytes"), "{e}");
        // The budget is the run's: a second read of the file finds it spent.
        let e = read_input_file(&path, "model", &ledger).unwrap_err().to_string();
        assert!(e.contains("needs about 1000 bytes on top of the 1000 bytes the run already holds"), "{e}");
    }
}
