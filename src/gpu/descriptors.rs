//! An owned descriptor set of storage images (GENERAL layout), then uniform buffers, then
//! storage buffers, bound in that order from binding 0, with its own pool so dropping it frees
//! everything. Compute passes are recorded with it in compute.rs.

use super::{Buffer, GpuContext, Image};
use crate::error::{Error, Result, VkResultExt};
use ash::vk;
use std::sync::Arc;

/// How many resources of each kind a set binds, in binding order.
#[derive(Debug, Clone, Copy)]
pub struct SetShape {
    pub images: usize,
    /// Read-only blocks a dispatch reads at offsets the same for every invocation: a software
    /// rasterizer loads such a value once for all its lanes, where it loads a storage buffer's
    /// lane by lane.
    pub uniform_buffers: usize,
    pub storage_buffers: usize,
}

impl SetShape {
    /// Storage images and storage buffers only.
    pub fn storage(images: usize, storage_buffers: usize) -> Self {
        Self { images, uniform_buffers: 0, storage_buffers }
    }

    /// Each kind's descriptor type and count, in binding order.
    fn kinds(self) -> [(vk::DescriptorType, usize); 3] {
        [
            (vk::DescriptorType::STORAGE_IMAGE, self.images),
            (vk::DescriptorType::UNIFORM_BUFFER, self.uniform_buffers),
            (vk::DescriptorType::STORAGE_BUFFER, self.storage_buffers),
        ]
    }

    /// The descriptor type of each binding, from binding 0.
    pub(crate) fn types(self) -> impl Iterator<Item = vk::DescriptorType> {
        self.kinds().into_iter().flat_map(|(ty, count)| std::iter::repeat_n(ty, count))
    }

    /// Refuses, naming the pass (`name`) and the limit, a compute stage binding this set with
    /// `push_size` bytes of push constants where `limits` do not allow it. Vulkan promises
    /// only 4 storage buffers and 4 storage images a stage; a layout past a device's limit is
    /// invalid usage, whose outcome no driver defines, so it must never reach the driver.
    pub(crate) fn check_fits(self, push_size: usize, limits: &vk::PhysicalDeviceLimits, name: &str) -> Result<()> {
        let per_stage_resources = self.images + self.uniform_buffers + self.storage_buffers;
        let needs = [
            (
                self.storage_buffers,
                limits.max_per_stage_descriptor_storage_buffers,
                "maxPerStageDescriptorStorageBuffers",
                "storage buffers",
            ),
            (
                self.storage_buffers,
                limits.max_descriptor_set_storage_buffers,
                "maxDescriptorSetStorageBuffers",
                "storage buffers",
            ),
            (
                self.uniform_buffers,
                limits.max_per_stage_descriptor_uniform_buffers,
                "maxPerStageDescriptorUniformBuffers",
                "uniform buffers",
            ),
            (
                self.uniform_buffers,
                limits.max_descriptor_set_uniform_buffers,
                "maxDescriptorSetUniformBuffers",
                "uniform buffers",
            ),
            (
                self.images,
                limits.max_per_stage_descriptor_storage_images,
                "maxPerStageDescriptorStorageImages",
                "storage images",
            ),
            (self.images, limits.max_descriptor_set_storage_images, "maxDescriptorSetStorageImages", "storage images"),
            (per_stage_resources, limits.max_per_stage_resources, "maxPerStageResources", "resources"),
            (push_size, limits.max_push_constants_size, "maxPushConstantsSize", "bytes of push constants"),
        ];
        match needs.into_iter().find(|&(needed, allowed, _, _)| needed > allowed as usize) {
            Some((needed, allowed, limit, what)) => Err(Error::Unsupported(format!(
                "the {name} pass binds {needed} {what} in one shader stage; this device allows {allowed} ({limit})"
            ))),
            None => Ok(()),
        }
    }
}

pub struct StorageSet {
    pub(super) ctx: Arc<GpuContext>,
    pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
}

impl StorageSet {
    pub fn new(
        ctx: &Arc<GpuContext>,
        layout: vk::DescriptorSetLayout,
        images: &[&Image],
        (uniforms, buffers): (&[&Buffer], &[&Buffer]),
        name: &str,
    ) -> Result<Self> {
        let d = &ctx.device;
        let shape = SetShape { images: images.len(), uniform_buffers: uniforms.len(), storage_buffers: buffers.len() };
        check_ranges(uniforms.iter().map(|b| b.size), buffers.iter().map(|b| b.size), &ctx.limits, name)?;
        let sizes: Vec<_> = shape
            .kinds()
            .into_iter()
            .filter(|&(_, count)| count > 0)
            .map(|(ty, count)| vk::DescriptorPoolSize { ty, descriptor_count: count as u32 })
            .collect();
        // SAFETY: valid device.
        let pool = unsafe {
            d.create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes), None)
        }
        .vk(name)?;
        let mut owned = Self { ctx: ctx.clone(), pool, set: vk::DescriptorSet::null() };
        let layouts = [layout];
        // SAFETY: the pool has room for one set of this layout.
        owned.set = unsafe {
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts),
            )
        }
        .vk(name)?[0];
        ctx.name_object(owned.set, name);
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = images
            .iter()
            .map(|i| [vk::DescriptorImageInfo::default().image_view(i.view).image_layout(vk::ImageLayout::GENERAL)])
            .collect();
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = uniforms
            .iter()
            .chain(buffers)
            .map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)])
            .collect();
        let write = |binding: usize, ty| {
            vk::WriteDescriptorSet::default().dst_set(owned.set).dst_binding(binding as u32).descriptor_type(ty)
        };
        let buffer_types = shape.types().skip(images.len());
        let writes: Vec<_> = image_infos
            .iter()
            .enumerate()
            .map(|(b, info)| write(b, vk::DescriptorType::STORAGE_IMAGE).image_info(info))
            .chain(
                buffer_infos
                    .iter()
                    .zip(buffer_types)
                    .enumerate()
                    .map(|(b, (info, ty))| write(images.len() + b, ty).buffer_info(info)),
            )
            .collect();
        // SAFETY: the set, views and buffers are alive.
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        Ok(owned)
    }
}

