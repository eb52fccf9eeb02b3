//! An owned descriptor set of storage images (GENERAL layout), then uniform buffers, then
//! storage buffers, bound in that order from binding 0, with its own pool so dropping it frees
//! everything. Compute passes are recorded with it in compute.rs.

use super::{Buffer, GpuContext, Image};
use crate::error::{Result, VkResultExt};
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

impl Drop for StorageSet {
    fn drop(&mut self) {
        // SAFETY: owned; submissions using the set have completed.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}
