//! The memory budget: how much memory one call may plan to use before it is refused.
//!
//! rangesynth runs inside long-running daemons, where an allocation the machine cannot satisfy
//! aborts the whole process (Rust's allocator does not return an error). So every size that
//! comes from outside — a file header, an image size, a batch — is turned into an estimate of
//! the bytes it will take, host and GPU together, and checked against this budget *before*
//! anything is allocated. A refusal names the figure, so the user can raise the budget
//! knowingly (`--memory-budget` or `RANGESYNTH_MEMORY_BUDGET`).
//!
//! The budget is one per run, not one per file: a [`Ledger`] holds what the run has taken so
//! far — every input's bytes, every structure parsed from them, every output built in memory —
//! and refuses the next charge that would take the total past the budget, naming the input
//! that crossed it. A check for what a step is about to allocate (a render's images, a
//! batch's buffers) is made on top of what the ledger holds. The ledger also knows every file
//! the run read, by identity, so that no output replaces one (io/atomic.rs).

pub use crate::error::Bytes;
use crate::error::{Error, Result};
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Environment variable setting the memory budget (bytes, or with a K, M, G or T suffix).
pub const MEMORY_BUDGET_ENV: &str = "RANGESYNTH_MEMORY_BUDGET";

/// The default budget, 4 GiB: a 4096² render or verification fits many times over; a
/// 16384² one (about 12 GiB) must be asked for.
pub const DEFAULT_MEMORY_BUDGET: u64 = 4 << 30;

/// Most bytes one call may plan to allocate, host and GPU memory together.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryBudget {
    bytes: u64,
}

impl Default for MemoryBudget {
    fn default() -> Self {
        Self { bytes: DEFAULT_MEMORY_BUDGET }
    }
}

impl MemoryBudget {
    pub const fn new(bytes: u64) -> Self {
        Self { bytes }
    }

    pub fn bytes(self) -> u64 {
        self.bytes
    }

    /// `RANGESYNTH_MEMORY_BUDGET` when set, else the default.
    pub fn from_env() -> Result<Self> {
        match std::env::var(MEMORY_BUDGET_ENV) {
            Ok(text) => Self::parse_setting(&text, MEMORY_BUDGET_ENV),
            Err(_) => Ok(Self::default()),
        }
    }

    /// Parses `text` as the value of `setting` (an option or environment variable, named in
    /// the error).
    pub fn parse_setting(text: &str, setting: &str) -> Result<Self> {
        text.parse().map_err(|e| match e {
            Error::Setting { reason, .. } => Error::Setting { setting: setting.to_string(), reason },
            other => other,
        })
    }

    /// Refuses `needed` bytes for `what` when they exceed the budget.
    pub fn check(self, what: impl fmt::Display, needed: u64) -> Result<()> {
        if needed > self.bytes {
            return Err(Error::TooLarge {
                what: what.to_string(),
                needed: Bytes(needed),
                held: Bytes(0),
                budget: Bytes(self.bytes),
            });
        }
        Ok(())
    }
}

/// A file's identity (device and inode): the same file whatever path, link or spelling names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FileId {
    device: u64,
    inode: u64,
}

impl FileId {
    #[cfg(unix)]
    pub fn of(metadata: &std::fs::Metadata) -> Self {
        use std::os::unix::fs::MetadataExt;
        Self { device: metadata.dev(), inode: metadata.ino() }
    }
}

/// One run's account against its memory budget: the bytes it holds, and the files it read.
#[derive(Debug)]
pub struct Ledger {
    budget: MemoryBudget,
    held: AtomicU64,
    inputs: Mutex<Vec<FileId>>,
}

impl Default for Ledger {
    /// A ledger of the default budget, holding nothing.
    fn default() -> Self {
        Self::new(MemoryBudget::default())
    }
}

/// Bytes a [`Ledger`] holds for a call, given back when it is dropped ([`Ledger::hold`]).
#[must_use = "the bytes are given back as soon as the guard is dropped"]
pub struct Held<'l> {
    ledger: &'l Ledger,
    bytes: u64,
}

