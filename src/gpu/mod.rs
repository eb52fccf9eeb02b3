//! The explicit-Vulkan layer: one file per concept (context, memory, barriers, shaders,
//! the pipeline cache, timestamps). Nothing here knows about range images.

mod barrier;
mod compute;
mod context;
mod descriptors;
mod devices;
mod encoder;
mod memory;
mod pipeline_cache;
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
pub use pipeline_cache::{default_cache_dir, CacheLoad, PipelineCacheReport, CACHE_DIR_ENV, MAX_PIPELINE_CACHE_BYTES};
pub use timing::Timestamps;
