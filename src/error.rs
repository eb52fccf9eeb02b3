//! The library's one error type. Device loss and out-of-memory are their own variants so an
//! embedding daemon can recover (recreate the renderer, or split a batch); every other
//! failure names what was wrong with which input.

use crate::limits::Bytes;
use ash::vk;
use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
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
    #[error("cannot access {}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: {reason}", path.display())]
    File { path: PathBuf, reason: String },
    /// A call would need more memory than its budget allows (limits.rs); nothing was allocated.
    #[error(
        "{what} needs about {needed}, more than the memory budget of {budget} \
         (raise it with --memory-budget or RANGESYNTH_MEMORY_BUDGET)"
    )]
    TooLarge { what: String, needed: Bytes, budget: Bytes },
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