impl Held<'_> {
    /// Takes `bytes` more for `what`, or refuses them as [`Ledger::charge`] does.
    pub fn grow(&mut self, what: impl fmt::Display, bytes: u64) -> Result<()> {
        self.ledger.charge(what, bytes)?;
        self.bytes += bytes;
        Ok(())
    }
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        self.ledger.release(self.bytes);
    }
}

impl Ledger {
    pub fn new(budget: MemoryBudget) -> Self {
        Self { budget, held: AtomicU64::new(0), inputs: Mutex::new(Vec::new()) }
    }

    pub fn budget(&self) -> MemoryBudget {
        self.budget
    }

    /// Bytes the run holds so far.
    pub fn held(&self) -> u64 {
        self.held.load(Ordering::Relaxed)
    }

    /// Bytes the run may still take.
    pub fn available(&self) -> u64 {
        self.budget.bytes().saturating_sub(self.held())
    }

    /// Refuses `needed` more bytes for `what` when, with what the run holds, they would
    /// exceed the budget. Takes nothing.
    pub fn check(&self, what: impl fmt::Display, needed: u64) -> Result<()> {
        self.refusal(what, needed, self.held()).map_or(Ok(()), Err)
    }

    /// Takes `bytes` for `what` for the rest of the run, or refuses them as [`Ledger::check`]
    /// does (then taking nothing).
    pub fn charge(&self, what: impl fmt::Display, bytes: u64) -> Result<()> {
        let mut held = self.held();
        loop {
            if let Some(refusal) = self.refusal(&what, bytes, held) {
                return Err(refusal);
            }
            match self.held.compare_exchange_weak(held, held + bytes, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => return Ok(()),
                Err(now) => held = now,
            }
        }
    }

    /// Takes `bytes` for `what` as [`Ledger::charge`] does, until the guard it returns is
    /// dropped: what a call holds while it runs (a verification's plan and what it gathers,
    /// the Python bindings' poses).
    pub fn hold(&self, what: impl fmt::Display, bytes: u64) -> Result<Held<'_>> {
        self.charge(what, bytes)?;
        Ok(Held { ledger: self, bytes })
    }

    /// Gives back `bytes` that [`Ledger::charge`] took and the run no longer holds: one image
    /// of a stream of images, once it is scored (src/bop/).
    pub fn release(&self, bytes: u64) {
        // Never fails: the closure always returns a value.
        let _ = self.held.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |held| Some(held.saturating_sub(bytes)));
    }

    fn refusal(&self, what: impl fmt::Display, needed: u64, held: u64) -> Option<Error> {
        (held.saturating_add(needed) > self.budget.bytes()).then(|| Error::TooLarge {
            what: what.to_string(),
            needed: Bytes(needed),
            held: Bytes(held),
            budget: Bytes(self.budget.bytes()),
        })
    }

    /// Notes that the run read the file `id` (so no output may replace it).
    pub(crate) fn record_input(&self, id: FileId) {
        let mut inputs = self.inputs.lock().unwrap_or_else(|p| p.into_inner());
        if !inputs.contains(&id) {
            inputs.push(id);
        }
    }

    /// Whether the run read the file `id`.
    pub fn read(&self, id: FileId) -> bool {
        self.inputs.lock().unwrap_or_else(|p| p.into_inner()).contains(&id)
    }
}

impl std::str::FromStr for MemoryBudget {
    type Err = Error;

    /// `4294967296`, `4096M`, `4G`, `0.5T` (binary units).
    fn from_str(text: &str) -> Result<Self> {
        let text = text.trim();
        let (number, unit) = match text.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
            Some((i, _)) => text.split_at(i),
            None => (text, ""),
        };
        let shift = match unit.to_ascii_uppercase().trim_end_matches(['B', 'I']) {
            "" => 0,
            "K" => 10,
            "M" => 20,
            "G" => 30,
            "T" => 40,
            _ => return Err(invalid(format!("{text:?} has an unknown unit {unit:?} (use K, M, G or T)"))),
        };
        let value = number
            .trim()
            .parse::<f64>()
            .ok()
            .map(|v| v * (1u64 << shift) as f64)
            .filter(|v| v.is_finite() && *v >= 1.0 && *v < u64::MAX as f64)
            .ok_or_else(|| invalid(format!("{text:?} is not a positive size such as 8G")))?;
        Ok(Self::new(value as u64))
    }
}

