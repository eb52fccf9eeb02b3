//! Outputs that are never seen half-written, and that only ever replace what an output was.
//!
//! Every output file is written to a temporary file in its own directory (so the final
//! rename stays on one file system, where it is atomic) and renamed over the target only once
//! it is complete and synced: a failure, SIGINT or SIGKILL before that leaves the previous file
//! whole, and a reader only ever sees the old file or the complete new one. A temporary file
//! is removed when its writer fails or is dropped; a killed process can leave one behind,
//! named `.NAME.*.tmp`, beside the target.
//!
//! Only a regular file is ever replaced. An output path that names a device, a FIFO, a socket,
//! a directory or a symbolic link to one is refused (checked when the output is started, and
//! again just before the rename): a rename would put a regular file in place of `/dev/null` or
//! of a link a user made, which is never what was asked. A symbolic link to a regular file is
//! replaced itself, as `rename` does: the new file takes the link's place, and the file it
//! named is left as it was.
//!
//! A set of files that belong together (a render's directory, an experiment's) is a directory
//! replaced whole. It is written into a hidden staging directory beside the target
//! (`.NAME.*.staging`, on the same file system), then, under an exclusive lock on the parent
//! directory (which the swap leaves in place, unlike the set's own), swapped with the target
//! by one `renameat2(RENAME_EXCHANGE)`, or renamed into place when there is no target yet; the
//! old set is removed after. A failure anywhere, or a kill at any point, leaves the target
//! either the previous set whole or the new one whole, and two sets written into one
//! directory at once each land whole, the later one winning. A killed process can leave its
//! staging directory behind. A file system that cannot exchange directories (`EINVAL`,
//! `ENOSYS` or `EOPNOTSUPP` from `renameat2`) gets an error, and the previous set stays: there
//! is no fallback of two renames, which a kill between them would leave with no set at all.
//!
//! What a user left in the target directory besides the set is carried into the new set
//! before the swap: regular files by hard link, symbolic links as links naming the same path.
//! Anything else there (a directory, a device, a FIFO, a socket) is refused before anything is
//! written, as is an entry under one of the set's names that is not what the set puts there.
//! The target is named by its canonical path (`--out .` is the working directory itself; a
//! link to a directory stands for the directory it names); the root directory cannot be a set.

use super::file_kind;
use crate::error::{Error, Result};
use crate::limits::{FileId, Ledger};
use std::ffi::{CString, OsString};
use std::fs::{File, FileType};
use std::io::{ErrorKind, Write};
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// An output being written; nothing appears at `path` until [`PendingFile::commit`].
pub struct PendingFile {
    temp: tempfile::NamedTempFile,
    path: PathBuf,
    /// The run whose inputs it may not replace, checked again at the commit
    /// ([`PendingFile::guarding_inputs`]).
    run: Option<Arc<Ledger>>,
}

