//! The memory budget: how much memory one call may plan to use before it is refused.
//!
//! rangesynth runs inside long-running daemons, where an allocation the machine cannot satisfy
//! aborts the whole process (Rust's allocator does not return an error). So every size that
//! comes from outside — a file header, an image size, a batch — is turned into an estimate of
//! the bytes it will take, host and GPU together, and checked against this budget *before*
//! anything is allocated. A refusal names the figure, so the user can raise the budget
//! knowingly (`--memory-budget` or `RANGESYNTH_MEMORY_BUDGET`).

use crate::error::{Error, Result};
use std::fmt;

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
            Ok(text) => text.parse().map_err(|e: Error| Error::Scene(format!("{MEMORY_BUDGET_ENV}: {e}"))),
            Err(_) => Ok(Self::default()),
        }
    }

    /// Refuses `needed` bytes for `what` when they exceed the budget.
    pub fn check(self, what: impl fmt::Display, needed: u64) -> Result<()> {
        if needed > self.bytes {
            return Err(Error::TooLarge { what: what.to_string(), needed: Bytes(needed), budget: Bytes(self.bytes) });
        }
        Ok(())
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
            _ => return Err(Error::Scene(format!("memory budget {text:?}: unknown unit {unit:?} (use K, M, G or T)"))),
        };
        let value = number
            .trim()
            .parse::<f64>()
            .ok()
            .map(|v| v * (1u64 << shift) as f64)
            .filter(|v| v.is_finite() && *v >= 1.0 && *v < u64::MAX as f64)
            .ok_or_else(|| Error::Scene(format!("memory budget {text:?} must be a positive size such as 8G")))?;
        Ok(Self::new(value as u64))
    }
}

/// A byte count shown the way people read it (`12.0 GiB`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
        let mut value = self.0 as f64;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        match unit {
            0 => write!(f, "{} bytes", self.0),
            _ => write!(f, "{value:.1} {}", UNITS[unit]),
        }
    }
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
        for bad in ["", "-1G", "0", "nan", "4X", "1e30T"] {
            assert_eq!(parse(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn a_refusal_names_both_figures() {
        let e = MemoryBudget::new(1 << 30).check("rendering", 3 << 29).unwrap_err().to_string();
        assert!(e.contains("1.5 GiB") && e.contains("1.0 GiB"), "{e}");
    }
}