fn invalid(reason: String) -> Error {
    Error::Setting { setting: "memory budget".into(), reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        let parse = |t: &str| t.parse::<MemoryBudget>().map(MemoryBudget::bytes).ok();
        assert_eq!(parse("1000"), Some(1000));
        assert_eq!(parse("4G"), Some(4 << 30));
        assert_eq!(parse("512MiB"), Some(512 << 20));
        assert_eq!(parse("0.5k"), Some(512));
        assert_eq!(parse("2T"), Some(2 << 40));
        // 16777216T is 2^64 bytes, one more than a u64 holds.
        for bad in ["", "-1G", "0", "nan", "4X", "1e30T", "16777216T"] {
            assert_eq!(parse(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn a_run_is_refused_once_its_charges_together_cross_the_budget() {
        let ledger = Ledger::new(MemoryBudget::new(1000));
        assert_eq!(ledger.budget(), MemoryBudget::new(1000));
        ledger.charge("the scene", 600).unwrap();
        ledger.check("a render", 400).unwrap();
        let e = ledger.charge("the model m.obj", 401).unwrap_err().to_string();
        assert!(e.starts_with("the model m.obj needs about 401 bytes on top of the 600 bytes the run already holds, more than the memory budget of 1000 bytes"), "{e}");
        assert_eq!(ledger.held(), 600, "a refused charge takes nothing");
        ledger.charge("the model m.obj", 400).unwrap();
        assert_eq!((ledger.held(), ledger.available()), (1000, 0));
        let e = ledger.check("one more byte", 1).unwrap_err().to_string();
        assert!(e.starts_with("one more byte needs about 1 bytes"), "{e}");
    }

    #[test]
    fn what_a_call_holds_is_given_back_when_it_ends() {
        let ledger = Ledger::new(MemoryBudget::new(1000));
        ledger.charge("the scene", 300).unwrap();
        {
            let _poses = ledger.hold("1 poses", 500).unwrap();
            assert_eq!(ledger.held(), 800);
            let e = ledger.check("their verifications", 201).unwrap_err().to_string();
            assert!(e.contains("on top of the 800 bytes the run already holds"), "{e}");
            assert!(ledger.hold("2 poses", 701).is_err());
            assert_eq!(ledger.held(), 800, "a refused hold takes nothing");
            let mut results = ledger.hold("1 verification", 100).unwrap();
            results.grow("its counts", 100).unwrap();
            let e = results.grow("more counts", 1).unwrap_err().to_string();
            assert!(e.starts_with("more counts needs about 1 bytes on top of the 1000 bytes"), "{e}");
        }
        assert_eq!(ledger.held(), 300, "the call's bytes are given back, the run's kept");
    }

    /// The budget is inclusive: a need of exactly the budget passes, one byte more does not.
    #[test]
    fn a_need_of_exactly_the_budget_passes() {
        let budget = MemoryBudget::new(1000);
        budget.check("the scene", 1000).unwrap();
        let e = budget.check("the scene", 1001).unwrap_err().to_string();
        assert!(e.starts_with("the scene needs about 1001 bytes"), "{e}");
    }

    #[test]
    fn a_bad_setting_is_named_once() {
        let e = MemoryBudget::parse_setting("4X", MEMORY_BUDGET_ENV).unwrap_err().to_string();
        assert_eq!(e, "RANGESYNTH_MEMORY_BUDGET: \"4X\" has an unknown unit \"X\" (use K, M, G or T)");
    }

    #[test]
    fn a_refusal_names_both_figures() {
        let e = MemoryBudget::new(1 << 30).check("rendering", 3 << 29).unwrap_err().to_string();
        assert!(e.contains("1.5 GiB") && e.contains("1.0 GiB"), "{e}");
    }
}