/// Refuses, naming the set, a buffer bound whole past what the device binds of its kind
/// (maxUniformBufferRange, maxStorageBufferRange): invalid usage, like a layout past its
/// limits ([`SetShape::check_fits`]). Whoever sizes a buffer by its input checks it against
/// the limit first, with a message naming the input (`check_pixel_buffers`); this is the
/// backstop for every set.
fn check_ranges(
    uniform_sizes: impl IntoIterator<Item = u64>,
    storage_sizes: impl IntoIterator<Item = u64>,
    limits: &vk::PhysicalDeviceLimits,
    name: &str,
) -> Result<()> {
    let kinds = [
        (uniform_sizes.into_iter().max(), limits.max_uniform_buffer_range, "uniform", "maxUniformBufferRange"),
        (storage_sizes.into_iter().max(), limits.max_storage_buffer_range, "storage", "maxStorageBufferRange"),
    ];
    match kinds.into_iter().find(|&(largest, allowed, _, _)| largest > Some(u64::from(allowed))) {
        Some((Some(size), allowed, kind, limit)) => Err(Error::Unsupported(format!(
            "{name} binds a {kind} buffer of {size} bytes; this device binds at most {allowed} ({limit})"
        ))),
        _ => Ok(()),
    }
}

impl Drop for StorageSet {
    fn drop(&mut self) {
        // SAFETY: owned; submissions using the set have completed.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The limits Vulkan promises every device (the specification's "Required Limits").
    fn vulkan_minimum() -> vk::PhysicalDeviceLimits {
        vk::PhysicalDeviceLimits {
            max_per_stage_descriptor_storage_buffers: 4,
            max_descriptor_set_storage_buffers: 24,
            max_per_stage_descriptor_uniform_buffers: 12,
            max_descriptor_set_uniform_buffers: 72,
            max_per_stage_descriptor_storage_images: 4,
            max_descriptor_set_storage_images: 24,
            max_per_stage_resources: 128,
            max_push_constants_size: 128,
            max_uniform_buffer_range: 16_384,
            max_storage_buffer_range: 1 << 27,
            ..Default::default()
        }
    }

    fn refusal(result: Result<()>) -> String {
        match result {
            Err(Error::Unsupported(message)) => message,
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn a_set_past_the_devices_limits_is_refused_by_name() {
        let limits = vulkan_minimum();
        assert!(SetShape { images: 4, uniform_buffers: 12, storage_buffers: 4 }.check_fits(128, &limits, "x").is_ok());
        let message = refusal(SetShape::storage(0, 9).check_fits(16, &limits, "witness mask"));
        assert_eq!(
            message,
            "the witness mask pass binds 9 storage buffers in one shader stage; this device allows 4 \
             (maxPerStageDescriptorStorageBuffers)"
        );
        let message = refusal(SetShape::storage(5, 0).check_fits(0, &limits, "effects"));
        assert!(message.contains("5 storage images") && message.contains("maxPerStageDescriptorStorageImages"));
        let uniforms = SetShape { images: 0, uniform_buffers: 13, storage_buffers: 0 };
        assert!(refusal(uniforms.check_fits(0, &limits, "u")).contains("maxPerStageDescriptorUniformBuffers"));
        assert!(refusal(SetShape::storage(0, 1).check_fits(132, &limits, "p")).contains("132 bytes of push constants"));
        let crowded = vk::PhysicalDeviceLimits { max_per_stage_resources: 7, ..vulkan_minimum() };
        let message =
            refusal(SetShape { images: 2, uniform_buffers: 2, storage_buffers: 4 }.check_fits(0, &crowded, "c"));
        assert!(message.contains("8 resources") && message.contains("maxPerStageResources"));
        let small_set = vk::PhysicalDeviceLimits { max_descriptor_set_storage_buffers: 3, ..vulkan_minimum() };
        assert!(
            refusal(SetShape::storage(0, 4).check_fits(0, &small_set, "s")).contains("maxDescriptorSetStorageBuffers")
        );
    }

    #[test]
    fn a_buffer_bound_past_the_devices_range_is_refused_by_name() {
        let limits = vulkan_minimum();
        assert!(check_ranges([16_384], [1 << 27], &limits, "the score's set").is_ok());
        let message = refusal(check_ranges([16_385], [], &limits, "the score's set"));
        assert_eq!(
            message,
            "the score's set binds a uniform buffer of 16385 bytes; this device binds at most 16384 (maxUniformBufferRange)"
        );
        let message = refusal(check_ranges([], [4, (1 << 27) + 1], &limits, "the mask's set"));
        assert!(message.contains("storage buffer of 134217729 bytes") && message.contains("maxStorageBufferRange"));
    }
}