impl PendingFile {
    /// Starts writing `path`: a temporary file beside it. Refuses a `path` that is anything
    /// but a regular file (or a link to one) or nothing.
    pub fn new(path: &Path) -> Result<Self> {
        refuse_unless_regular(path)?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let name = path.file_name().ok_or_else(|| Error::file(path, "an output must name a file"))?;
        let prefix = format!(".{}.", name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // Like a file created in place (tempfile's default is private, 0600).
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let temp = builder.tempfile_in(dir).map_err(|e| Error::io(dir, e))?;
        Ok(Self { temp, path: path.to_path_buf(), run: None })
    }

    /// Refuses, at the commit, to replace any file `run` has read by then
    /// ([`refuse_overwriting_inputs`]): a run that reads its inputs as it goes (`bop` reads each
    /// scene's depth images, cameras and models as it reaches them) writes its output after
    /// reading all of them, and a check when the output starts sees only those read before.
    pub fn guarding_inputs(mut self, run: &Arc<Ledger>) -> Self {
        self.run = Some(run.clone());
        self
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
        // What `path` is may have changed while the file was written.
        refuse_unless_regular(&path)?;
        if let Some(run) = &self.run {
            refuse_overwriting_inputs([path.as_path()], run)?;
        }
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

/// Refuses `path` unless it is nothing (a dangling link counts as nothing: the link is
/// replaced) or a regular file, through links.
fn refuse_unless_regular(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(not_replaceable(path, meta.file_type(), "a regular file", "an output")),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(path, e)),
    }
}

/// The refusal of `path`, which is a `found` where an output needs `wanted`.
fn not_replaceable(path: &Path, found: FileType, wanted: &str, output: &str) -> Error {
    let link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    let through = if link && !found.is_symlink() { " (through a symbolic link)" } else { "" };
    Error::file(path, format!("is {}{through}, not {wanted}; refusing to replace it with {output}", file_kind(found)))
}

/// A set of files and directories that belong together (a render's directory, an
/// experiment's), written into a hidden staging directory beside the target directory and
/// swapped with it whole (module docs).
pub struct StagedSet {
    /// Holds the new set until the commit, the old one after it; removed when dropped.
    staging: tempfile::TempDir,
    /// The target as given, for the paths [`StagedSet::commit`] returns.
    given: PathBuf,
    /// The target's canonical path, whose parent is a directory.
    target: PathBuf,
    files: Vec<OsString>,
    dirs: Vec<OsString>,
}

/// An entry of the target directory that is not the set's, as it is carried into the new one.
enum Carried {
    /// A regular file, linked.
    File,
    /// A symbolic link, made again naming this path.
    Link(PathBuf),
}

impl StagedSet {
    /// Starts the set `files` and `dirs` (names in the directory) that will replace `target`:
    /// creates `target`'s parent if needed and a staging directory in it. Refuses at once what
    /// the commit would refuse.
    pub fn new(target: &Path, files: &[&str], dirs: &[&str]) -> Result<Self> {
        let resolved = resolve(target)?;
        let (parent, name) = match (resolved.parent(), resolved.file_name()) {
            (Some(parent), Some(name)) => (parent, name),
            _ => return Err(Error::file(target, "is the root directory, which a set cannot replace")),
        };
        let prefix = format!(".{}.", name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".staging");
        // Like a directory created in place (tempfile's default is private, 0700).
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o777));
        let staging = builder.tempdir_in(parent).map_err(|e| Error::io(parent, e))?;
        let set = Self {
            staging,
            given: target.to_path_buf(),
            target: resolved,
            files: files.iter().map(OsString::from).collect(),
            dirs: dirs.iter().map(OsString::from).collect(),
        };
        set.to_carry()?;
        Ok(set)
    }

    /// Where to write the set's file or directory `name` before the commit.
    pub fn staged(&self, name: &str) -> PathBuf {
        self.staging.path().join(name)
    }

    /// Carries what else the target directory holds into the staged set and swaps it in,
    /// under an exclusive lock on the parent directory, so concurrent sets take turns; the
    /// old set is removed. Returns the paths of the set's files, under the target as given.
    pub fn commit(self) -> Result<Vec<PathBuf>> {
        let parent = self.target.parent().unwrap_or(Path::new("/"));
        let lock = File::open(parent).map_err(|e| Error::io(parent, e))?;
        lock.lock().map_err(|e| Error::io(parent, e))?;
        let replace = self.exists()?;
        if replace {
            for (name, carried) in self.to_carry()? {
                let (from, to) = (self.target.join(&name), self.staging.path().join(&name));
                match carried {
                    Carried::File => std::fs::hard_link(&from, &to),
                    Carried::Link(names) => std::os::unix::fs::symlink(names, &to),
                }
                .map_err(|e| Error::io(&from, e))?;
            }
            // The directory keeps its permissions.
            let permissions = std::fs::metadata(&self.target).map_err(|e| Error::io(&self.target, e))?.permissions();
            std::fs::set_permissions(self.staging.path(), permissions).map_err(|e| Error::io(&self.target, e))?;
        }
        stop_for_test("stop-before");
        match replace {
            true => exchange(self.staging.path(), &self.target)?,
            false => std::fs::rename(self.staging.path(), &self.target).map_err(|e| Error::io(&self.target, e))?,
        }
        stop_for_test("stop-after");
        Ok(self.files.iter().map(|name| self.given.join(name)).collect())
        // Dropping `self.staging` removes the old set (after a plain rename there is nothing
        // there), and closing `lock` releases the lock.
    }

    /// Whether the target exists; refuses one that is not a directory.
    fn exists(&self) -> Result<bool> {
        match std::fs::symlink_metadata(&self.target) {
            Ok(meta) if meta.is_dir() => Ok(true),
            Ok(meta) => Err(not_replaceable(&self.target, meta.file_type(), "a directory", "a set of outputs")),
            Err(e) if e.kind() == ErrorKind::NotFound => Ok(false),
            Err(e) => Err(Error::io(&self.target, e)),
        }
    }

    /// The target directory's entries that are not the set's, to carry into the new set;
    /// refuses an entry under a set name that is not what the set puts there, and an entry
    /// that cannot be carried.
    fn to_carry(&self) -> Result<Vec<(OsString, Carried)>> {
        if !self.exists()? {
            return Ok(Vec::new());
        }
        let mut carried = Vec::new();
        for entry in std::fs::read_dir(&self.target).map_err(|e| Error::io(&self.target, e))? {
            let entry = entry.map_err(|e| Error::io(&self.target, e))?;
            let (name, path) = (entry.file_name(), entry.path());
            // The set's own entries are replaced, if they are what the set puts there.
            if self.files.contains(&name) || self.dirs.contains(&name) {
                let wanted = if self.dirs.contains(&name) { "a directory" } else { "a regular file" };
                match std::fs::metadata(&path) {
                    Ok(meta) if file_kind(meta.file_type()) != wanted => {
                        return Err(not_replaceable(&path, meta.file_type(), wanted, "an output"))
                    }
                    Err(e) if e.kind() != ErrorKind::NotFound => return Err(Error::io(&path, e)),
                    _ => continue,
                }
            }
            let file_type = entry.file_type().map_err(|e| Error::io(&path, e))?;
            if file_type.is_file() {
                carried.push((name, Carried::File));
            } else if file_type.is_symlink() {
                carried.push((name, Carried::Link(std::fs::read_link(&path).map_err(|e| Error::io(&path, e))?)));
            } else {
                return Err(Error::file(
                    &path,
                    format!(
                        "is {} beside the outputs in {}, which are replaced as a whole directory: only regular \
                         files and symbolic links are carried over, so nothing was written (move it out)",
                        file_kind(file_type),
                        self.given.display()
                    ),
                ));
            }
        }
        Ok(carried)
    }
}

