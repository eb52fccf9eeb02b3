//! Outputs that are never seen half-written.
//!
//! Every output file is written to a temporary file in its own directory (so the final
//! rename stays on one file system, where it is atomic) and renamed over the target only once
//! it is complete and synced: a failure, SIGINT or SIGKILL before that leaves the previous file
//! whole, and a reader only ever sees the old file or the complete new one. A temporary file
//! is removed when its writer fails or is dropped; a killed process can leave one behind,
//! named `.NAME.*.tmp`, beside the target.
//!
//! A set of files (a render's directory) is written whole into a staging directory first,
//! then moved in under an exclusive lock on the directory: a render that fails leaves the
//! previous complete set, and two renders into one directory at once each leave a complete
//! set of their own, the later one winning whole, never a mixture. (A kill during the moves
//! themselves, a few renames long, can still leave a mixture.)

use crate::error::{Error, Result};
use crate::limits::{FileId, Ledger};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// An output being written; nothing appears at `path` until [`PendingFile::commit`].
pub struct PendingFile {
    temp: tempfile::NamedTempFile,
    path: PathBuf,
}

impl PendingFile {
    /// Starts writing `path`: a temporary file beside it.
    pub fn new(path: &Path) -> Result<Self> {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let name = path.file_name().ok_or_else(|| Error::file(path, "an output must name a file"))?;
        let prefix = format!(".{}.", name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // Like a file created in place (tempfile's default is private, 0600).
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let temp = builder.tempfile_in(dir).map_err(|e| Error::io(dir, e))?;
        Ok(Self { temp, path: path.to_path_buf() })
    }

    /// The file to write into.
    pub fn file(&mut self) -> &mut File {
        self.temp.as_file_mut()
    }

    /// Syncs the complete file and renames it over `path`.
    pub fn commit(mut self) -> Result<()> {
        let path = self.path;
        self.temp
            .as_file_mut()
            .flush()
            .and_then(|()| self.temp.as_file().sync_all())
            .map_err(|e| Error::io(&path, e))?;
        self.temp.persist(&path).map_err(|e| Error::io(&path, e.error))?;
        Ok(())
    }
}

/// Writes `path` atomically with `write`.
pub fn write_atomically(path: &Path, write: impl FnOnce(&mut File) -> Result<()>) -> Result<()> {
    let mut pending = PendingFile::new(path)?;
    write(pending.file())?;
    pending.commit()
}

/// A set of files that belong together (a render's directory), written into a hidden
/// staging directory inside the target directory and moved into it together.
pub struct StagedSet {
    staging: tempfile::TempDir,
    target: PathBuf,
}

impl StagedSet {
    /// Creates `target` if needed, and a staging directory in it.
    pub fn new(target: &Path) -> Result<Self> {
        std::fs::create_dir_all(target).map_err(|e| Error::io(target, e))?;
        let staging =
            tempfile::Builder::new().prefix(".staging.").tempdir_in(target).map_err(|e| Error::io(target, e))?;
        Ok(Self { staging, target: target.to_path_buf() })
    }

    /// Where to write the set's file `name` before the commit.
    pub fn staged(&self, name: &str) -> PathBuf {
        self.staging.path().join(name)
    }

    /// Moves the staged files `names` into the target directory, each by an atomic rename,
    /// all under an exclusive lock on the directory, so concurrent sets take turns. Returns
    /// their final paths. A set not committed leaves the target directory as it was.
    pub fn commit(self, names: &[&str]) -> Result<Vec<PathBuf>> {
        let lock = File::open(&self.target).map_err(|e| Error::io(&self.target, e))?;
        lock.lock().map_err(|e| Error::io(&self.target, e))?;
        // A rename onto a directory is the one that can fail here; find it before moving any.
        if let Some(path) = names.iter().map(|name| self.target.join(name)).find(|p| p.is_dir()) {
            return Err(Error::file(path, "is a directory; the render's files were not written"));
        }
        names
            .iter()
            .map(|name| {
                let path = self.target.join(name);
                std::fs::rename(self.staged(name), &path).map_err(|e| Error::io(&path, e))?;
                Ok(path)
            })
            .collect()
        // The lock is released when `lock` is closed, the staging directory removed when
        // `self.staging` is dropped.
    }
}

/// Refuses an output that is one of the files the run read (the same file, by device and
/// inode, so links and other spellings of a path count too, and so do the files an input
/// names, such as a model's material libraries): writing it would destroy what was read.
pub fn refuse_overwriting_inputs<'a>(outputs: impl IntoIterator<Item = &'a Path>, ledger: &Ledger) -> Result<()> {
    for output in outputs {
        if std::fs::metadata(output).is_ok_and(|out| ledger.read(FileId::of(&out))) {
            return Err(Error::file(output, "this output is one of the run's inputs; refusing to overwrite it"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_previous_file_and_no_temporary() {
        let dir = crate::io::scratch_dir("atomic-fail");
        let path = dir.join("out.txt");
        std::fs::write(&path, "old").unwrap();
        let result = write_atomically(&path, |f| {
            f.write_all(b"partial").unwrap();
            Err(Error::Scene("failed halfway".into()))
        });
        assert!(result.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "the temporary file was left behind");
        write_atomically(&path, |f| f.write_all(b"new").map_err(|e| Error::io("x", e))).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        // Readable by others, as a file created in place would be (under the usual umask).
        let mode = std::os::unix::fs::PermissionsExt::mode(&std::fs::metadata(&path).unwrap().permissions());
        // SAFETY: umask only reads and sets this process's file mode mask; set back at once.
        let umask = unsafe {
            let m = libc::umask(0o022);
            libc::umask(m);
            m
        };
        assert_eq!(mode & 0o777, 0o666 & !umask as u32);
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_through_a_link() {
        let dir = crate::io::scratch_dir("atomic-input");
        let input = dir.join("in.json");
        std::fs::write(&input, "{}").unwrap();
        std::os::unix::fs::symlink(&input, dir.join("link.json")).unwrap();
        std::fs::write(dir.join("other.json"), "{}").unwrap();
        let ledger = Ledger::default();
        crate::io::read_input_file(&input, "hypothesis file", &ledger, 1).unwrap();
        let link = dir.join("link.json");
        let e = refuse_overwriting_inputs([link.as_path()], &ledger).unwrap_err().to_string();
        assert!(e.contains("refusing to overwrite"), "{e}");
        assert!(refuse_overwriting_inputs([dir.join("new.jsonl").as_path()], &ledger).is_ok());
        assert!(refuse_overwriting_inputs([dir.join("other.json").as_path()], &ledger).is_ok());
    }
}
