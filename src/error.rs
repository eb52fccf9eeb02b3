//! The library's one error type. Device loss and out-of-memory are their own variants so an
//! embedding daemon can recover (recreate the renderer, or split a batch); every other
//! failure names what was wrong with which input.

use ash::vk;
use std::fmt;
use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    #[error("Vulkan is not available on this machine: {0}")]
    VulkanUnavailable(String),
    #[error("no usable Vulkan device: {0}")]
    NoDevice(String),
    #[error("the Vulkan device lacks what rangesynth needs: {0}")]
    Unsupported(String),
    #[error("the GPU ran out of memory while {0}")]
    OutOfMemory(String),
    #[error("the Vulkan device was lost while {0}")]
    DeviceLost(String),
    #[error("Vulkan call failed while {context}: {result}")]
    Vulkan { context: String, result: vk::Result },
    #[error("invalid model {name}: {reason}")]
    Mesh { name: String, reason: String },
    #[error("invalid scene: {0}")]
    Scene(String),
    /// A setting (an option, an environment variable) has a value that cannot be used.
    #[error("{setting}: {reason}")]
    Setting { setting: String, reason: String },
    #[error("cannot access {}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: {reason}", path.display())]
    File { path: PathBuf, reason: String },
    /// A dependency's parser panicked on an input (guard_parser); nothing it made was kept.
    #[error("{input}: {parser} failed on this input ({message}); please report it with the file")]
    ParserPanic { input: String, parser: &'static str, message: String },
    /// A call would need more memory than its budget allows (limits.rs); nothing was allocated.
    /// `held` is what the run held already (limits.rs, `Ledger`).
    #[error(
        "{what} needs about {needed}{}, more than the memory budget of {budget} \
         (raise it with --memory-budget or RANGESYNTH_MEMORY_BUDGET)",
        held_note(*.held)
    )]
    TooLarge { what: String, needed: Bytes, held: Bytes, budget: Bytes },
}

impl Error {
    /// Maps a failed Vulkan call once, so callers can tell the recoverable cases apart.
    pub(crate) fn vulkan(context: &str, result: vk::Result) -> Self {
        match result {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                Error::OutOfMemory(context.to_string())
            }
            vk::Result::ERROR_DEVICE_LOST => Error::DeviceLost(context.to_string()),
            result => Error::Vulkan { context: context.to_string(), result },
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }

    pub(crate) fn file(path: impl Into<PathBuf>, reason: impl std::fmt::Display) -> Self {
        Error::File { path: path.into(), reason: reason.to_string() }
    }

    /// The same error, naming what it is about (`hypothesis "h7"`, `object 3`) where its
    /// message is about the input and does not already say which part: a refusal of a
    /// 5,000-hypothesis file names the one hypothesis that caused it.
    pub(crate) fn concerning(self, subject: &str) -> Self {
        match self {
            Error::Scene(reason) => Error::Scene(format!("{subject}: {reason}")),
            Error::TooLarge { what, needed, held, budget } => {
                Error::TooLarge { what: format!("{subject}: {what}"), needed, held, budget }
            }
            other => other,
        }
    }
}

fn held_note(held: Bytes) -> String {
    match held.0 {
        0 => String::new(),
        _ => format!(" on top of the {held} the run already holds"),
    }
}

/// Runs `parse`, a dependency's parser reading `input`, so that a panic inside it becomes an
/// error naming the input rather than the end of the process (or of the daemon embedding the
/// library). The project checks what it gives each such parser; this is the boundary for
/// what the checks miss. (A build with `panic = "abort"` cannot catch the panic.)
pub(crate) fn guard_parser<T>(input: &str, parser: &'static str, parse: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(parse)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .map(String::as_str)
            .or(panic.downcast_ref::<&str>().copied())
            .unwrap_or("it panicked");
        Err(Error::ParserPanic { input: input.to_string(), parser, message: crate::untrusted::escaped(message, 200) })
    })
}

/// `.vk("creating the image")` on an `ash` result.
pub(crate) trait VkResultExt<T> {
    fn vk(self, context: &str) -> Result<T>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn vk(self, context: &str) -> Result<T> {
        self.map_err(|r| Error::vulkan(context, r))
    }
}

impl From<gpu_allocator::AllocationError> for Error {
    fn from(e: gpu_allocator::AllocationError) -> Self {
        match e {
            gpu_allocator::AllocationError::OutOfMemory => Error::OutOfMemory("allocating GPU memory".into()),
            other => {
                Error::Vulkan { context: format!("allocating GPU memory ({other})"), result: vk::Result::ERROR_UNKNOWN }
            }
        }
    }
}

/// A byte count shown the way people read it (`12.0 GiB`), in errors about the memory
/// budget and sizes.
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