/// `target` by its canonical path, its parent created if need be.
fn resolve(target: &Path) -> Result<PathBuf> {
    match std::fs::canonicalize(target) {
        Ok(path) => Ok(path),
        Err(e) if e.kind() == ErrorKind::NotFound => {
            let name = target.file_name().ok_or_else(|| Error::file(target, "names no directory"))?;
            let parent = match target.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
            Ok(std::fs::canonicalize(parent).map_err(|e| Error::io(parent, e))?.join(name))
        }
        Err(e) => Err(Error::io(target, e)),
    }
}

/// Swaps the directories `staging` and `target` in one step.
fn exchange(staging: &Path, target: &Path) -> Result<()> {
    let c_path = |p: &Path| CString::new(p.as_os_str().as_bytes()).map_err(|e| Error::io(p, e.into()));
    let (from, to) = (c_path(staging)?, c_path(target)?);
    let result = if fail_for_test() {
        Err(std::io::Error::from_raw_os_error(libc::EINVAL))
    } else {
        // SAFETY: both paths are NUL-terminated C strings that outlive the call, which only
        // reads them; AT_FDCWD makes them relative to the working directory (they are absolute).
        match unsafe {
            libc::renameat2(libc::AT_FDCWD, from.as_ptr(), libc::AT_FDCWD, to.as_ptr(), libc::RENAME_EXCHANGE)
        } {
            0 => Ok(()),
            _ => Err(std::io::Error::last_os_error()),
        }
    };
    let Err(error) = result else { return Ok(()) };
    match error.raw_os_error() {
        Some(libc::EINVAL | libc::ENOSYS | libc::EOPNOTSUPP) => Err(Error::file(
            target,
            format!(
                "this file system cannot swap two directories at once (renameat2 with RENAME_EXCHANGE: {error}), \
                 so the outputs were not written and the previous ones are as they were; remove the directory \
                 or write to a new one"
            ),
        )),
        _ => Err(Error::io(target, error)),
    }
}

/// The hook of tests/outputs.rs, `RANGESYNTH_TEST_COMMIT`: `fail` fails the swap as a file
/// system without it would.
fn fail_for_test() -> bool {
    std::env::var_os(TEST_HOOK).is_some_and(|v| v == "fail")
}

