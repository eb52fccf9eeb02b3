//! The explicit-Vulkan layer: one file per concept (context, memory, barriers, shaders,
//! timestamps). Nothing here knows about range images.

mod barrier;
mod compute;
mod context;
mod descriptors;
mod devices;
mod encoder;
mod memory;
pub(crate) mod shaders;
mod timing;
mod upload;

pub use barrier::{barrier, Access, BufferTransition, ImageTransition};
pub use compute::ComputePipeline;
pub use context::{ContextOptions, GpuContext, ValidationLog, DEVICE_ENV, VALIDATION_ENV};
pub use descriptors::{SetShape, StorageSet};
pub use devices::{list_devices, DeviceInfo};
pub use encoder::{Encoder, Step};
pub use memory::{Buffer, BufferDesc, Image, ImageDesc, DEPTH_FORMAT};
pub use timing::Timestamps;