/// The hook of tests/outputs.rs, `RANGESYNTH_TEST_COMMIT=POINT:MARKER`: at `point` of a
/// commit (`stop-before` or `stop-after` the swap), creates the file MARKER and waits there
/// for the test to kill the process.
fn stop_for_test(point: &str) {
    let Some(hook) = std::env::var_os(TEST_HOOK) else { return };
    let hook = hook.to_string_lossy();
    if let Some(marker) = hook.strip_prefix(point).and_then(|rest| rest.strip_prefix(':')) {
        let _ = File::create(marker);
        loop {
            std::thread::sleep(std::time::Duration::from_secs(60));
        }
    }
}

const TEST_HOOK: &str = "RANGESYNTH_TEST_COMMIT";

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
        let e = result.unwrap_err().to_string();
        assert!(e.contains("failed halfway"), "the writer's own error is returned: {e}");
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

    fn fifo(path: &Path) {
        let c = CString::new(path.as_os_str().as_bytes()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o666) }, 0);
    }

    fn write(path: &Path, text: &str) -> Result<()> {
        write_atomically(path, |f| f.write_all(text.as_bytes()).map_err(|e| Error::io(path, e)))
    }

    /// A path whose file cannot be looked at (a loop of links) is refused, naming it, and left
    /// as it was: it is not known to be nothing.
    #[test]
    fn an_output_that_cannot_be_looked_at_is_refused() {
        let dir = crate::io::scratch_dir("atomic-loop");
        let looped = dir.join("loop");
        std::os::unix::fs::symlink(&looped, &looped).unwrap();
        let e = write(&looped, "new").unwrap_err().to_string();
        assert!(e.contains(&looped.display().to_string()), "{e}");
        assert_eq!(std::fs::read_link(&looped).unwrap(), looped, "the link is left as it was");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "a temporary file was left behind");
    }

    #[test]
    fn only_a_regular_file_or_nothing_is_replaced() {
        let dir = crate::io::scratch_dir("atomic-kinds");
        let (node, link, socket, sub) = (dir.join("fifo"), dir.join("link"), dir.join("socket"), dir.join("sub"));
        fifo(&node);
        std::os::unix::fs::symlink(&node, &link).unwrap();
        drop(std::os::unix::net::UnixListener::bind(&socket).unwrap());
        std::fs::create_dir(&sub).unwrap();
        for (path, says) in [
            (&node, "is a FIFO, not a regular file"),
            (&link, "is a FIFO (through a symbolic link)"),
            (&socket, "is a socket"),
            (&sub, "is a directory"),
        ] {
            let e = write(path, "new").unwrap_err().to_string();
            assert!(e.contains(&path.display().to_string()) && e.contains(says), "{e}");
        }
        assert!(std::os::unix::fs::FileTypeExt::is_fifo(&std::fs::symlink_metadata(&node).unwrap().file_type()));
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 4, "a temporary file was left behind");
        // A link to a regular file, or to nothing, is replaced itself.
        let (kept, to_kept, dangling) = (dir.join("kept"), dir.join("to_kept"), dir.join("dangling"));
        std::fs::write(&kept, "mine").unwrap();
        std::os::unix::fs::symlink(&kept, &to_kept).unwrap();
        std::os::unix::fs::symlink(dir.join("nothing"), &dangling).unwrap();
        for path in [&to_kept, &dangling] {
            write(path, "new").unwrap();
            assert!(std::fs::symlink_metadata(path).unwrap().is_file());
            assert_eq!(std::fs::read_to_string(path).unwrap(), "new");
        }
        assert_eq!(std::fs::read_to_string(&kept).unwrap(), "mine");
    }

    /// The entries of `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    /// Where the old set has a link under one of the set's names, a dangling one is replaced
    /// like nothing, and one that cannot be followed (a loop) is refused, naming it; so is a
    /// target that is a loop itself.
    #[test]
    fn a_set_replaces_a_dangling_link_under_its_name_and_refuses_a_loop() {
        let parent = crate::io::scratch_dir("atomic-set-links");
        let target = parent.join("set");
        std::fs::create_dir(&target).unwrap();
        std::os::unix::fs::symlink(parent.join("nothing"), target.join("a.txt")).unwrap();
        let set = StagedSet::new(&target, &["a.txt"], &[]).unwrap();
        write(&set.staged("a.txt"), "new").unwrap();
        set.commit().unwrap();
        assert_eq!(std::fs::read_to_string(target.join("a.txt")).unwrap(), "new");
        let looped = target.join("a.txt");
        std::fs::remove_file(&looped).unwrap();
        std::os::unix::fs::symlink(&looped, &looped).unwrap();
        let e =
            StagedSet::new(&target, &["a.txt"], &[]).err().expect("a loop under a set's name is refused").to_string();
        assert!(e.contains(&looped.display().to_string()), "{e}");
        // A target that is itself a loop cannot be resolved: it cannot be accessed.
        let looped_target = parent.join("looped set");
        std::os::unix::fs::symlink(&looped_target, &looped_target).unwrap();
        let e = StagedSet::new(&looped_target, &["a.txt"], &[]).err().expect("a looped target is refused").to_string();
        assert!(e.starts_with("cannot access") && e.contains("looped set"), "{e}");
    }

    #[test]
    fn a_set_replaces_its_directory_whole_and_carries_what_else_was_there() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let parent = crate::io::scratch_dir("atomic-set");
        let target = parent.join("set");
        // A first set into no directory: renamed into place.
        let set = StagedSet::new(&target, &["a.txt", "b.txt"], &["views"]).unwrap();
        assert!(!target.exists(), "the target was made before the commit");
        for name in ["a.txt", "b.txt"] {
            write(&set.staged(name), "old").unwrap();
        }
        std::fs::create_dir_all(set.staged("views").join("old-1")).unwrap();
        assert_eq!(set.commit().unwrap(), [target.join("a.txt"), target.join("b.txt")]);
        // The user's file, link and permissions.
        std::fs::write(target.join("notes.txt"), "mine").unwrap();
        std::os::unix::fs::symlink("a.txt", target.join("link")).unwrap();
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o750)).unwrap();
        let notes = std::fs::metadata(target.join("notes.txt")).unwrap().ino();

        let set = StagedSet::new(&target, &["a.txt", "b.txt"], &["views"]).unwrap();
        write(&set.staged("a.txt"), "new").unwrap();
        std::fs::create_dir_all(set.staged("views").join("new-1")).unwrap();
        set.commit().unwrap();
        assert_eq!(names(&target), ["a.txt", "link", "notes.txt", "views"], "b.txt of the old set stayed");
        assert_eq!(names(&target.join("views")), ["new-1"]);
        assert_eq!(std::fs::read_to_string(target.join("link")).unwrap(), "new");
        assert_eq!(std::fs::metadata(target.join("notes.txt")).unwrap().ino(), notes);
        assert_eq!(std::fs::metadata(&target).unwrap().permissions().mode() & 0o777, 0o750);
        assert_eq!(names(&parent), ["set"], "the old set or a staging directory was left");

        // What cannot be carried, or is not what the set puts under its name, is refused at once.
        for (name, is_dir, says) in
            [("sub", true, "is a directory beside the outputs"), ("views", false, "is a regular file, not a directory")]
        {
            let path = target.join(name);
            let _ = std::fs::remove_dir_all(&path);
            match is_dir {
                true => std::fs::create_dir(&path).unwrap(),
                false => std::fs::write(&path, "").unwrap(),
            }
            let e = StagedSet::new(&target, &["a.txt"], &["views"]).err().unwrap().to_string();
            assert!(e.contains(&path.display().to_string()) && e.contains(says), "{e}");
            assert_eq!(names(&parent), ["set"]);
        }
        fifo(&parent.join("fifo"));
        let e = StagedSet::new(&parent.join("fifo"), &["a.txt"], &[]).err().unwrap().to_string();
        assert!(e.contains("is a FIFO, not a directory"), "{e}");
        let e = StagedSet::new(Path::new("/"), &["a.txt"], &[]).err().unwrap().to_string();
        assert!(e.contains("root directory"), "{e}");
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_through_a_link() {
        let dir = crate::io::scratch_dir("atomic-input");
        let input = dir.join("in.json");
        std::fs::write(&input, "{}").unwrap();
        std::os::unix::fs::symlink(&input, dir.join("link.json")).unwrap();
        std::fs::write(dir.join("other.json"), "{}").unwrap();
        let ledger = Ledger::default();
        crate::io::read_input_file(&input, "hypothesis file", &ledger).unwrap();
        let link = dir.join("link.json");
        let e = refuse_overwriting_inputs([link.as_path()], &ledger).unwrap_err().to_string();
        assert!(e.contains("refusing to overwrite"), "{e}");
        assert!(refuse_overwriting_inputs([dir.join("new.jsonl").as_path()], &ledger).is_ok());
        assert!(refuse_overwriting_inputs([dir.join("other.json").as_path()], &ledger).is_ok());
    }
}
